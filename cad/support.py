"""Support ``SP_d(i, j)``: would part i, let fall along d, be stopped by part j?

DESIGN.md ("Support"): a part p is supported in ``S + {p}`` iff it cannot fall. This module
gives the pairwise relation the state graph ORs over ``S`` (a bitset test, like contact and
freedom); ``d`` is the gravity direction of the spec (``-z`` by default).

Rule
----
``SP_d(i, j)`` holds iff either

1. **Drop test.** Moving i along ``d`` by the *support travel* ``t(i, j)`` would drive it
   into j deeper than the pair's penetration tolerance. It is the exact sweep test of
   :mod:`cad.freedom` (parts eroded by their shrinks, :mod:`cad.tolerances`), limited to
   the travel: some face of i facing ``d`` and some face of j facing ``-d`` overlap in
   projection with ``0 <= h_j - h_i <= t`` somewhere on the overlap. The travel is
   ``SUPPORT_TRAVEL_FACTOR`` (3) times the pair's tolerance ``s_i + s_j``; since erosion
   already opens a gap of ``s_i + s_j`` between faces that touch, a part standing on j,
   or hanging in it across a clearance of up to twice the tolerance (a shaft lying in a
   bearing bore, the fingers of a box side standing in the base's slots with kerf
   clearance) is supported; a part with nothing within that distance below falls.
   Faces need not lie flat on each other: inclined faces (a cone, a chamfer, a finger
   flank) stop the fall just as well.
2. **Captured in a hole.** i is fitted in j across the gravity axis (j touches i and
   blocks it in each of the four directions across ``d``: a pin in a hole, a shaft in a
   bore) and a fall along ``d`` of at most the *capture travel* ``min(e_i, e_j)``, the
   shorter of the two parts' extents along ``d``, drives i into j. A dowel drawn a little
   above the bottom of its blind hole, or a shaft in a bore whose shoulder lies further
   down, slides along the hole it is guided by and stops on j; it cannot fall away. A pin
   in a through hole is not captured (nothing of j lies below it).
3. **Threaded on.** i is fitted around j along the gravity axis: j touches i and blocks
   it in each of the four directions across ``d`` (``TC`` true and ``TT`` false for each:
   a zero-clearance or press fit all round) and j's cross-section at i's mid-height lies
   inside i's (j passes through i). A nut on a bolt, a press-fitted bearing on a
   shaft or a washer on a stud does not fall off a vertical bolt although nothing lies
   below it: the thread or the fit holds it (CAD draws threads as plain cylinders, so the
   drop test alone would let every hanging nut fall). The converse does not hold: a bolt
   passing through a plate is not threaded on the plate (the plate's section is not
   inside the bolt's).

So a nut waits for its bolt, a screw for the part its head or thread bears on, a box side
stands in the base's fingers, and a part merely touching the assembly from the side or
from below (``TC`` without support) needs to be ``held``.
"""

from __future__ import annotations

import numpy as np
import trimesh

from cad.assembly import Assembly
from cad.freedom import facing_pairs, sweep_blocked

SUPPORT_TRAVEL_FACTOR = 3.0
"""Support travel of a pair, in multiples of its penetration tolerance."""
SUPPORT_RULES = ("rests", "captured", "threaded")
"""The rules of the module docstring (drop test, captured in a hole, threaded on), as
``plan.json``'s ``geometry.support`` names them for a checker replaying a plan."""
_INSIDE_MARGIN = 1e-6
"""Relative slack of the cross-section containment test."""


