"""Fits: a screw, stud or pin drawn into its hole deeper than the penetration tolerance.

CAD draws a tapped hole at the tap-drill diameter and the screw at its nominal diameter, so
every screw, threaded stud or standoff in a tapped hole overlaps the hole's wall all round
by the thread depth: about 0.08 to 0.1 of the diameter (M3 in a 2.5 mm hole: 0.25 mm; M8
in 6.8 mm: 0.6 mm; UNC 1/4-20 in 5.1 mm: 0.62 mm), more than the default tolerance of the
pair (:mod:`cad.tolerances`). Press fits drawn with their interference do the same.

Rule
----
When parts i and j, eroded by their shrinks, still overlap, the smaller of the two (by
bounding-box diagonal), the *inner* part, is eroded further for this pair only, by the
least ``e`` (found by bisection) that separates them, up to :data:`FIT_SHARE` (0.2) of its
thickness ``T`` (:func:`cad.tolerances.part_thickness`; a round bar of radius r has
``T ~ r``, so 0.1 of the diameter, the deepest ISO or UNC thread). The pair is a *fit* iff,
with that extra erosion, j touches the inner part and blocks it in each of the four
directions across some axis, and the inner part can leave along that axis one way or the
other: it sits in a hole of j and can be screwed or pressed in along the hole. The pair's
contact, freedom and support are then those of the two parts with the inner part's shrink
raised by ``e`` (its tolerance ``s_i + s_j + e``); every other pair keeps its own.

An overlap that is not a fit (a face sunk into another part, a part placed wrongly) or
that needs more than the share stays the one-line error naming the pair and the depth.
With an explicit penetration tolerance (``--penetration-tol``, the spec's
``penetration_tol``) there are no fits: every pair has exactly that tolerance.

A pair the spec accepts (``overlap_ok:``, :mod:`asp.cad_keys`: a press fit, a modelled
thread, the pieces of a visual asset) is taken as touching whatever its shape
(:func:`accepted_overlap`): its inner part is eroded for that pair by the least that
separates the two, up to :data:`ACCEPTED_SHARE` (0.4) of its thickness, as a fit without the
hole test. A pair nested deeper (an axle drawn through a visual body shell) passes
*through*: the two touch and rest on each other along every direction and neither blocks
the other (``Relations.through``; a checker does not test the pair against each other).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cad.assembly import Assembly
from cad.contact import contact_relation
from cad.freedom import (
    eroded_meshes,
    interpenetration_error,
    intersects,
    overlaps,
    translational_freedom,
)
from cad.offset import offset_mesh
from cad.support import fitted_across, support_relation
from cad.tolerances import Tolerances, part_thickness

FIT_SHARE = 0.2
"""Largest extra erosion of the inner part of a fit, as a share of its thickness."""
ACCEPTED_SHARE = 0.4
"""Largest extra erosion of the inner part of a pair the spec accepts (``overlap_ok:``)."""
_BISECTIONS = 10


@dataclass(frozen=True, eq=False)
class Fit:
    """A screw, stud or pin drawn into a hole of another part (see the module docstring).

    Attributes
    ----------
    inner, outer : int
        Part indices: the part in the hole and the part with the hole.
    extra : float
        Extra erosion of the inner part for this pair (mm).
    through : bool
        An accepted pair nested too deep to part: they touch and support each other along
        every direction, neither blocks the other (:func:`accepted_overlap`).
    tc, tt, sp : np.ndarray
        Contact, freedom and support of the pair, shape ``(2, 2, 6)``, order
        ``(inner, outer)``.
    """

    inner: int
    outer: int
    extra: float
    tc: np.ndarray
    tt: np.ndarray
    sp: np.ndarray
    through: bool = False

    def write_into(self, tc: np.ndarray, tt: np.ndarray, sp: np.ndarray) -> None:
        """Replace the pair's rows of the ``(n, n, 6)`` tables by the fit's."""
        idx = (self.inner, self.outer)
        for full, pair in ((tc, self.tc), (tt, self.tt), (sp, self.sp)):
            for r in range(2):
                for c in range(2):
                    if r != c:
                        full[idx[r], idx[c]] = pair[r, c]


def find_fits(assembly: Assembly, tols: Tolerances, eroded, accepted=()) -> list[Fit]:
    """Every pair overlapping deeper than its tolerance, as a fit.

    ``accepted``: pairs of part ids the spec accepts as overlapping (``overlap_ok:``):
    each is taken as touching (:func:`accepted_overlap`), whatever the tolerance.

    Raises
    ------
    ValueError
        Pairs that are not fits, all in one line: ``parts 'a' and 'b' interpenetrate by
        about X mm ...`` (or ``N pairs of parts interpenetrate ...``).
    """
    ids = assembly.ids
    ok = {frozenset(pair) for pair in accepted}
    fits, wrong = [], []
    for overlap in overlaps(assembly, tols, eroded):
        if frozenset((ids[overlap.a], ids[overlap.b])) in ok:
            fits.append(accepted_overlap(assembly, tols, eroded, overlap.a, overlap.b))
            continue
        fit = None if tols.explicit else as_fit(assembly, tols, eroded, overlap.a, overlap.b)
        if fit is None:
            wrong.append(overlap)
        else:
            fits.append(fit)
    if wrong:
        raise interpenetration_error(assembly, tols, wrong)
    return fits


def as_fit(assembly: Assembly, tols: Tolerances, eroded, a: int, b: int) -> Fit | None:
    """The fit of overlapping parts ``a`` and ``b``, or None when they are not one."""
    parted = _separated(assembly, tols, eroded, a, b, FIT_SHARE)
    if parted is None:
        return None
    inner, outer, extra = parted
    fit = _pair_fit(assembly, tols, inner, outer, extra)
    for axis in range(3):
        if (
            fitted_across(fit.tc, fit.tt, axis)[0, 1]
            and fit.tt[0, 1, 2 * axis : 2 * axis + 2].any()
        ):
            return fit
    return None


def accepted_overlap(assembly: Assembly, tols: Tolerances, eroded, a: int, b: int) -> Fit:
    """Parts ``a`` and ``b``, overlapping as the spec accepts, taken as touching: the
    smaller eroded for this pair by the least that parts them, or, nested deeper than
    :data:`ACCEPTED_SHARE` of its thickness, passing through the other (module docstring)."""
    parted = _separated(assembly, tols, eroded, a, b, ACCEPTED_SHARE)
    if parted is None:
        every = np.ones((2, 2, 6), dtype=bool)
        return Fit(a, b, 0.0, every, every, every, through=True)
    return _pair_fit(assembly, tols, *parted)


def _separated(assembly, tols, eroded, a: int, b: int, share: float):
    """``(inner, outer, extra)``: the smaller part (by bounding-box diagonal) and the
    least extra erosion of it, up to ``share`` of its thickness, that parts it from the
    other's eroded mesh (bisection); None when that is not enough."""
    sizes = [float(np.linalg.norm(np.ptp(assembly.parts[k].bounds, axis=0))) for k in (a, b)]
    inner, outer = (a, b) if sizes[0] <= sizes[1] else (b, a)
    mesh = assembly.parts[inner].mesh
    limit = share * part_thickness(mesh)

    def apart(extra: float) -> bool:
        shrunk = offset_mesh(mesh, -(float(tols.shrink[inner]) + extra))
        return not intersects(shrunk, eroded[outer])

    if limit <= 0 or not apart(limit):
        return None
    lo, hi = 0.0, limit
    for _ in range(_BISECTIONS):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if apart(mid) else (mid, hi)
    return inner, outer, hi


def _pair_fit(assembly: Assembly, tols: Tolerances, inner: int, outer: int, extra: float) -> Fit:
    """The pair's contact, freedom and support with the inner part shrunk ``extra`` more."""
    pair = Assembly(parts=(assembly.parts[inner], assembly.parts[outer]), units=assembly.units)
    shrink = np.array([tols.shrink[inner] + extra, tols.shrink[outer]], dtype=float)
    reach = None if tols.reach is None else np.asarray(tols.reach)[[inner, outer]]
    pair_tols = Tolerances(tols.contact, shrink, tols.explicit, reach)
    pair_eroded = eroded_meshes(pair, shrink)
    tc = contact_relation(pair, penetration_tol=pair_tols)
    tt = translational_freedom(pair, penetration_tol=pair_tols, check=False, eroded=pair_eroded)
    sp = support_relation(pair, pair_tols, pair_eroded, tc, tt)
    return Fit(inner, outer, extra, tc, tt, sp)
