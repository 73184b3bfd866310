"""Contact ``TC_d(i, j)``: parts i and j touch and j lies on the ``d`` side of i.

Rule
----
Along each axis, a face of i whose outward normal has a component of at least
:data:`cad.tolerances.CONTACT_NORMAL_MIN` (0.25, i.e. the normal is within about 75.5
degrees of ``d``) along ``d`` is paired with a face of j whose normal has at least that
component along ``-d``. If their projections along ``d`` overlap and somewhere on the
overlap the gap between them, measured along the face normal (gap along ``d`` times the
mean normal component), lies in ``[-tol(i, j), contact_tol(i, j)]``, then j touches i on
its ``d`` side: ``TC_d(i, j)`` and, by the same evidence, ``TC_-d(j, i)``. A negative gap
(overlap) counts only where the two faces overlap with positive area; faces that merely meet
along an edge count only within :data:`cad.tolerances.DEFAULT_CONTACT_TOL_MM` (0.01 mm),
so a step or a hole continued in the next part at a slightly different depth is not taken
for a sideways contact. Here ``tol(i, j)`` is the pair's penetration tolerance, by default
the sum of the two parts' shrinks, and ``contact_tol(i, j)`` its contact tolerance, by
default from the smaller part's size so that clearance fits touch (:mod:`cad.tolerances`).
The range of the gap over the overlap polygon is exact
(:func:`cad.projection.height_gap_range`).

So a face contact on an axis-aligned plane gives exactly its axis direction; a face on an
inclined plane gives every axis direction its normal leans towards by at least 0.25 (a
45-degree face gives two directions); a round peg touching a hole wall, or sitting in it with a
clearance within the contact tolerance, gives the four sideways directions (those in which
the gap is within the tolerance). Two parts whose closest surfaces face each other at a steep angle
(edge against edge, both normals further than 75.5 degrees from every axis) get no
direction. Touching along only a line or a point counts (e.g. two boxes that share an
edge are in contact along both faces' axes).

Open meshes (:func:`distance_contacts`)
---------------------------------------
Parts cut from one visual mesh lack the faces where they meet: no face of one opposes a
face of the other, though their surfaces touch. For a pair with an open part (a mesh that
is not watertight) and no contact by faces, contact is decided by distance: the two
surfaces come within the pair's contact tolerance (FCL's distance of the meshes). The
direction is the axis along which the parts' surface centroids lie farthest apart (j on
that side of i); :func:`cad.relations.compute_relations` takes it as contact and, the
open part having no face to rest on, as support along it.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse.csgraph import connected_components

from cad.assembly import Assembly
from cad.faces import FaceSet, axis_face_sets, bounds_overlap, crop_pair, unit_normals
from cad.progress import progress_bar
from cad.projection import box_pair_chunks, height_gap_range, overlap_share
from cad.tolerances import CONTACT_NORMAL_MIN, DEFAULT_CONTACT_TOL_MM, resolve_tolerances

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
        Contact tolerance in mm for every pair: largest gap that still counts as touching
        (default: per pair, from the smaller part's size, :mod:`cad.tolerances`).
    penetration_tol : float or Tolerances, optional
        Largest overlap in mm that counts as touching, for every pair; default the
        per-part rule of :mod:`cad.tolerances` (``s_i + s_j`` for the pair).
    progress : bool
        Show a progress bar over the pairs.

    Returns
    -------
    np.ndarray
        Bool, shape ``(n, n, 6)``: ``tc[i, j, d]`` is true iff i and j touch with j on
        the ``d`` side of i (order ``+x,-x,+y,-y,+z,-z``). ``tc[i, j, d] ==
        tc[j, i, d ^ 1]``; the diagonal is false.
    """
    tols = resolve_tolerances(assembly, tol, penetration_tol)
    n = len(assembly)
    tc = np.zeros((n, n, 6), dtype=bool)
    triangles = [np.asarray(p.mesh.triangles, dtype=float) for p in assembly.parts]
    normals = [unit_normals(t) for t in triangles]
    bounds = [p.bounds for p in assembly.parts]
    pairs = [(a, b) for a in range(n) for b in range(n) if a != b]
    bar = progress_bar(progress, 3 * len(pairs), "contact")
    for axis in range(3):
        sets = [
            axis_face_sets(t, nn, axis, CONTACT_NORMAL_MIN)
            for t, nn in zip(triangles, normals, strict=True)
        ]
        for a, b in pairs:
            bar.update(1)
            ptol, ctol = tols.pair(a, b), tols.contact_pair(a, b)
            if not bounds_overlap(bounds[a], bounds[b], pad=(ctol + ptol) / CONTACT_NORMAL_MIN):
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
    front, back = crop_pair(front, back, lo, hi)
    for ia, ib in box_pair_chunks(front.box, back.box):
        near = (back.hmin[ib] - front.hmax[ia] <= hi) & (back.hmax[ib] - front.hmin[ia] >= lo)
        ia, ib = ia[near], ib[near]
        order = np.argsort(-overlap_share(front.box[ia], back.box[ib]), kind="stable")
        ia, ib = ia[order], ib[order]
        for start in range(0, len(ia), _CHUNK):
            sa, sb = ia[start : start + _CHUNK], ib[start : start + _CHUNK]
            p_uv, p_h = front.take(sa)
            q_uv, q_h = back.take(sb)
            overlap, gap_min, gap_max = height_gap_range(p_uv, p_h, q_uv, q_h)
            cosine = 0.5 * (front.nk[sa] - back.nk[sb])
            lower, upper = gap_min * cosine, gap_max * cosine
            # Touching within the contact tolerance: a shared face, edge or point, or a
            # clearance (a gap up to contact_tol); edges meet within the fixed 0.01 mm.
            edge_tol = min(contact_tol, DEFAULT_CONTACT_TOL_MM)
            if np.any(overlap & (lower <= contact_tol) & (upper >= -edge_tol)):
                return True
            # Overlapping up to the penetration tolerance counts only where the faces
            # overlap with positive area: faces merely meeting along an edge at different
            # depths (a step, a hole continued in the next part) are not a contact.
            deep = overlap & (lower <= contact_tol) & (upper >= -penetration_tol)
            if np.any(deep):
                k = np.flatnonzero(deep)
                inner, g_min, g_max = height_gap_range(
                    _shrink(p_uv[k]), p_h[k], _shrink(q_uv[k]), q_h[k]
                )
                hit = inner & (g_min * cosine[k] <= contact_tol)
                hit &= g_max * cosine[k] >= -penetration_tol
                if np.any(hit):
                    return True
    return False


