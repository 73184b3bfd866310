"""Offset a triangle mesh: move every face plane along its normal by a distance.

Used with a negative distance to *erode* parts by half the penetration tolerance before
the exact sweep test (see :mod:`cad.freedom`). Each vertex is displaced by the vector
``v`` that best satisfies ``v . n_f = distance`` for its incident faces ``f`` (weighted
by the face angle at the vertex, least squares with small eigenvalues dropped). At a
vertex of up to three distinct planes this is the exact intersection of the offset planes
(a cube corner moves by ``distance * (1, 1, 1)``); on a flat or smoothly tessellated
surface it is the offset along the normal. The result is exact for convex polyhedra and
accurate to a fraction of ``distance`` at concave edges, which is all a tolerance needs.

An open mesh (a STEP tessellation with faces missing) has *free edges*, edges of one
face only. The face that should meet a free edge is taken as perpendicular to the surface
there: each free edge adds the plane through it whose normal lies in its face and points
away from the face. So an open sheet is eroded from its free edges too, not only along its
normals; without this, two parts whose coplanar side walls touch along a free edge (two
identical slotted disc springs stacked on each other) touch at every erosion.
"""

from __future__ import annotations

import numpy as np
import trimesh

_EIGEN_FLOOR = 1e-2
"""Eigenvalues below this share of the largest are dropped (nearly parallel planes)."""
_MAX_STRETCH = 2.0
"""A vertex moves by at most this multiple of ``|distance|`` (sharp spikes); a vertex on a
free edge by at most ``FREE_EDGE_PULL`` times more."""
FREE_EDGE_PULL = 2.0
"""A free edge is moved back in its face by this multiple of ``|distance|``: the face
missing there cannot be eroded, so the edge retreats for it as well (two open parts whose
faces meet where one of them has a face missing are then parted by the erosion too)."""


def offset_vertices(mesh: trimesh.Trimesh, distance: float) -> np.ndarray:
    """Vertices of ``mesh`` with every face plane moved by ``distance`` along its normal.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        Mesh with outward normals, ``V`` vertices and ``F`` faces.
    distance : float
        Offset; negative moves faces inwards (erosion).

    Returns
    -------
    np.ndarray
        Offset vertex positions, shape ``(V, 3)``; faces are unchanged.
    """
    vertices = np.asarray(mesh.vertices, dtype=float)
    if distance == 0.0 or len(mesh.faces) == 0:
        return vertices.copy()
    faces = np.asarray(mesh.faces)
    normals = np.asarray(mesh.face_normals, dtype=float)
    angles = np.nan_to_num(np.asarray(mesh.face_angles, dtype=float))
    outer = normals[:, :, None] * normals[:, None, :]
    gram = np.zeros((len(vertices), 3, 3))
    rhs = np.zeros((len(vertices), 3))
    for corner in range(3):
        weight = angles[:, corner]
        np.add.at(gram, faces[:, corner], weight[:, None, None] * outer)
        np.add.at(rhs, faces[:, corner], weight[:, None] * normals)
    ends, away = free_edge_planes(mesh)
    for end in range(2):  # the missing side of a free edge spans half a turn at each end
        np.add.at(gram, ends[:, end], (np.pi / 2) * away[:, :, None] * away[:, None, :])
        np.add.at(rhs, ends[:, end], (np.pi / 2) * FREE_EDGE_PULL * away)
    eigval, eigvec = np.linalg.eigh(gram)
    keep = eigval > _EIGEN_FLOOR * eigval[:, -1:]
    proj = np.einsum("nij,ni->nj", eigvec, rhs)
    coeff = np.where(keep, proj / np.where(keep, eigval, 1.0), 0.0)
    disp = np.einsum("nij,nj->ni", eigvec, coeff) * distance
    norm = np.linalg.norm(disp, axis=1)
    limit = np.full(len(vertices), _MAX_STRETCH * abs(distance))
    limit[ends.ravel()] *= FREE_EDGE_PULL
    scale = np.where(norm > limit, limit / np.maximum(norm, 1e-300), 1.0)
    return vertices + disp * scale[:, None]


def free_edge_planes(mesh: trimesh.Trimesh) -> tuple[np.ndarray, np.ndarray]:
    """Free edges of ``mesh`` (edges of one face only) and the outward normals of the
    planes standing on them at right angles to their faces.

    Returns
    -------
    ends : np.ndarray
        Vertex indices of each free edge, shape ``(E, 2)``.
    away : np.ndarray
        Unit vector in the edge's face, perpendicular to the edge and pointing away from
        the face, shape ``(E, 3)``.
    """
    counts = np.bincount(mesh.edges_unique_inverse, minlength=len(mesh.edges_unique))
    free = counts[mesh.edges_unique_inverse] == 1
    ends = np.asarray(mesh.edges)[free]
    faces = np.asarray(mesh.edges_face)[free]
    vertices = np.asarray(mesh.vertices, dtype=float)
    start, stop = vertices[ends[:, 0]], vertices[ends[:, 1]]
    away = np.cross(stop - start, np.asarray(mesh.face_normals, dtype=float)[faces])
    outside = 0.5 * (start + stop) - np.asarray(mesh.triangles_center)[faces]
    away *= np.where(np.einsum("ij,ij->i", away, outside) < 0, -1.0, 1.0)[:, None]
    length = np.linalg.norm(away, axis=1)
    keep = length > 0
    return ends[keep], away[keep] / length[keep, None]


def offset_mesh(mesh: trimesh.Trimesh, distance: float) -> trimesh.Trimesh:
    """A copy of ``mesh`` offset by ``distance`` (see :func:`offset_vertices`)."""
    return trimesh.Trimesh(
        vertices=offset_vertices(mesh, distance), faces=np.asarray(mesh.faces), process=False
    )
