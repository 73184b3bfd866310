"""Default tolerances, in millimetres, and how they follow the size of each part.

Contact tolerance: per part, the smaller part of a pair decides
----------------------------------------------------------------
Two parts are in contact where their facing surfaces are at most the pair's contact
tolerance apart (or overlap by at most the penetration tolerance). Real products are full
of clearance fits (a pin in its hole, a bolt in a clearance hole, a shaft in a bush) whose
surfaces never meet: the gap is a design clearance, not a sign that the parts are apart.
Every part ``p`` gets a contact reach ``c_p`` and a pair the smaller of its two reaches::

    c_p = min( max(0.01 mm, 0.02 x D_p),  0.2 mm )
    contact_tol(i, j) = min(c_i, c_j)

with ``D_p`` the diagonal of the part's bounding box, as below. So the gap that counts as
touching follows the smaller part (a clearance is cut for the pin, not for the plate):
a 5.6 mm pin accepts 0.11 mm (the Fabrica duct's pins sit in their holes with 0.1 mm
radial clearance; Fabrica itself used 0.2), an M3 screw (D ~ 12 mm) 0.2 mm, a 0.5 mm
ball 0.01 mm (the floor, the old fixed tolerance). The cap, 0.2 mm, keeps parts that are
merely near each other apart (a 0.25 mm gap between a 6 mm wheel and its body is not a
contact). The direction is the contact's as in DESIGN.md: for a pin with radial
clearance, the sideways directions in which the gap is within the tolerance (all four
when the pin is centred). Edges meeting at different depths still count only within
:data:`DEFAULT_CONTACT_TOL_MM` (:mod:`cad.contact`).

An explicit ``contact_tol`` (``--contact-tol``) replaces the rule for every pair.

Penetration tolerance: per-part shrink amounts, summed per pair
---------------------------------------------------------------
Every part ``p`` gets a *shrink* ``s_p``: its faces are moved inwards by ``s_p`` before
the interference check and the sweep test (:mod:`cad.freedom`). Two parts whose surfaces
overlap by at most ``s_i + s_j`` are then disjoint, so the penetration tolerance of a
pair is the sum of the shrinks of its two parts::

    s_p = min( max(0.025 mm, 0.003 x D_p),  0.25 mm,  0.1 x T_p )
    tol(i, j) = s_i + s_j

- ``D_p`` is the diagonal of the part's bounding box: big parts are exported with coarser
  tessellation and drawn with bigger interferences, so their shrink grows with their size
  (0.3 % of the diagonal), from a floor of 0.025 mm (a pair of small parts keeps the old
  0.05 mm) to a cap of 0.25 mm (two big parts accept 0.5 mm, never more).
- ``T_p`` is the part's thickness: the smallest extent of its bounding box and, for a
  closed mesh, its mean wall thickness ``2 V / A`` (volume over half the surface area; a
  sheet of thickness t gives about t, a round bar of radius r gives r). A part is never
  shrunk by more than a tenth of it, so a thin sheet keeps 80 % of its thickness and
  still blocks, and a small screw is not eroded away.

What this accepts, with the default rule (pair tolerances of ordinary parts):

==============================================  ==========================
two 10 mm cubes                                  0.104 mm
M8 bolt (D ~ 38 mm) in a 100 mm bracket          0.115 + 0.25 = 0.365 mm
two 150 x 80 x 6 mm finger-jointed panels        0.25 + 0.25 = 0.5 mm
spur gears of 44 and 64 mm (10 mm thick)         0.189 + 0.25 = 0.44 mm
0.5 mm sheet against anything                    at most 0.05 mm from the sheet
==============================================  ==========================

so tessellation overlaps (hundredths), zero-clearance pins drawn at the hole diameter
with another polygon, finger joints cut with kerf compensation and press fits interfering
by two to four tenths pass as they come. An overlap no deeper than the pair's tolerance
counts as touching; a deeper one in the assembled pose is a ValueError naming the pair and
the depth, unless it is a *fit* (:mod:`cad.fits`): a screw, stud or pin in a hole drawn
at the tap-drill diameter or pressed in, overlapping the wall all round by up to a fifth of
its thickness. Features shallower than the tolerance do not block a slide either (a 0.2 mm
ridge between two 100 mm parts is ignored), which is the price of accepting real exports.

An explicit ``penetration_tol`` (``--penetration-tol``) replaces the rule: every part then
shrinks by ``penetration_tol / 2`` and every pair has exactly that tolerance.

Support travel
--------------
A part is supported if a fall of ``3 x tol(i, j)`` (:data:`cad.support.SUPPORT_TRAVEL_FACTOR`)
would drive it into a part already there (:mod:`cad.support`): it may stand on that part
or hang in it across a clearance of up to ``2 x tol(i, j)``. A part fitted in a hole of
that part (a dowel, a screw, a shaft in a bore) may fall further, up to the shorter of the
two parts' extents along gravity: the hole guides it onto the bottom or the shoulder.

Both tolerances are in millimetres whatever the source unit, because meshes are stored in
mm; the same parts therefore give the same tables in any unit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

from cad.errors import GeometryError
from cad.numbers import plain_number

DEFAULT_CONTACT_TOL_MM = 0.01
"""Smallest default contact tolerance (the floor of the per-part rule)."""
CONTACT_PER_SIZE = 0.02
"""Default contact reach per mm of the part's bounding-box diagonal."""
CONTACT_CAP_MM = 0.2
"""Largest default contact reach of a part."""
DEFAULT_PENETRATION_TOL_MM = 0.05
"""Smallest default pair tolerance (two parts at the shrink floor)."""
SHRINK_FLOOR_MM = 0.025
"""Smallest default shrink of a part (before the thickness limit)."""
SHRINK_PER_SIZE = 3e-3
"""Default shrink per mm of the part's bounding-box diagonal."""
SHRINK_CAP_MM = 0.25
"""Largest default shrink of a part."""
SHRINK_PER_THICKNESS = 0.1
"""A part is never shrunk by more than this share of its thickness."""
PENETRATION_TOL_PER_SIZE = SHRINK_PER_SIZE
"""Kept for callers of the old name; see :data:`SHRINK_PER_SIZE`."""
TOL_LIMIT_MM = 100.0
"""Largest explicit contact or penetration tolerance (mm) accepted."""
CONTACT_NORMAL_MIN = 0.25
"""A surface faces direction ``d`` for contact if its normal's component along ``d`` is at
least this (normal within about 75.5 degrees of ``d``)."""