def support_relation(
    assembly: Assembly,
    tols,
    eroded: list[trimesh.Trimesh],
    tc: np.ndarray,
    tt: np.ndarray,
    *,
    progress: bool = False,
) -> np.ndarray:
    """Support of every ordered pair of parts, for each direction of gravity.

    Parameters
    ----------
    assembly : Assembly
        ``n`` parts in assembled pose (mm).
    tols : cad.tolerances.Tolerances
        Tolerances of the assembly (pair tolerance ``s_i + s_j``).
    eroded : list of trimesh.Trimesh
        The parts eroded by their shrinks (:func:`cad.freedom.eroded_meshes`).
    tc, tt : (n, n, 6) bool
        Contact (:func:`cad.contact.contact_relation`) and translational freedom
        (:func:`cad.freedom.translational_freedom`).
    progress : bool
        Show a progress bar over the pairs.

    Returns
    -------
    (n, n, 6) bool
        ``sp[i, j, d]``: part i falling along direction ``d`` is stopped by part j (drop
        test or threaded on, see the module docstring). The diagonal is false.
    """
    n = len(assembly)
    sp = np.zeros((n, n, 6), dtype=bool)
    travel = SUPPORT_TRAVEL_FACTOR * (tols.shrink[:, None] + tols.shrink[None, :])
    fitted = [fitted_across(tc, tt, axis) for axis in range(3)]
    extents = np.array([np.ptp(p.bounds, axis=0) for p in assembly.parts]).reshape(n, 3)
    for axis, a, b, front, back, bounds in facing_pairs(eroded, progress, "support"):
        t = float(travel[a, b])
        if fitted[axis][a, b]:
            t = max(t, float(min(extents[a, axis], extents[b, axis])))
        # a falling along +axis is stopped by b (and b falling along -axis by a)
        if bounds[b][0, axis] - bounds[a][1, axis] > t or bounds[b][1, axis] < bounds[a][0, axis]:
            continue
        if sweep_blocked(front, back, travel=t):
            sp[a, b, 2 * axis] = True
            sp[b, a, 2 * axis + 1] = True
    meshes = [p.mesh for p in assembly.parts]
    for axis in range(3):
        for a, b in zip(*np.nonzero(fitted[axis]), strict=True):
            if a != b and threaded_on(meshes[a], meshes[b], axis):
                sp[a, b, 2 * axis] = sp[a, b, 2 * axis + 1] = True
    return sp


def fitted_across(tc: np.ndarray, tt: np.ndarray, axis: int) -> np.ndarray:
    """``(n, n)`` bool: j touches i and blocks it in each of the four directions across
    ``axis`` (a pin in a hole, a nut on a bolt, a shaft in a bore)."""
    across = [d for d in range(6) if d // 2 != axis]
    return tc[:, :, across].all(axis=2) & ~tt[:, :, across].any(axis=2)


def threaded_on(outer: trimesh.Trimesh, inner: trimesh.Trimesh, axis: int) -> bool:
    """Whether ``inner`` passes through ``outer`` along ``axis`` (a bolt through a nut).

    The cross-section of ``inner`` at the mid-height of ``outer`` (a plane across ``axis``)
    must exist and lie inside the cross-section bounds of ``outer`` at that height.
    """
    lo, hi = np.asarray(outer.bounds)[:, axis]
    normal = np.zeros(3)
    normal[axis] = 1.0
    origin = np.zeros(3)
    origin[axis] = 0.5 * (lo + hi)
    b_in = _section_bounds(inner, origin, normal)
    b_out = _section_bounds(outer, origin, normal)
    if b_in is None or b_out is None:
        return False
    others = [k for k in range(3) if k != axis]
    b_in, b_out = b_in[:, others], b_out[:, others]
    slack = _INSIDE_MARGIN * float(np.ptp(b_out, axis=0).max())
    inside = np.all(b_in[0] >= b_out[0] - slack) and np.all(b_in[1] <= b_out[1] + slack)
    smaller = np.any(np.ptp(b_in, axis=0) < np.ptp(b_out, axis=0) - slack)
    return bool(inside and smaller)


def _section_bounds(mesh: trimesh.Trimesh, origin: np.ndarray, normal: np.ndarray):
    """(2, 3) bounds of the cross-section of ``mesh`` by a plane, or None when the plane
    misses it: the bounds of ``mesh.section``'s segments, without building its path."""
    lines = trimesh.intersections.mesh_plane(mesh, plane_normal=normal, plane_origin=origin)
    if len(lines) == 0:
        return None
    points = np.asarray(lines, dtype=float).reshape(-1, 3)
    return np.array([points.min(axis=0), points.max(axis=0)])