_AREA_SHRINK = 1e-4
"""Projected triangles are scaled about their centroids by ``1 - _AREA_SHRINK`` to tell a
shared area (still overlapping) from a shared edge or point (no longer overlapping)."""


def _shrink(uv: np.ndarray) -> np.ndarray:
    """Triangles ``(N, 3, 2)`` scaled slightly about their centroids."""
    centre = uv.mean(axis=1, keepdims=True)
    return centre + (uv - centre) * (1.0 - _AREA_SHRINK)


def distance_contacts(assembly: Assembly, tols, tc: np.ndarray) -> list[tuple[int, int, int]]:
    """``(a, b, d)``: parts ``a < b``, one of them open, with no contact by faces (``tc``)
    whose surfaces lie within the pair's contact tolerance; ``b`` on the ``d`` side of ``a``
    (module docstring, "Open meshes")."""
    import fcl

    parts = assembly.parts
    is_open = [not p.mesh.is_watertight for p in parts]
    if not any(is_open):
        return []
    objects: dict[int, object] = {}

    def obj(k: int):
        if k not in objects:
            objects[k] = fcl_object(parts[k].mesh)
        return objects[k]

    found = []
    for a in range(len(parts)):
        for b in range(a + 1, len(parts)):
            if not (is_open[a] or is_open[b]) or tc[a, b].any():
                continue
            ctol = tols.contact_pair(a, b)
            if not bounds_overlap(parts[a].bounds, parts[b].bounds, pad=ctol):
                continue
            gap = fcl.distance(obj(a), obj(b), fcl.DistanceRequest(), fcl.DistanceResult())
            if gap <= ctol:
                delta = _surface_centroid(parts[b].mesh) - _surface_centroid(parts[a].mesh)
                axis = int(np.argmax(np.abs(delta)))
                found.append((a, b, 2 * axis + (0 if delta[axis] >= 0 else 1)))
    return found


