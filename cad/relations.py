"""All relations of an assembly, and the subassembly tests of eqs. 3-5 (DESIGN.md)."""

from __future__ import annotations

import warnings
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from cad.assembly import Assembly
from cad.contact import contact_relation, distance_contacts, nearest_contacts
from cad.directions import DIRECTIONS
from cad.errors import GeometryError, Interpenetration
from cad.fits import find_fits
from cad.freedom import eroded_meshes, with_locking
from cad.freedom import translational_freedom as _freedom
from cad.offset import FREE_EDGE_PULL
from cad.support import SUPPORT_RULES, SUPPORT_TRAVEL_FACTOR, support_relation
from cad.tolerances import resolve_tolerances


@dataclass(frozen=True, eq=False)
class Relations:
    """Contact and translational freedom of every ordered pair of parts.

    Attributes
    ----------
    parts : tuple[str, ...]
        Part ids; index ``i`` of the tables is ``parts[i]``.
    tc : np.ndarray
        Bool, shape ``(n, n, 6)``: ``tc[i, j, d]`` = ``TC_d(i, j)``.
    tt : np.ndarray
        Bool, shape ``(n, n, 6)``: ``tt[i, j, d]`` = ``TT_d(i, j)``.
    contact_tol : float
        Contact tolerance used, in mm.
    penetration_tol : float
        Largest penetration tolerance of any pair, in mm (the explicit value if one was
        given); pair ``(i, j)`` tolerates ``part_shrink[i] + part_shrink[j]``.
    part_shrink : tuple[float, ...]
        Shrink of each part in mm (:mod:`cad.tolerances`).
    part_reach : tuple[float, ...]
        Contact reach of each part in mm: pair ``(i, j)`` counts a gap of up to
        ``min(part_reach[i], part_reach[j])`` as touching; empty when ``contact_tol``
        applies to every pair (an explicit contact tolerance).
    open_parts : tuple[str, ...]
        Parts whose mesh is not closed (watertight) after its duplicate vertices were
        merged: their erosion, and so their relations, are approximate.
    units : str
        Source length unit of the assembly (tables do not depend on it).
    directions : tuple[str, ...]
        ``("+x", "-x", "+y", "-y", "+z", "-z")``.
    sp : np.ndarray or None
        Bool, shape ``(n, n, 6)``: ``sp[i, j, d]`` = part i falling along ``d`` is stopped
        by part j (:mod:`cad.support`); None when not computed (tables built by hand).
    fits : tuple of (str, str, float)
        Screws, studs and pins drawn into a hole deeper than the pair's tolerance
        (:mod:`cad.fits`): (inner part, part with the hole, extra tolerance in mm).
    through : tuple of (str, str)
        Pairs the spec accepts as overlapping (``overlap_ok:``) that are nested too deep to
        part: they touch and rest on each other along every direction, neither blocks the
        other (:func:`cad.fits.accepted_overlap`).
    nearest : tuple of (str, str, int, float)
        Pairs across the model's gaps that join the contact graph's pieces into one (a
        plate floating off the part it is fixed to): (part, part, direction index of the
        second's side, gap in mm) (:func:`cad.contact.nearest_contacts`); not in ``tc``:
        :func:`with_nearest` adds them, as the planner reads a file.
    """

    parts: tuple[str, ...]
    tc: np.ndarray
    tt: np.ndarray
    contact_tol: float = 0.0
    penetration_tol: float = 0.0
    units: str = "mm"
    part_shrink: tuple[float, ...] = ()
    part_reach: tuple[float, ...] = ()
    open_parts: tuple[str, ...] = ()
    directions: tuple[str, ...] = DIRECTIONS
    sp: np.ndarray | None = None
    fits: tuple[tuple[str, str, float], ...] = ()
    through: tuple[tuple[str, str], ...] = ()
    nearest: tuple[tuple[str, str, int, float], ...] = ()

    def __post_init__(self) -> None:
        n = len(self.parts)
        for name in ("tc", "tt", "sp"):
            if getattr(self, name) is None:
                continue
            table = np.asarray(getattr(self, name), dtype=bool)
            if table.shape != (n, n, 6):
                raise GeometryError(f"{name} must have shape ({n}, {n}, 6), got {table.shape}")
            table = table.copy()
            table.setflags(write=False)
            object.__setattr__(self, name, table)

    def index(self, part: str | int) -> int:
        """Table index of a part id (an int is returned as is, after a range check)."""
        if isinstance(part, (int, np.integer)):
            if not 0 <= int(part) < len(self.parts):
                raise GeometryError(f"part index {part} out of range")
            return int(part)
        try:
            return self.parts.index(part)
        except ValueError:
            raise GeometryError(f"unknown part {part!r}") from None

    def to_dict(self) -> dict:
        """JSON-ready dict: ``parts``, ``directions``, ``tc``, ``tt`` ([i][j][d]), tolerances."""
        return {
            "parts": list(self.parts),
            "directions": list(self.directions),
            "units": "mm",
            "source_units": self.units,
            "contact_tol_mm": self.contact_tol,
            "penetration_tol_mm": self.penetration_tol,
            "part_shrink_mm": list(self.part_shrink),
            **({} if not self.part_reach else {"part_reach_mm": list(self.part_reach)}),
            "tc": self.tc.tolist(),
            "tt": self.tt.tolist(),
            **({} if self.sp is None else {"sp": self.sp.tolist()}),
            **({} if not self.fits else {"fits": [list(f) for f in self.fits]}),
            **({} if not self.through else {"through": [list(t) for t in self.through]}),
        }


