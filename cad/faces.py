"""Per-part triangle data projected along one axis, shared by contact and freedom."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class FaceSet:
    """Triangles of one part that face one sense of an axis, projected along it.

    Attributes
    ----------
    uv : np.ndarray
        Projected vertices, shape ``(m, 3, 2)`` (the two other axes, in order).
    h : np.ndarray
        Vertex heights along the axis, shape ``(m, 3)``.
    box : np.ndarray
        2-D bounds ``[umin, vmin, umax, vmax]``, shape ``(m, 4)``.
    hmin, hmax : np.ndarray
        Height range of each triangle, shape ``(m,)``.
    nk : np.ndarray
        Normal component along the axis, shape ``(m,)``.
    """

    uv: np.ndarray
    h: np.ndarray
    box: np.ndarray
    hmin: np.ndarray
    hmax: np.ndarray
    nk: np.ndarray

    def __len__(self) -> int:
        return len(self.h)

    def take(self, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(uv[idx], h[idx])``."""
        return self.uv[idx], self.h[idx]


def unit_normals(triangles: np.ndarray) -> np.ndarray:
    """Unit normals of triangles ``(m, 3, 3)`` by the right-hand rule; zero if degenerate."""
    n = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return np.where(length > 0, n / np.where(length > 0, length, 1.0), 0.0)


def axis_face_sets(
    triangles: np.ndarray, normals: np.ndarray, axis: int, min_component: float
) -> tuple[FaceSet, FaceSet]:
    """Split triangles into those facing ``+axis`` and ``-axis``.

    Parameters
    ----------
    triangles : np.ndarray
        Shape ``(m, 3, 3)``.
    normals : np.ndarray
        Unit outward normals, shape ``(m, 3)``.
    axis : int
        0, 1 or 2.
    min_component : float
        A triangle faces ``+axis`` if its normal component is ``>= min_component`` and
        ``-axis`` if ``<= -min_component``; the others are ignored.

    Returns
    -------
    (FaceSet, FaceSet)
        Faces towards ``+axis`` and towards ``-axis``.
    """
    others = [(axis + 1) % 3, (axis + 2) % 3]
    uv_all = triangles[:, :, others]
    h_all = triangles[:, :, axis]
    nk_all = normals[:, axis]
    sets = []
    for mask in (nk_all >= min_component, nk_all <= -min_component):
        uv, h = uv_all[mask], h_all[mask]
        box = np.concatenate([uv.min(axis=1), uv.max(axis=1)], axis=1).reshape(-1, 4)
        sets.append(
            FaceSet(
                uv=uv,
                h=h,
                box=box,
                hmin=h.min(axis=1, initial=np.inf),
                hmax=h.max(axis=1, initial=-np.inf),
                nk=nk_all[mask],
            )
        )
    return sets[0], sets[1]


def bounds_overlap(
    a: np.ndarray, b: np.ndarray, pad: float = 0.0, axes: tuple[int, ...] = (0, 1, 2)
) -> bool:
    """Whether bounds ``a`` and ``b`` (each ``(2, 3)``) overlap along ``axes``, padded."""
    ax = list(axes)
    return bool(np.all(a[0, ax] <= b[1, ax] + pad) and np.all(b[0, ax] <= a[1, ax] + pad))
