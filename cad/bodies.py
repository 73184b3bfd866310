"""The closed bodies of one mesh: a part that is several solids, split into one per body.

A CAD export sometimes fuses a whole product into one solid (FreeCAD's "toy truck" of the
APLAN benchmark: one STEP solid of 61 shells) or one STL/GLB mesh. :func:`closed_bodies`
finds the separate bodies of such a mesh; :mod:`cad.scene` makes each a part.

The rule, in this order:

1. Faces are joined where they share a vertex position (coordinates equal to within
   :data:`MERGE_DIGITS` significant digits of the mesh's size). OCCT tessellates each
   B-rep face on its own: faces of one shell may share their corner positions but not
   their edges (T-junctions), so joining by shared edges alone could cut a solid into its
   faces, while joining by positions keeps each shell whole. Shells that touch (parts of
   one fused solid resting face to face: the toy truck's cabin, chassis and supports)
   share positions too; a piece in which every edge (a pair of positions) is used by an
   even number of faces has no T-junction, and is split into its shells
   (:func:`_shells`): faces are joined across an edge of two faces, and where four or more
   meet with two of them back to back (two shells resting on each other) each face is
   joined to the face its solid's inside turns to first around the edge; where none lie
   back to back the solid touches itself along the edge (an Inventor part's lobes meeting
   along an edge) and all are joined.
2. Each piece must be a closed surface: its vector area (the sum of the face normals
   times the face areas) is zero for a closed surface whatever its tessellation, and
   equals the area of the hole for an open one. A piece is closed when the vector area is
   at most :data:`CLOSED_VECTOR_AREA` of its area. One open piece: the mesh is not split
   (it is a visual mesh, not solids).
3. A closed piece of negative volume (inward normals) is the cavity of the smallest body
   around its centroid (winding number one), and joins it; with no body around it, it is
   a body written inside out (the toy truck's mixer drum), and is turned.

Bodies come in the order of their first face in the mesh.

**Shells a STEP declares** (``shells``: the face count of each closed shell of the file's
one solid, :func:`cad.step.solid_shells`). Shells resting face to face on each other at
edges that do not meet end to end (T-junctions: the toy truck's cabin, chassis and drum
supports) stay one piece by rule 1. A STEP says how many shells there are and how many
B-rep faces each has, and OCCT tessellates each B-rep face as a patch of its own vertices,
a shell's faces one after the other (the shells themselves in an order of OCCT's). So when
the mesh's patches (faces joined by shared vertex indices) come in runs, as many as the
file's faces, the mesh is cut into consecutive runs of patches, one block per shell, each
block closed (rule 2's test) and connected (joined by positions), the blocks' sizes being
the shells' face counts, every one used once (:func:`_declared_shells`; a depth-first
search from the first patch, the smaller size first). A union of several shells, or an
open part of one, fails one of the tests, so a block that passes is one shell. With no
such cut, rule 1 applies as before.
"""

from __future__ import annotations

import numpy as np
import trimesh
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

MERGE_DIGITS = 8
"""Vertex positions are equal when they agree to this many digits of the mesh's size
(1e-8 x its bounding-box diagonal: 1 nm on a 100 mm part; OCCT writes a shared B-rep
vertex with the same coordinates into every face it bounds)."""
CLOSED_VECTOR_AREA = 1e-4
"""A piece is closed when its vector area is at most this fraction of its area."""
FLUSH_RADIANS = 1e-3
"""Two faces about one edge within this angle lie on each other (back to back: two
shells touching; the tessellations of one curved contact differ by about 2e-5 rad)."""