def compute_relations(
    assembly: Assembly,
    *,
    contact_tol: float | None = None,
    penetration_tol: float | None = None,
    progress: bool = False,
    overlap_ok=(),
) -> Relations:
    """Contact, translational freedom and support of an assembly.

    Parameters
    ----------
    assembly : Assembly
        ``n`` parts in assembled pose.
    contact_tol : float, optional
        Contact tolerance in mm (default 0.01 mm).
    penetration_tol : float, optional
        Penetration tolerance in mm for every pair. Default: per part, a shrink
        ``s_p = min(max(0.025, 0.003 x diagonal), 0.25, 0.1 x thickness)`` mm, and pair
        ``(i, j)`` tolerates ``s_i + s_j`` (:mod:`cad.tolerances`).
    progress : bool
        Show tqdm progress bars over the pairs.
    overlap_ok : iterable of (str, str)
        Pairs of part ids whose overlap is as modelled (the spec's ``overlap_ok:``): each
        taken as touching (:func:`cad.fits.accepted_overlap`).

    Returns
    -------
    Relations
        ``tc``, ``tt`` and ``sp`` (:mod:`cad.support`), each shape ``(n, n, 6)``.

    Raises
    ------
    ValueError
        Two parts interpenetrate deeper than the penetration tolerance and are not a fit
        (a screw or pin in a hole, :mod:`cad.fits`): a GeometryError naming every such
        pair and the ``overlap_ok:`` line that accepts them, and, computed with them
        accepted (its ``relations`` attribute), the pairs that then lock each other and the
        ``flex:`` line that lets each in (:func:`cad.freedom.with_locking`): every line the
        file needs in one message.
    """
    tols = resolve_tolerances(assembly, contact_tol, penetration_tol)
    eroded = eroded_meshes(assembly, tols.shrink)
    try:
        fits = find_fits(assembly, tols, eroded, overlap_ok)
    except Interpenetration as exc:
        if exc.unit_wrong:
            raise
        accepted = compute_relations(  # what else the file needs once they are accepted
            assembly,
            contact_tol=contact_tol,
            penetration_tol=penetration_tol,
            progress=progress,
            overlap_ok=(*overlap_ok, *exc.pairs),
        )
        raise with_locking(exc, assembly, accepted) from None
    tc = contact_relation(assembly, penetration_tol=tols, progress=progress)
    tt = _freedom(assembly, penetration_tol=tols, progress=progress, check=False, eroded=eroded)
    sp = support_relation(assembly, tols, eroded, tc, tt, progress=progress)
    for fit in fits:
        fit.write_into(tc, tt, sp)
    for a, b, d in distance_contacts(assembly, tols, tc):  # open meshes: by distance
        tc[a, b, d] = tc[b, a, d ^ 1] = True
        sp[a, b, d] = sp[b, a, d ^ 1] = True
    ids = assembly.ids
    return Relations(
        parts=assembly.ids,
        tc=tc,
        tt=tt,
        contact_tol=tols.contact,
        penetration_tol=tols.penetration,
        units=assembly.units,
        part_shrink=tuple(float(x) for x in tols.shrink),
        part_reach=() if tols.reach is None else tuple(float(x) for x in tols.reach),
        open_parts=tuple(p.id for p in assembly.parts if not p.mesh.is_watertight),
        sp=sp,
        fits=tuple(
            (ids[f.inner], ids[f.outer], _up(float(f.extra))) for f in fits if not f.through
        ),
        through=tuple((ids[f.inner], ids[f.outer]) for f in fits if f.through),
        nearest=tuple(
            (ids[a], ids[b], d, round(gap, 6)) for a, b, d, gap in nearest_contacts(assembly, tc)
        ),
    )


