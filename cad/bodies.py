"""The closed bodies of one mesh: a part that is several solids, split into one per body.

A CAD export sometimes fuses a whole product into one solid (FreeCAD's "toy truck" of the
APLAN benchmark: one STEP solid of 61 shells) or one STL/GLB mesh. :func:`closed_bodies`
finds the separate bodies of such a mesh; :mod:`cad.scene` makes each a part.

The rule, in this order:

1. Faces are joined where they share a vertex position (coordinates equal to within
   :data:`MERGE_DIGITS` significant digits of the mesh's size). OCCT tessellates each
   B-rep face on its own: faces of one shell share their corner positions but not their
   edges (T-junctions), so joining by shared edges would cut a solid into its faces (the
   toy truck's solid became 542 pieces), while joining by positions keeps each shell whole.
2. Each piece must be a closed surface: its vector area (the sum of the face normals
   times the face areas) is zero for a closed surface whatever its tessellation, and
   equals the area of the hole for an open one. A piece is closed when the vector area is
   at most :data:`CLOSED_VECTOR_AREA` of its area. One open piece: the mesh is not split
   (it is a visual mesh, not solids).
3. A closed piece of negative volume (inward normals) is the cavity of the smallest body
   around its centroid (winding number one), and joins it; with no body around it, it is
   a body written inside out (the toy truck's mixer drum), and is turned.

Bodies come in the order of their first face in the mesh.
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


def closed_bodies(mesh: trimesh.Trimesh) -> tuple[trimesh.Trimesh, ...] | None:
    """The closed bodies of ``mesh`` when it holds two or more, else None.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        One part's mesh, in any unit and frame.

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
    labels = _pieces(mesh)
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


def _pieces(mesh: trimesh.Trimesh) -> np.ndarray:
    """A piece label per face: faces joined where they share a vertex position."""
    vertices = np.asarray(mesh.vertices, dtype=float)
    size = float(np.linalg.norm(np.ptp(vertices, axis=0))) or 1.0
    grid = np.round(vertices / (size * 10.0**-MERGE_DIGITS)).astype(np.int64)
    _, position = np.unique(grid, axis=0, return_inverse=True)
    faces = position.reshape(-1)[np.asarray(mesh.faces)]
    n_faces, n_positions = len(faces), int(position.max()) + 1
    rows = np.repeat(np.arange(n_faces), 3)  # face k -- its three positions
    graph = coo_matrix(
        (np.ones(len(rows)), (rows, n_faces + faces.reshape(-1))),
        shape=(n_faces + n_positions,) * 2,
    )
    _, labels = connected_components(graph, directed=False)
    _, face_labels = np.unique(labels[:n_faces], return_inverse=True)  # first face first
    order = np.argsort(np.unique(face_labels, return_index=True)[1])
    return np.argsort(order)[face_labels]


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