def checked_tolerance(value, name: str) -> float | None:
    """An explicit tolerance (mm) after the range check; None stays None (the default rule).

    ``name`` is ``contact_tol`` (``0 <= value <= TOL_LIMIT_MM``) or ``penetration_tol``
    (``0 < value <= TOL_LIMIT_MM``).

    Raises
    ------
    GeometryError
        One line naming the tolerance, the range and the value.
    """
    if value is None:
        return None
    low = "0" if name == "contact_tol" else "above 0"
    wanted = f"{name}: expected a number of mm from {low} to {TOL_LIMIT_MM:g}, got {value!r}"
    number = plain_number(value)
    if number is None:
        raise GeometryError(wanted)
    too_low = number < 0 if name == "contact_tol" else number <= 0
    if not np.isfinite(number) or too_low or number > TOL_LIMIT_MM:
        raise GeometryError(wanted)
    return number


def part_thickness(mesh: trimesh.Trimesh) -> float:
    """Thickness of a part in mm: smallest bounding-box extent, and ``2 V / A`` if closed."""
    extents = np.ptp(np.asarray(mesh.bounds, dtype=float), axis=0)
    thickness = float(extents.min())
    if mesh.is_watertight:
        area = float(mesh.area)
        volume = abs(float(mesh.volume))
        if area > 0 and volume > 0:
            thickness = min(thickness, 2.0 * volume / area)
    return thickness


def part_shrink(diagonal_mm: float, thickness_mm: float) -> float:
    """Default shrink (mm) of a part with this bounding-box diagonal and thickness (mm)."""
    by_size = min(max(SHRINK_FLOOR_MM, SHRINK_PER_SIZE * float(diagonal_mm)), SHRINK_CAP_MM)
    return min(by_size, SHRINK_PER_THICKNESS * float(thickness_mm))


def part_contact_reach(diagonal_mm: float) -> float:
    """Default contact reach (mm) of a part with this bounding-box diagonal (mm)."""
    by_size = max(DEFAULT_CONTACT_TOL_MM, CONTACT_PER_SIZE * float(diagonal_mm))
    return min(by_size, CONTACT_CAP_MM)


def part_diagonals(meshes: list[trimesh.Trimesh]) -> np.ndarray:
    """Bounding-box diagonal of each mesh (mm), shape ``(n,)``."""
    return np.array(
        [float(np.linalg.norm(np.ptp(np.asarray(m.bounds), axis=0))) for m in meshes]
    ).reshape(len(meshes))


