"""Contact ``TC_d(i, j)``: parts i and j touch and j lies on the ``d`` side of i.

Rule
----
Along each axis, a face of i whose outward normal has a component of at least
:data:`cad.tolerances.CONTACT_NORMAL_MIN` (0.25, i.e. the normal is within about 75.5
degrees of ``d``) along ``d`` is paired with a face of j whose normal has at least that
component along ``-d``. If their projections along ``d`` overlap and somewhere on the
overlap the gap between them, measured along the face normal (gap along ``d`` times the
mean normal component), lies in ``[-penetration_tol, contact_tol]``, then j touches i on
its ``d`` side: ``TC_d(i, j)`` and, by the same evidence, ``TC_-d(j, i)``. The range of
the gap over the overlap polygon is exact (:func:`cad.projection.height_gap_range`).

So a face contact on an axis-aligned plane gives exactly its axis direction; a face on an
inclined plane gives every axis direction its normal leans towards by at least 0.25 (a
45-degree face gives two directions); a round peg touching a hole wall gives the four
sideways directions. Two parts whose closest surfaces face each other at a steep angle
(edge against edge, both normals further than 75.5 degrees from every axis) get no
direction. Touching along only a line or a point counts (e.g. two boxes that share an
edge are in contact along both faces' axes).
"""

from __future__ import annotations

import numpy as np

from cad.assembly import Assembly
from cad.faces import FaceSet, axis_face_sets, bounds_overlap, unit_normals
from cad.freedom import part_diagonals
from cad.progress import progress_bar
from cad.projection import box_pair_chunks, height_gap_range
from cad.tolerances import CONTACT_NORMAL_MIN, resolve_tolerances

_CHUNK = 4096


def contact_relation(
    assembly: Assembly,
    tol: float | None = None,
    *,
    penetration_tol: float | None = None,
    progress: bool = False,
) -> np.ndarray:
    """Contact of every ordered pair of parts, per direction.

    Parameters
    ----------
    assembly : Assembly
        ``n`` parts in assembled pose (mm).
    tol : float, optional
        Contact tolerance in mm: largest gap that still counts as touching (default
        :data:`cad.tolerances.DEFAULT_CONTACT_TOL_MM`, 0.01 mm).
    penetration_tol : float, optional
        Largest overlap in mm that counts as touching (default
        :func:`cad.tolerances.default_penetration_tol`).
    progress : bool
        Show a progress bar over the pairs.

    Returns
    -------
    np.ndarray
        Bool, shape ``(n, n, 6)``: ``tc[i, j, d]`` is true iff i and j touch with j on
        the ``d`` side of i (order ``+x,-x,+y,-y,+z,-z``). ``tc[i, j, d] ==
        tc[j, i, d ^ 1]``; the diagonal is false.
    """
    ctol, ptol = resolve_tolerances(part_diagonals(assembly), tol, penetration_tol)
    n = len(assembly)
    tc = np.zeros((n, n, 6), dtype=bool)
    triangles = [np.asarray(p.mesh.triangles, dtype=float) for p in assembly.parts]
    normals = [unit_normals(t) for t in triangles]
    bounds = [p.bounds for p in assembly.parts]
    reach = (ctol + ptol) / CONTACT_NORMAL_MIN
    pairs = [(a, b) for a in range(n) for b in range(n) if a != b]
    bar = progress_bar(progress, 3 * len(pairs), "contact")
    for axis in range(3):
        sets = [
            axis_face_sets(t, nn, axis, CONTACT_NORMAL_MIN)
            for t, nn in zip(triangles, normals, strict=True)
        ]
        for a, b in pairs:
            bar.update(1)
            if not bounds_overlap(bounds[a], bounds[b], pad=reach):
                continue
            if faces_touch(sets[a][0], sets[b][1], ctol, ptol):
                tc[a, b, 2 * axis] = True
                tc[b, a, 2 * axis + 1] = True
    bar.close()
    return tc


def faces_touch(front: FaceSet, back: FaceSet, contact_tol: float, penetration_tol: float) -> bool:
    """Whether faces of i facing ``+axis`` touch faces of j facing ``-axis``.

    Parameters
    ----------
    front, back : FaceSet
        Faces of i towards ``+axis`` and of j towards ``-axis``.
    contact_tol, penetration_tol : float
        Largest gap and largest overlap (mm, along the normal) that count as touching.

    Returns
    -------
    bool
        True iff some pair overlaps in projection with a normal gap in
        ``[-penetration_tol, contact_tol]`` somewhere on the overlap.
    """
    lo = -penetration_tol / CONTACT_NORMAL_MIN
    hi = contact_tol / CONTACT_NORMAL_MIN
    for ia, ib in box_pair_chunks(front.box, back.box):
        near = (back.hmin[ib] - front.hmax[ia] <= hi) & (back.hmax[ib] - front.hmin[ia] >= lo)
        ia, ib = ia[near], ib[near]
        for start in range(0, len(ia), _CHUNK):
            sa, sb = ia[start : start + _CHUNK], ib[start : start + _CHUNK]
            overlap, gap_min, gap_max = height_gap_range(*front.take(sa), *back.take(sb))
            cosine = 0.5 * (front.nk[sa] - back.nk[sb])
            hit = (
                overlap & (gap_min * cosine <= contact_tol) & (gap_max * cosine >= -penetration_tol)
            )
            if np.any(hit):
                return True
    return False