def closed_bodies(
    mesh: trimesh.Trimesh, shells: tuple[int, ...] | None = None
) -> tuple[trimesh.Trimesh, ...] | None:
    """The closed bodies of ``mesh`` when it holds two or more, else None.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        One part's mesh, in any unit and frame.
    shells : tuple of int, optional
        The face count of each shell of the STEP solid the mesh tessellates (the module's
        "Shells a STEP declares"); None: the mesh alone decides.

    Returns
    -------
    tuple of trimesh.Trimesh or None
        One mesh per body (a cavity joined to the body around it, a body written inside
        out turned), in the order of their first face; None when the mesh is one body, or
        a piece of it is open (see the module's rule).
    """
    faces = np.asarray(mesh.faces)
    if len(faces) < 8:
        return None
    labels = _declared_shells(mesh, shells) if shells and len(shells) > 1 else None
    labels = _pieces(mesh) if labels is None else labels
    count = int(labels.max()) + 1
    if count < 2:
        return None
    triangles = np.asarray(mesh.triangles)
    areas = np.asarray(mesh.area_faces)
    vector = np.zeros((count, 3))
    np.add.at(vector, labels, np.asarray(mesh.face_normals) * areas[:, None])
    area = np.bincount(labels, weights=areas, minlength=count)
    if np.any(np.linalg.norm(vector, axis=1) > CLOSED_VECTOR_AREA * area):
        return None
    signed = np.einsum("ij,ij->i", triangles[:, 0], np.cross(triangles[:, 1], triangles[:, 2]))
    volume = np.bincount(labels, weights=signed / 6.0, minlength=count)
    owner = _cavity_owners(triangles, labels, volume)
    bodies = []
    for body in np.unique(owner):
        members = np.nonzero(owner == body)[0]
        pieces = [_piece_mesh(mesh, labels, k, turn=volume[k] < 0 and k == body) for k in members]
        bodies.append(pieces[0] if len(pieces) == 1 else trimesh.util.concatenate(pieces))
    return tuple(bodies) if len(bodies) >= 2 else None


SEARCH_STEPS = 200_000
"""Most blocks tried by :func:`_declared_shells` before it gives up (rule 1 then applies)."""


def _declared_shells(mesh: trimesh.Trimesh, shells: tuple[int, ...]) -> np.ndarray | None:
    """A shell label per face: the mesh's patches (faces joined by vertex index) cut into
    consecutive blocks, one per declared shell (module docstring), or None when the
    patches do not come in one run each, their count is not the faces declared, or no cut
    passes the tests within :data:`SEARCH_STEPS` blocks tried."""
    faces = np.asarray(mesh.faces)
    n_vertices = len(mesh.vertices)
    rows = np.concatenate([faces[:, 0], faces[:, 1]])
    cols = np.concatenate([faces[:, 1], faces[:, 2]])
    graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n_vertices, n_vertices))
    n_patches, vertex_patch = connected_components(graph, directed=False)
    patch = vertex_patch[faces[:, 0]]
    starts = np.r_[True, patch[1:] != patch[:-1]]
    if n_patches != sum(shells) or int(starts.sum()) != n_patches:
        return None
    run = np.cumsum(starts) - 1  # the patch of each face, numbered in face order
    areas = np.asarray(mesh.area_faces)
    vector = np.zeros((n_patches, 3))
    np.add.at(vector, run, np.asarray(mesh.face_normals) * areas[:, None])
    cum_vector = np.vstack([np.zeros(3), np.cumsum(vector, axis=0)])
    cum_area = np.r_[0.0, np.cumsum(np.bincount(run, weights=areas, minlength=n_patches))]
    vertices = np.asarray(mesh.vertices, dtype=float)
    size = float(np.linalg.norm(np.ptp(vertices, axis=0))) or 1.0
    grid = np.round(vertices / (size * 10.0**-MERGE_DIGITS)).astype(np.int64)
    position = np.unique(grid, axis=0, return_inverse=True)[1].reshape(-1)[faces]
    first_face = np.r_[np.flatnonzero(starts), len(faces)]
    tested: dict[tuple[int, int], bool] = {}

    def one_shell(i: int, j: int) -> bool:
        """Patches ``i .. j-1``: closed (rule 2) and connected by positions."""
        if (i, j) not in tested:
            area = cum_area[j] - cum_area[i]
            ok = bool(np.linalg.norm(cum_vector[j] - cum_vector[i]) <= CLOSED_VECTOR_AREA * area)
            if ok:
                block = position[first_face[i] : first_face[j]]
                used, local = np.unique(block, return_inverse=True)
                k = len(block)
                link = coo_matrix(
                    (np.ones(3 * k), (np.repeat(np.arange(k), 3), k + local.reshape(-1))),
                    shape=(k + len(used),) * 2,
                )
                ok = connected_components(link, directed=False)[0] == 1
            tested[(i, j)] = ok
        return tested[(i, j)]

    left: dict[int, int] = {}
    for count in shells:
        left[count] = left.get(count, 0) + 1
    cut: list[int] = []
    steps = [0]

    def search(i: int) -> bool:
        if i == n_patches:
            return True
        for count in sorted(left):
            if not left[count] or i + count > n_patches or steps[0] > SEARCH_STEPS:
                continue
            steps[0] += 1
            if one_shell(i, i + count):
                left[count] -= 1
                cut.append(count)
                if search(i + count):
                    return True
                left[count] += 1
                cut.pop()
        return False

    import sys

    depth = sys.getrecursionlimit()
    sys.setrecursionlimit(max(depth, len(shells) + 100))
    try:
        found = search(0)
    finally:
        sys.setrecursionlimit(depth)
    if not found:
        return None
    block_of_patch = np.repeat(np.arange(len(cut)), cut)
    return block_of_patch[run]