def default_contact_reaches(meshes: list[trimesh.Trimesh]) -> np.ndarray:
    """Default contact reach of each mesh (mm), shape ``(n,)``."""
    return np.array([part_contact_reach(d) for d in part_diagonals(meshes)]).reshape(len(meshes))


def default_shrinks(meshes: list[trimesh.Trimesh]) -> np.ndarray:
    """Default shrink of each mesh (mm), shape ``(n,)``."""
    diagonals = part_diagonals(meshes)
    return np.array(
        [part_shrink(d, part_thickness(m)) for d, m in zip(diagonals, meshes, strict=True)]
    ).reshape(len(meshes))


def default_penetration_tol(diagonals_mm: np.ndarray) -> float:
    """Default tolerance (mm) of a pair of two parts of the median diagonal (thick parts).

    The tolerance actually used is per pair (:class:`Tolerances`); this is a summary.
    """
    if len(diagonals_mm) == 0:
        return DEFAULT_PENETRATION_TOL_MM
    median = float(np.median(diagonals_mm))
    return 2.0 * part_shrink(median, np.inf)


@dataclass(frozen=True, eq=False)
class Tolerances:
    """Tolerances of one assembly, in mm.

    Attributes
    ----------
    contact : float
        Largest gap that counts as touching, for any pair (the explicit value if one was
        given); pair ``(i, j)`` uses :meth:`contact_pair`.
    shrink : np.ndarray
        Per-part shrink, shape ``(n,)``; the penetration tolerance of pair ``(i, j)`` is
        ``shrink[i] + shrink[j]``.
    explicit : bool
        The penetration tolerance was given (every shrink is half of it).
    reach : np.ndarray or None
        Per-part contact reach, shape ``(n,)``; pair ``(i, j)`` counts a gap up to
        ``min(reach[i], reach[j])`` as touching. None: ``contact`` for every pair.
    """

    contact: float
    shrink: np.ndarray
    explicit: bool = False
    reach: np.ndarray | None = None

    def contact_pair(self, a: int, b: int) -> float:
        """Contact tolerance of parts ``a`` and ``b`` (largest gap that counts as touching)."""
        if self.reach is None:
            return float(self.contact)
        return float(min(self.reach[a], self.reach[b]))

    def pair(self, a: int, b: int) -> float:
        """Penetration tolerance of parts ``a`` and ``b``."""
        return float(self.shrink[a] + self.shrink[b])

    @property
    def penetration(self) -> float:
        """Largest penetration tolerance of any pair (the explicit value if one was given)."""
        if len(self.shrink) == 0:
            return DEFAULT_PENETRATION_TOL_MM
        top = np.sort(self.shrink)[-2:]
        return float(top.sum() if len(top) == 2 else 2 * top[0])


def resolve_tolerances(
    assembly, contact_tol: float | None = None, penetration_tol: float | None = None
) -> Tolerances:
    """Tolerances of ``assembly`` (a :class:`cad.Assembly` or a list of meshes, in mm).

    ``penetration_tol`` None gives the per-part default rule of this module, a number the
    same tolerance for every pair. A :class:`Tolerances` passed as ``penetration_tol`` is
    returned as is (with ``contact_tol`` filled in if given).

    Raises
    ------
    ValueError
        A tolerance out of range (:func:`checked_tolerance`).
    """
    meshes = [p.mesh for p in assembly.parts] if hasattr(assembly, "parts") else list(assembly)
    if isinstance(penetration_tol, Tolerances):
        if contact_tol is None:
            return penetration_tol
        base = penetration_tol
        penetration_tol, explicit_shrink = None, base.shrink
    else:
        explicit_shrink = None
    if contact_tol is None:
        reach = default_contact_reaches(meshes)
        ctol = _largest_pair_reach(reach)
    else:
        reach, ctol = None, checked_tolerance(contact_tol, "contact_tol")
    if explicit_shrink is not None:
        return Tolerances(ctol, explicit_shrink, base.explicit, reach)
    if penetration_tol is None:
        return Tolerances(ctol, default_shrinks(meshes), False, reach)
    ptol = checked_tolerance(penetration_tol, "penetration_tol")
    return Tolerances(ctol, np.full(len(meshes), ptol / 2.0), True, reach)


def _largest_pair_reach(reach: np.ndarray) -> float:
    """Largest ``min(reach[i], reach[j])`` over pairs ``i != j`` (a summary of the rule)."""
    if len(reach) < 2:
        return DEFAULT_CONTACT_TOL_MM if len(reach) == 0 else float(reach[0])
    return float(np.sort(reach)[-2])
