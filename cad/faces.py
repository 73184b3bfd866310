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

    def subset(self, mask: np.ndarray) -> FaceSet:
        """The faces where ``mask`` is true (``self`` when it is true everywhere)."""
        rows = np.flatnonzero(mask)
        if rows.size == len(self.h):
            return self
        return FaceSet(
            self.uv[rows],
            self.h[rows],
            self.box[rows],
            self.hmin[rows],
            self.hmax[rows],
            self.nk[rows],
        )


def _crop(faces: FaceSet, other: FaceSet, lo: float, hi: float, sign: float) -> FaceSet:
    """Faces of ``faces`` whose box meets ``other``'s 2-D region and height window.

    ``sign`` is +1 when ``faces`` is the front set (heights compared as ``other - faces``)
    and -1 when it is the back set.
    """
    o_lo, o_hi = other.box.min(axis=0)[:2], other.box.max(axis=0)[2:]
    box = faces.box
    keep = (box[:, 0] <= o_hi[0]) & (box[:, 1] <= o_hi[1])
    keep &= (box[:, 2] >= o_lo[0]) & (box[:, 3] >= o_lo[1])
    if sign > 0:
        keep &= (faces.hmax >= other.hmin.min() - hi) & (faces.hmin <= other.hmax.max() - lo)
    else:
        keep &= (faces.hmin <= other.hmax.max() + hi) & (faces.hmax >= other.hmin.min() + lo)
    return faces.subset(keep)


_REFINE_SHARE = 0.25
"""Long triangles are cut until no projected edge exceeds this share of the other set's
region (so that their 2-D boxes hug them)."""
_REFINE_LEVELS = 8
_REFINE_ABOVE = 1 << 21
"""Only pairs of face sets with more candidate pairs than this are refined."""


def refine(
    faces: FaceSet, max_len: float, region: tuple[np.ndarray, np.ndarray] | None = None
) -> FaceSet:
    """Split triangles by longest-edge bisection until projected edges are <= ``max_len``.

    The pieces tile each triangle exactly and heights stay linear, so every test on the
    pieces equals the test on the triangle; only the 2-D boxes get tighter (a long sliver
    of a triangulated cap has a box far larger than itself). With ``region = (lo, hi)``
    (2-D corners), pieces whose box misses it are dropped as they appear.
    """
    if len(faces) == 0 or not np.isfinite(max_len) or max_len <= 0:
        return faces
    uv, h, nk = faces.uv, faces.h, faces.nk
    box = faces.box
    width = np.maximum(box[:, 2] - box[:, 0], box[:, 3] - box[:, 1])
    active = width > max_len  # a triangle's longest edge is at least its box width
    if not active.any():
        return faces
    done = [(uv[~active], h[~active], nk[~active])]
    uv, h, nk = uv[active], h[active], nk[active]
    for level in range(_REFINE_LEVELS + 1):
        d = uv[:, [1, 2, 0]] - uv  # edge k runs k -> k+1
        edge = d[..., 0] ** 2 + d[..., 1] ** 2
        longest = edge.argmax(axis=1)
        split = edge[np.arange(len(uv)), longest] > max_len**2
        if level == _REFINE_LEVELS:
            split[:] = False
        done.append((uv[~split], h[~split], nk[~split]))
        if not split.any():
            break
        rows = np.nonzero(split)[0]
        k = longest[rows]
        i0, i1, i2 = k, (k + 1) % 3, (k + 2) % 3
        a_uv, b_uv, c_uv = uv[rows, i0], uv[rows, i1], uv[rows, i2]
        a_h, b_h, c_h = h[rows, i0], h[rows, i1], h[rows, i2]
        m_uv, m_h = 0.5 * (a_uv + b_uv), 0.5 * (a_h + b_h)
        uv = np.concatenate([np.stack([a_uv, m_uv, c_uv], 1), np.stack([m_uv, b_uv, c_uv], 1)])
        h = np.concatenate([np.stack([a_h, m_h, c_h], 1), np.stack([m_h, b_h, c_h], 1)])
        nk = np.concatenate([nk[rows], nk[rows]])
        if region is not None:
            lo_uv, hi_uv = tri_min(uv), tri_max(uv)
            inside = (
                (lo_uv[:, 0] <= region[1][0])
                & (lo_uv[:, 1] <= region[1][1])
                & (hi_uv[:, 0] >= region[0][0])
                & (hi_uv[:, 1] >= region[0][1])
            )
            uv, h, nk = uv[inside], h[inside], nk[inside]
    uv = np.concatenate([x[0] for x in done])
    h = np.concatenate([x[1] for x in done])
    nk = np.concatenate([x[2] for x in done])
    box = np.concatenate([tri_min(uv), tri_max(uv)], axis=1)
    return FaceSet(uv, h, box, tri_min(h), tri_max(h), nk)


def crop_pair(front: FaceSet, back: FaceSet, lo: float, hi: float) -> tuple[FaceSet, FaceSet]:
    """Drop faces that cannot form a pair with any face of the other set; cut long ones.

    A pair ``(p, q)`` of ``front`` and ``back`` can matter only if their 2-D boxes overlap
    and ``back.hmin[q] - front.hmax[p] <= hi`` and ``back.hmax[q] - front.hmin[p] >= lo``
    (``lo``, ``hi`` may be infinite). Each set is cut to the region the other set spans;
    triangles longer than a quarter of that region are split (:func:`refine`) and cut
    again. All linear in the number of faces, and it removes whole sides of a part far
    from the other part and the long slivers whose boxes would pair with everything.
    """
    for _ in range(2):
        if len(front) == 0 or len(back) == 0:
            break
        front = _crop(front, back, lo, hi, 1.0)
        if len(front) == 0:
            break
        back = _crop(back, front, lo, hi, -1.0)
    if len(front) * len(back) <= _REFINE_ABOVE:
        return front, back
    for faces_is_front in (True, False):
        faces, other = (front, back) if faces_is_front else (back, front)
        region = (other.box[:, :2].min(axis=0), other.box[:, 2:].max(axis=0))
        extent = float(np.max(region[1] - region[0]))
        faces = refine(faces, _REFINE_SHARE * extent, region)
        faces = _crop(faces, other, lo, hi, 1.0 if faces_is_front else -1.0)
        if faces_is_front:
            front = faces
        else:
            back = faces
        if len(faces) == 0:
            break
    return front, back


def tri_min(x: np.ndarray) -> np.ndarray:
    """Minimum over the three vertices (axis 1), faster than ``x.min(axis=1)``."""
    return np.minimum(np.minimum(x[:, 0], x[:, 1]), x[:, 2])


def tri_max(x: np.ndarray) -> np.ndarray:
    """Maximum over the three vertices (axis 1)."""
    return np.maximum(np.maximum(x[:, 0], x[:, 1]), x[:, 2])


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
        box = np.concatenate([tri_min(uv), tri_max(uv)], axis=1).reshape(-1, 4)
        sets.append(
            FaceSet(
                uv=uv,
                h=h,
                box=box,
                hmin=tri_min(h),
                hmax=tri_max(h),
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