def _pieces(mesh: trimesh.Trimesh) -> np.ndarray:
    """A piece label per face: faces joined where they share a vertex position."""
    vertices = np.asarray(mesh.vertices, dtype=float)
    size = float(np.linalg.norm(np.ptp(vertices, axis=0))) or 1.0
    grid = np.round(vertices / (size * 10.0**-MERGE_DIGITS)).astype(np.int64)
    _, first, position = np.unique(grid, axis=0, return_index=True, return_inverse=True)
    faces = position.reshape(-1)[np.asarray(mesh.faces)]
    n_faces, n_positions = len(faces), int(position.max()) + 1
    rows = np.repeat(np.arange(n_faces), 3)  # face k -- its three positions
    graph = coo_matrix(
        (np.ones(len(rows)), (rows, n_faces + faces.reshape(-1))),
        shape=(n_faces + n_positions,) * 2,
    )
    _, labels = connected_components(graph, directed=False)
    labels = labels[:n_faces]
    shells = _shells(vertices[first], faces, labels)
    _, face_labels = np.unique(shells, return_inverse=True)
    order = np.argsort(np.unique(face_labels, return_index=True)[1])  # first face first
    return np.argsort(order)[face_labels]


def _shells(vertices: np.ndarray, faces: np.ndarray, pieces: np.ndarray) -> np.ndarray:
    """A shell label per face: each piece (``pieces``, faces joined by positions) whose
    edges are all used an even number of times split into its shells (module docstring);
    ``faces`` index positions, ``vertices`` their coordinates by position index."""
    n = len(faces)
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    owner = np.tile(np.arange(n), 3)
    third = np.concatenate([faces[:, 2], faces[:, 0], faces[:, 1]])
    key = np.sort(edges, axis=1)
    _, edge, uses = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    edge = edge.reshape(-1)
    odd = np.zeros(int(pieces.max()) + 1, dtype=bool)
    odd[pieces[owner[uses[edge] % 2 == 1]]] = True  # T-junctions: keep those pieces whole
    rows, cols, rested = [], [], []
    order = np.argsort(edge, kind="stable")
    starts = np.flatnonzero(np.r_[True, edge[order][1:] != edge[order][:-1]])
    for lo, hi in zip(starts, np.r_[starts[1:], len(order)], strict=True):
        ends = order[lo:hi]
        if odd[pieces[owner[ends[0]]]]:
            continue
        if len(ends) == 2:
            rows.append(owner[ends[0]])
            cols.append(owner[ends[1]])
            continue
        pairs, flush = _pairs_around(vertices, edges[ends], third[ends], owner[ends])
        for a, b in pairs:
            rows.append(owner[ends[a]])
            cols.append(owner[ends[b]])
        if flush:
            rested.append(owner[ends])
    keep = np.flatnonzero(odd[pieces])  # whole pieces: joined to their first face
    first = np.unique(pieces, return_index=True)[1]
    rows += keep.tolist()
    cols += first[pieces[keep]].tolist()
    graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))
    shells = connected_components(graph, directed=False)[1]
    return _joined_at_points(faces, shells, [np.unique(shells[f]) for f in rested])


def _joined_at_points(faces: np.ndarray, shells: np.ndarray, rested: list) -> np.ndarray:
    """``shells`` with shells that share a position joined, unless they rest on each other
    (both at an edge where faces lie back to back, ``rested``): bodies touching at a
    point or along an edge only are one solid touching itself."""
    apart = {(int(a), int(b)) for group in rested for a in group for b in group if a != b}
    at = np.column_stack([faces.reshape(-1), np.repeat(shells, 3)])
    at = np.unique(at, axis=0)  # (position, shell) incidences, by position
    same = at[1:, 0] == at[:-1, 0]
    pairs = [
        (int(a), int(b))
        for a, b in zip(at[:-1, 1][same], at[1:, 1][same], strict=True)
        if (int(a), int(b)) not in apart
    ]
    if not pairs:
        return shells
    m = int(shells.max()) + 1
    rows, cols = zip(*pairs, strict=True)
    graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(m, m))
    return connected_components(graph, directed=False)[1][shells]