NEAREST_SHARE = 0.5
"""Pieces of the contact graph are joined across a gap of at most this share of the
smaller part's bounding-box diagonal (:func:`nearest_contacts`)."""


def nearest_contacts(assembly: Assembly, tc: np.ndarray) -> list[tuple[int, int, int, float]]:
    """``(a, b, d, gap)``: the pairs across a model's gaps that join the parts' contact graph
    (``tc``, either way) into one piece: the pair of parts of two different pieces with the
    smallest gap first, then the next, as a minimum spanning forest of the pieces; a pair
    is taken only when its gap is at most :data:`NEAREST_SHARE` of the smaller part's
    diagonal, ``b`` on the ``d`` side of ``a`` (the axis of the centroids' offset). None
    when no two parts touch at all (then the contact tolerance or the unit is the question,
    not parts off the product).

    Why: a part may only be inserted touching the parts already there, so the parts
    placed always form one piece of the contact graph, and a product whose graph is in
    pieces has no plan. A visual model floats parts a little off the part they are fixed
    to (a satellite's mounting plate 2.3 mm off its front, a board on stand-offs short of
    it, the fasteners not modelled); joining the pieces by their nearest parts changes only
    such files, and only those pairs."""
    import fcl

    parts = assembly.parts
    n = len(parts)
    touches = np.asarray(tc, bool).any(axis=2)
    touches = touches | touches.T
    if not touches.any():  # nothing touches: a tolerance, not a model's gap
        return []
    piece = connected_components(touches, directed=False)[1]
    if piece.max() == 0:
        return []
    objects = [fcl_object(p.mesh) for p in parts]
    diagonal = [float(np.linalg.norm(np.ptp(p.bounds, axis=0))) for p in parts]
    pairs = []
    for a in range(n):
        for b in range(a + 1, n):
            if piece[a] == piece[b]:
                continue
            gap = fcl.distance(objects[a], objects[b], fcl.DistanceRequest(), fcl.DistanceResult())
            if gap <= NEAREST_SHARE * min(diagonal[a], diagonal[b]):
                pairs.append((float(gap), a, b))
    root = list(range(int(piece.max()) + 1))

    def find(k: int) -> int:
        while root[k] != k:
            root[k] = root[root[k]]
            k = root[k]
        return k

    found = []
    for gap, a, b in sorted(pairs):
        if find(piece[a]) == find(piece[b]):
            continue
        root[find(piece[b])] = find(piece[a])
        delta = _surface_centroid(parts[b].mesh) - _surface_centroid(parts[a].mesh)
        axis = int(np.argmax(np.abs(delta)))
        found.append((a, b, 2 * axis + (0 if delta[axis] >= 0 else 1), gap))
    return found


def fcl_object(mesh):
    """An FCL collision object of a mesh in place."""
    import fcl

    model = fcl.BVHModel()
    model.beginModel(len(mesh.vertices), len(mesh.faces))
    model.addSubModel(np.asarray(mesh.vertices, float), np.asarray(mesh.faces, dtype=np.int32))
    model.endModel()
    return fcl.CollisionObject(model, fcl.Transform())


def _surface_centroid(mesh) -> np.ndarray:
    """The area-weighted centre of a mesh's faces (open or closed)."""
    areas = np.asarray(mesh.area_faces)
    return (np.asarray(mesh.triangles_center) * areas[:, None]).sum(axis=0) / max(
        areas.sum(), 1e-300
    )
