"""Exact 2-D kernels behind contact and freedom along an axis.

For an axis ``k`` every triangle is projected onto the plane of the two other axes
(coordinates ``u, v``) and keeps its height ``h`` (coordinate ``k``) at each vertex. For a
pair of triangles ``p, q`` the height difference ``h_q - h_p`` is an affine function on the
common part of their projections, a convex polygon, so its range there is spanned by the
polygon's corners: vertices of one triangle inside the other and crossings of their edges.
:func:`height_gap_range` evaluates exactly those (at most 15) points, vectorised over many
pairs. :func:`box_pair_chunks` is the broad phase: pairs of overlapping 2-D boxes, by
brute force in row blocks (cheap for the few thousand faces of a part, and it lets the
caller stop early) or, for very large sets, with a uniform grid (:func:`box_pairs`).
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

_BLOCK = 1 << 20
"""Box comparisons per brute-force block."""
_GRID_ABOVE = 1 << 25
"""Use the grid when a full comparison matrix would exceed this many entries."""
_EPS = 1e-9
"""Relative slack of the inside / on-edge tests (closed triangles)."""


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _barycentric(tri: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Barycentric coordinates of ``pts`` (N, m, 2) in triangles ``tri`` (N, 3, 2)."""
    origin = tri[:, 0, :]
    e1 = tri[:, 1, :] - origin
    e2 = tri[:, 2, :] - origin
    det = _cross(e1, e2)
    det = np.where(np.abs(det) > 0.0, det, np.inf)
    w = pts - origin[:, None, :]
    l1 = _cross(w, e2[:, None, :]) / det[:, None]
    l2 = _cross(e1[:, None, :], w) / det[:, None]
    return np.stack([1.0 - l1 - l2, l1, l2], axis=-1)