def _pairs_around(
    vertices: np.ndarray, edges: np.ndarray, third: np.ndarray, index: np.ndarray
) -> tuple[list, bool]:
    """Which faces around one edge of four or more belong together, and whether two of them
    lie back to back: each face (row ``k``:
    its directed edge ``edges[k]`` and third vertex ``third[k]``) along the edge's first
    direction with the face against it that a turn about the edge towards its inside
    meets first (a face lying on it, back to back, is met last); the nearest pairs are
    taken first, each face once; with no two faces back to back (no bodies resting on
    each other: one solid touching itself along the edge) all are joined. Where two faces
    lie on each other the same way round
    (bodies overlapping there) the gaps tie, and the faces nearer in the mesh's order
    (``index``: OCCT writes a shell's faces together) pair first."""
    p, q = vertices[edges[0, 0]], vertices[edges[0, 1]]
    axis = (q - p) / (np.linalg.norm(q - p) or 1.0)
    sense = np.where(edges[:, 0] == edges[0, 0], 1.0, -1.0)  # along the axis or against it
    out = vertices[third] - p
    out -= np.outer(out @ axis, axis)  # from the edge into each face, across the axis
    ref = out[0] / (np.linalg.norm(out[0]) or 1.0)
    angle = np.arctan2(np.cross(ref, out) @ axis, out @ ref)
    along, against = np.flatnonzero(sense > 0), np.flatnonzero(sense < 0)
    # a face's outward normal is (its edge's direction) x (into it): a turn towards the
    # inside of a face along the axis goes to decreasing angle
    gap = np.mod(angle[along][:, None] - angle[against][None, :], 2.0 * np.pi)
    flush = (gap < FLUSH_RADIANS) | (gap > 2.0 * np.pi - FLUSH_RADIANS)
    if not flush.any():  # no two bodies resting on each other: one body meets itself here
        return [(0, k) for k in range(1, len(edges))], False
    gap[flush] = 2.0 * np.pi
    near = np.abs(index[along][:, None] - index[against][None, :])
    tied = np.round(gap / FLUSH_RADIANS)
    pairs, used_a, used_b = [], set(), set()
    for flat in np.lexsort((near.ravel(), tied.ravel())):
        a, b = divmod(int(flat), len(against))
        if a not in used_a and b not in used_b:
            pairs.append((int(along[a]), int(against[b])))
            used_a.add(a)
            used_b.add(b)
    return pairs, True


def _cavity_owners(triangles: np.ndarray, labels: np.ndarray, volume: np.ndarray) -> np.ndarray:
    """The body each piece belongs to: itself, or for a cavity the smallest body around
    its centroid (winding number one; itself when no body is around it: a body written
    inside out)."""
    owner = np.arange(len(volume))
    for k in np.nonzero(volume < 0)[0]:
        inside = triangles[labels == k]
        centre = _centroid(inside)
        around = [
            j
            for j in np.nonzero(volume > 0)[0]
            if _winding_number(triangles[labels == j], centre) > 0.5
        ]
        if around:
            owner[k] = min(around, key=lambda j: volume[j])
    return owner


def _centroid(triangles: np.ndarray) -> np.ndarray:
    """The centroid of the volume a closed surface bounds (either orientation)."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    signed = np.einsum("ij,ij->i", a, np.cross(b, c))
    return (signed[:, None] * (a + b + c)).sum(axis=0) / (4.0 * signed.sum())


def _winding_number(triangles: np.ndarray, point: np.ndarray) -> float:
    """How many times a closed surface winds around ``point`` (1 inside, 0 outside;
    Van Oosterom and Strackee's solid angle of each triangle)."""
    a, b, c = (triangles[:, j] - point for j in range(3))
    la, lb, lc = (np.linalg.norm(v, axis=1) for v in (a, b, c))
    numerator = np.einsum("ij,ij->i", a, np.cross(b, c))
    denominator = (
        la * lb * lc
        + np.einsum("ij,ij->i", a, b) * lc
        + np.einsum("ij,ij->i", b, c) * la
        + np.einsum("ij,ij->i", c, a) * lb
    )
    return float(np.arctan2(numerator, denominator).sum() / (2.0 * np.pi))


def _piece_mesh(mesh: trimesh.Trimesh, labels: np.ndarray, piece: int, turn: bool):
    """The faces of one piece as a mesh of their own (turned inside out when ``turn``)."""
    index = np.nonzero(labels == piece)[0]
    faces = np.asarray(mesh.faces)[index]
    used, local = np.unique(faces, return_inverse=True)
    local = local.reshape(-1, 3)
    return trimesh.Trimesh(np.asarray(mesh.vertices)[used], local[:, ::-1] if turn else local)
