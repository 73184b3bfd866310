"""Offset a triangle mesh: move every face plane along its normal by a distance.

Used with a negative distance to *erode* parts by half the penetration tolerance before
the exact sweep test (see :mod:`cad.freedom`). Each vertex is displaced by the vector
``v`` that best satisfies ``v . n_f = distance`` for its incident faces ``f`` (weighted
by the face angle at the vertex, least squares with small eigenvalues dropped). At a
vertex of up to three distinct planes this is the exact intersection of the offset planes
(a cube corner moves by ``distance * (1, 1, 1)``); on a flat or smoothly tessellated
surface it is the offset along the normal. The result is exact for convex polyhedra and
accurate to a fraction of ``distance`` at concave edges, which is all a tolerance needs.
"""

from __future__ import annotations

import numpy as np
import trimesh

_EIGEN_FLOOR = 1e-2
"""Eigenvalues below this share of the largest are dropped (nearly parallel planes)."""
_MAX_STRETCH = 2.0
"""A vertex moves by at most this multiple of ``|distance|`` (sharp spikes)."""


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
    eigval, eigvec = np.linalg.eigh(gram)
    keep = eigval > _EIGEN_FLOOR * eigval[:, -1:]
    proj = np.einsum("nij,ni->nj", eigvec, rhs)
    coeff = np.where(keep, proj / np.where(keep, eigval, 1.0), 0.0)
    disp = np.einsum("nij,nj->ni", eigvec, coeff) * distance
    norm = np.linalg.norm(disp, axis=1)
    limit = _MAX_STRETCH * abs(distance)
    scale = np.where(norm > limit, limit / np.maximum(norm, 1e-300), 1.0)
    return vertices + disp * scale[:, None]


def offset_mesh(mesh: trimesh.Trimesh, distance: float) -> trimesh.Trimesh:
    """A copy of ``mesh`` offset by ``distance`` (see :func:`offset_vertices`)."""
    return trimesh.Trimesh(
        vertices=offset_vertices(mesh, distance), faces=np.asarray(mesh.faces), process=False
    )