def height_gap_range(
    p_uv: np.ndarray, p_h: np.ndarray, q_uv: np.ndarray, q_h: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Range of ``h_q - h_p`` over the overlap of the projections of triangle pairs.

    Parameters
    ----------
    p_uv, q_uv : np.ndarray
        Projected triangles, shape ``(N, 3, 2)`` each (pair ``n`` is ``p_uv[n], q_uv[n]``).
    p_h, q_h : np.ndarray
        Heights of their vertices along the projection axis, shape ``(N, 3)``.

    Returns
    -------
    overlap : np.ndarray
        Bool, shape ``(N,)``: the closed projections share a point.
    gap_min, gap_max : np.ndarray
        Float, shape ``(N,)``: minimum and maximum of ``h_q - h_p`` over the shared
        region (``+inf`` / ``-inf`` where ``overlap`` is false).
    """
    n = len(p_uv)
    if n == 0:
        empty = np.zeros(0)
        return np.zeros(0, dtype=bool), empty, empty
    values, valid = [], []
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        # vertices of p inside q
        lam = _barycentric(q_uv, p_uv)
        valid.append(np.all(lam >= -_EPS, axis=-1))
        values.append(np.einsum("nmk,nk->nm", lam, q_h) - p_h)
        # vertices of q inside p
        lam = _barycentric(p_uv, q_uv)
        valid.append(np.all(lam >= -_EPS, axis=-1))
        values.append(q_h - np.einsum("nmk,nk->nm", lam, p_h))
        # crossings of an edge of p with an edge of q
        nxt = [1, 2, 0]
        ps, pe = p_uv[:, :, None, :], p_uv[:, nxt, None, :]
        qs, qe = q_uv[:, None, :, :], q_uv[:, None, nxt, :]
        r, e, w = pe - ps, qe - qs, qs - ps
        denom = _cross(r, e)
        scale = np.linalg.norm(r, axis=-1) * np.linalg.norm(e, axis=-1)
        ok = np.abs(denom) > 1e-12 * scale
        denom = np.where(ok, denom, 1.0)
        s = _cross(w, e) / denom
        t = _cross(w, r) / denom
        ok &= (s >= -_EPS) & (s <= 1 + _EPS) & (t >= -_EPS) & (t <= 1 + _EPS)
        s, t = np.clip(s, 0.0, 1.0), np.clip(t, 0.0, 1.0)
        ph_s, ph_e = p_h[:, :, None], p_h[:, nxt, None]
        qh_s, qh_e = q_h[:, None, :], q_h[:, None, nxt]
        gap = (qh_s + t * (qh_e - qh_s)) - (ph_s + s * (ph_e - ph_s))
        valid.append(ok.reshape(n, 9))
        values.append(gap.reshape(n, 9))
    valid_all = np.concatenate(valid, axis=1)
    value_all = np.concatenate(values, axis=1)
    valid_all &= np.isfinite(value_all)
    overlap = valid_all.any(axis=1)
    gap_min = np.where(valid_all, value_all, np.inf).min(axis=1)
    gap_max = np.where(valid_all, value_all, -np.inf).max(axis=1)
    return overlap, gap_min, gap_max


def box_pairs(a: np.ndarray, b: np.ndarray, max_cells: int = 256) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs of overlapping closed 2-D boxes.

    Parameters
    ----------
    a, b : np.ndarray
        Boxes ``[umin, vmin, umax, vmax]``, shapes ``(Na, 4)`` and ``(Nb, 4)``.
    max_cells : int
        The grid has at most this many cells along each side.

    Returns
    -------
    ia, ib : np.ndarray
        Int arrays of equal length: ``a[ia[k]]`` overlaps ``b[ib[k]]``; each pair once.
    """
    none = np.zeros(0, dtype=np.int64)
    if len(a) == 0 or len(b) == 0:
        return none, none
    lo = np.minimum(a[:, :2].min(axis=0), b[:, :2].min(axis=0))
    hi = np.maximum(a[:, 2:].max(axis=0), b[:, 2:].max(axis=0))
    sizes = np.concatenate([a[:, 2:] - a[:, :2], b[:, 2:] - b[:, :2]])
    cell = max(float(np.median(sizes.max(axis=1))), float((hi - lo).max()) / max_cells, 1e-12)
    width = int(np.floor((hi[0] - lo[0]) / cell)) + 1

    def cells(boxes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        c0 = np.floor((boxes[:, :2] - lo) / cell).astype(np.int64)
        c1 = np.floor((boxes[:, 2:] - lo) / cell).astype(np.int64)
        span = c1 - c0 + 1
        count = span[:, 0] * span[:, 1]
        idx = np.repeat(np.arange(len(boxes)), count)
        k = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
        nx = np.repeat(span[:, 0], count)
        cx = np.repeat(c0[:, 0], count) + k % nx
        cy = np.repeat(c0[:, 1], count) + k // nx
        return idx, cx + width * cy, c0

    ia, akey, a0 = cells(a)
    ib, bkey, b0 = cells(b)
    order = np.argsort(bkey, kind="stable")
    bkey, ib = bkey[order], ib[order]
    left = np.searchsorted(bkey, akey, "left")
    count = np.searchsorted(bkey, akey, "right") - left
    total = int(count.sum())
    if total == 0:
        return none, none
    pa = np.repeat(ia, count)
    key = np.repeat(akey, count)
    pos = np.repeat(left, count) + np.arange(total) - np.repeat(np.cumsum(count) - count, count)
    pb = ib[pos]
    # keep each pair only in the first cell both boxes cover (no duplicates)
    ref = np.maximum(a0[pa], b0[pb])
    keep = key == ref[:, 0] + width * ref[:, 1]
    pa, pb = pa[keep], pb[keep]
    hit = (
        (a[pa, 0] <= b[pb, 2])
        & (b[pb, 0] <= a[pa, 2])
        & (a[pa, 1] <= b[pb, 3])
        & (b[pb, 1] <= a[pa, 3])
    )
    return pa[hit], pb[hit]


def box_pair_chunks(a: np.ndarray, b: np.ndarray) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Yield blocks ``(ia, ib)`` of overlapping 2-D boxes; together, every pair once.

    Parameters
    ----------
    a, b : np.ndarray
        Boxes ``[umin, vmin, umax, vmax]``, shapes ``(Na, 4)`` and ``(Nb, 4)``.

    Yields
    ------
    ia, ib : np.ndarray
        Int arrays of equal length: ``a[ia[k]]`` overlaps ``b[ib[k]]``.
    """
    if len(a) == 0 or len(b) == 0:
        return
    if len(a) * len(b) > _GRID_ABOVE:
        yield box_pairs(a, b)
        return
    rows = max(1, _BLOCK // len(b))
    for start in range(0, len(a), rows):
        block = a[start : start + rows]
        hit = (
            (block[:, None, 0] <= b[None, :, 2])
            & (b[None, :, 0] <= block[:, None, 2])
            & (block[:, None, 1] <= b[None, :, 3])
            & (b[None, :, 1] <= block[:, None, 3])
        )
        ia, ib = np.nonzero(hit)
        if len(ia):
            yield ia + start, ib