def with_nearest(relations: Relations) -> Relations:
    """``relations`` with the pieces of its contact graph joined by their nearest parts
    (``relations.nearest``, :func:`cad.contact.nearest_contacts`: contact and support
    across the gap, both ways), as the planner reads a file; one warning names them.
    Unchanged when there are none."""
    if not relations.nearest:
        return relations
    from dataclasses import replace

    tc, sp = np.array(relations.tc, dtype=bool), relations.sp
    sp = None if sp is None else np.array(sp, dtype=bool)
    ids = list(relations.parts)
    for part, near, d, _ in relations.nearest:
        a, b = ids.index(part), ids.index(near)
        tc[a, b, d] = tc[b, a, d ^ 1] = True
        if sp is not None:
            sp[a, b, d] = sp[b, a, d ^ 1] = True
    found = relations.nearest
    shown = ", ".join(f"{a} to {b} ({gap:.3g} mm)" for a, b, _, gap in found[:10])
    more = f" and {len(found) - 10} more" if len(found) > 10 else ""
    warnings.warn(
        f"the parts touch in {len(found) + 1} or more pieces, joined by the nearest parts "
        f"across the model's gaps, each pair taken as touching (cad/contact.py): {shown}{more}",
        stacklevel=2,
    )
    return replace(relations, tc=tc, sp=sp)


def replay_rules(relations: Relations) -> dict:
    """How the relations treat the meshes, for a checker replaying a plan from them alone.

    Returns
    -------
    dict
        ``merge_vertices`` (true: coincident vertices of each mesh are merged first),
        ``erosion`` (how a part is shrunk by its ``part_shrink``), ``free_edge_pull`` (an
        open part's free edges also move back in their faces by this many shrinks,
        :data:`cad.offset.FREE_EDGE_PULL`), ``contact_reach``
        (part -> mm, or None when ``contact_tol`` holds for every pair),
        ``support_travel_factor``, ``support`` (the rules a part is supported by,
        :data:`cad.support.SUPPORT_RULES`), ``fits`` (``inner, outer, extra_shrink`` mm: the inner
        part is shrunk by that much more against the outer one only), ``through`` (pairs
        accepted as overlapping, nested too deep to part: never tested against each other,
        touching and resting on each other; only when there are some), ``open_parts`` and
        ``nearest`` (pairs across the model's gaps joining its contact graph's pieces,
        :func:`with_nearest`: ``part``, ``near`` on its ``side``, the ``gap`` in mm; each pair
        touches, and ``part`` rests on ``near`` when ``side`` is gravity, ``near`` on ``part``
        when it is the opposite; only when there are some).
    """
    ids = [str(p) for p in relations.parts]
    reach = tuple(getattr(relations, "part_reach", ()))
    return {
        "merge_vertices": True,
        "erosion": "face_planes",
        "free_edge_pull": FREE_EDGE_PULL,
        "contact_reach": dict(zip(ids, map(float, reach), strict=True)) if reach else None,
        "support_travel_factor": SUPPORT_TRAVEL_FACTOR,
        "support": list(SUPPORT_RULES),
        "fits": [
            {"inner": str(i), "outer": str(o), "extra_shrink": float(e)}
            for i, o, e in getattr(relations, "fits", ())
        ],
        **(
            {"through": [[str(a), str(b)] for a, b in through]}
            if (through := getattr(relations, "through", ()))
            else {}
        ),
        "open_parts": [str(p) for p in getattr(relations, "open_parts", ())],
        **(
            {
                "nearest": [
                    {"part": str(a), "near": str(b), "side": DIRECTIONS[d], "gap": float(gap)}
                    for a, b, d, gap in nearest
                ]
            }
            if (nearest := getattr(relations, "nearest", ()))
            else {}
        ),
    }


def _indices(
    relations: Relations, p: str | int, subset: Iterable[str | int]
) -> tuple[int, list[int]]:
    ip = relations.index(p)
    members = sorted({relations.index(j) for j in subset})
    if not members:
        raise GeometryError("the subassembly S must not be empty")
    if ip in members:
        raise GeometryError(f"part {relations.parts[ip]!r} is already in S")
    return ip, members


def rtc(relations: Relations, p: str | int, S: Iterable[str | int]) -> bool:
    """Eq. 3: ``RTC(p, S) = OR_d OR_{j in S} TC_d(p, j)`` (p touches the subassembly)."""
    ip, members = _indices(relations, p, S)
    return bool(relations.tc[ip, members, :].any())


def tt_set(relations: Relations, p: str | int, S: Iterable[str | int]) -> np.ndarray:
    """Eq. 4: ``TT_d(p, S) = AND_{j in S} TT_d(p, j)``, bool array of shape ``(6,)``."""
    ip, members = _indices(relations, p, S)
    return relations.tt[ip, members, :].all(axis=0)


def rtt(relations: Relations, p: str | int, S: Iterable[str | int]) -> bool:
    """Eq. 5: ``RTT(p, S) = OR_d TT_d(p, S)`` (some straight direction is free)."""
    return bool(tt_set(relations, p, S).any())


def _up(mm: float) -> float:
    """``mm`` rounded up to 0.1 micrometre (a fit's extra shrink, never below the one used)."""
    return float(np.ceil(mm * 1e4) / 1e4)
