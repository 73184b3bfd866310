"""Exact 2-D kernels behind contact and freedom along an axis.

For an axis ``k`` every triangle is projected onto the plane of the two other axes
(coordinates ``u, v``) and keeps its height ``h`` (coordinate ``k``) at each vertex. For a
pair of triangles ``p, q`` the height difference ``h_q - h_p`` is an affine function on the
common part of their projections, a convex polygon, so its range there is spanned by the
polygon's corners: vertices of one triangle inside the other and crossings of their edges.
:func:`height_gap_range` evaluates exactly those (at most 15) points, vectorised over many
pairs. :func:`box_pair_chunks` is the broad phase: pairs of overlapping 2-D boxes, by
brute force in row blocks (cheap for the few thousand faces of a part) or, for large
sets, with a uniform grid of per-axis cell sizes whose long boxes are compared apart
(:func:`grid_pair_chunks`, about linear); both yield blocks so the caller can stop early.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

_BLOCK = 1 << 18
"""Box comparisons per brute-force block."""
_GRID_ABOVE = 1 << 22
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


def _inside(lam: np.ndarray) -> np.ndarray:
    """(N, m) bool: every barycentric coordinate of ``lam`` (N, m, 3) at least ``-_EPS``."""
    return (lam[..., 0] >= -_EPS) & (lam[..., 1] >= -_EPS) & (lam[..., 2] >= -_EPS)


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
        valid.append(_inside(lam))
        values.append(np.einsum("nmk,nk->nm", lam, q_h) - p_h)
        # vertices of q inside p
        lam = _barycentric(p_uv, q_uv)
        valid.append(_inside(lam))
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


def _brute_blocks(
    a: np.ndarray, b: np.ndarray, ia_map: np.ndarray | None = None, ib_map: np.ndarray | None = None
) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Overlapping pairs by comparing every box of ``a`` with every box of ``b``, in rows."""
    if len(a) == 0 or len(b) == 0:
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
            ia = ia + start
            yield (
                ia if ia_map is None else ia_map[ia],
                ib if ib_map is None else ib_map[ib],
            )


class _Grid:
    """Uniform grid over 2-D boxes with one cell size per axis (thin strips stay cheap).

    Cells are about the median box size along each axis (at most ``max_cells`` per side).
    Boxes covering more than :data:`_BIG_SPAN` cells are kept out of the grid and compared
    by brute force (:meth:`pairs` handles both).
    """

    def __init__(self, a: np.ndarray, b: np.ndarray, max_cells: int) -> None:
        self.lo = np.minimum(a[:, :2].min(axis=0), b[:, :2].min(axis=0))
        hi = np.maximum(a[:, 2:].max(axis=0), b[:, 2:].max(axis=0))
        sizes = np.concatenate([a[:, 2:] - a[:, :2], b[:, 2:] - b[:, :2]])
        extent = np.maximum(hi - self.lo, 1e-12)
        self.cell = np.maximum(np.median(sizes, axis=0), extent / max_cells)
        self.cell = np.maximum(self.cell, extent * 1e-9)
        self.width = int(np.floor(extent[0] / self.cell[0])) + 2

    def cells(self, boxes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        c0 = np.floor((boxes[:, :2] - self.lo) / self.cell).astype(np.int64)
        c1 = np.floor((boxes[:, 2:] - self.lo) / self.cell).astype(np.int64)
        return c0, c1 - c0 + 1

    def keys(self, c0: np.ndarray, span: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(box index, cell key)`` for every cell each box covers."""
        count = span[:, 0] * span[:, 1]
        idx = np.repeat(np.arange(len(c0)), count)
        k = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
        nx = np.repeat(span[:, 0], count)
        cx = np.repeat(c0[:, 0], count) + k % nx
        cy = np.repeat(c0[:, 1], count) + k // nx
        return idx, cx + self.width * cy


_BIG_SPAN = 64
"""Boxes covering more grid cells than this are compared by brute force instead."""
_CANDIDATES = 1 << 18
"""Candidate pairs per yielded grid block (bounds memory; lets callers stop early)."""


def overlap_share(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Area of the intersection of boxes ``a[k]`` and ``b[k]`` over the smaller box's area.

    1 when one box holds the other, near 0 when two long slivers merely cross corners:
    a cheap likelihood that the triangles inside really overlap (used to test likely
    pairs first so that a search for one hit stops early).
    """
    w = np.minimum(a[:, 2:], b[:, 2:]) - np.maximum(a[:, :2], b[:, :2])
    inter = np.prod(np.maximum(w, 0.0), axis=1)
    area_a = np.prod(a[:, 2:] - a[:, :2], axis=1)
    area_b = np.prod(b[:, 2:] - b[:, :2], axis=1)
    return inter / np.maximum(np.minimum(area_a, area_b), 1e-300)


def box_pairs(a: np.ndarray, b: np.ndarray, max_cells: int = 256) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs of overlapping closed 2-D boxes (all at once; see :func:`grid_pair_chunks`).

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
    blocks = list(grid_pair_chunks(a, b, max_cells))
    if not blocks:
        none = np.zeros(0, dtype=np.int64)
        return none, none
    return np.concatenate([x for x, _ in blocks]), np.concatenate([y for _, y in blocks])


def grid_pair_chunks(
    a: np.ndarray, b: np.ndarray, max_cells: int = 256
) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Blocks of overlapping box pairs found with a uniform grid; every pair once.

    Work is about linear in the number of boxes and of overlapping pairs: boxes of
    ordinary size go into a grid of per-axis cell sizes, the few that span many cells
    (long slivers of a triangulated cap) are compared with every box of the other set.
    """
    if len(a) == 0 or len(b) == 0:
        return
    grid = _Grid(a, b, max_cells)
    a0, aspan = grid.cells(a)
    b0, bspan = grid.cells(b)
    a_big = aspan[:, 0] * aspan[:, 1] > _BIG_SPAN
    b_big = bspan[:, 0] * bspan[:, 1] > _BIG_SPAN
    ia_big, ib_big = np.nonzero(a_big)[0], np.nonzero(b_big)[0]
    ia_small, ib_small = np.nonzero(~a_big)[0], np.nonzero(~b_big)[0]
    # big boxes of a against all of b, small boxes of a against big boxes of b
    yield from _brute_blocks(a[ia_big], b, ia_big, None)
    yield from _brute_blocks(a[ia_small], b[ib_big], ia_small, ib_big)
    if len(ia_small) == 0 or len(ib_small) == 0:
        return
    # small against small through the grid
    ib_idx, bkey = grid.keys(b0[ib_small], bspan[ib_small])
    order = np.argsort(bkey, kind="stable")
    bkey, ib_cell = bkey[order], ib_small[ib_idx[order]]
    ia_idx, akey = grid.keys(a0[ia_small], aspan[ia_small])
    left = np.searchsorted(bkey, akey, "left")
    count = np.searchsorted(bkey, akey, "right") - left
    ends = np.cumsum(count)
    # split the (a cell entry, b box) candidates into blocks of about _CANDIDATES
    cuts = np.searchsorted(ends, np.arange(_CANDIDATES, int(ends[-1]), _CANDIDATES), "left")
    bounds = [0, *(int(c) + 1 for c in cuts), len(akey)]
    for lo, hi in zip(bounds[:-1], bounds[1:], strict=True):
        if hi <= lo:
            continue
        cnt = count[lo:hi]
        total = int(cnt.sum())
        if total == 0:
            continue
        pa = ia_small[np.repeat(ia_idx[lo:hi], cnt)]
        key = np.repeat(akey[lo:hi], cnt)
        pos = np.repeat(left[lo:hi], cnt) + np.arange(total) - np.repeat(np.cumsum(cnt) - cnt, cnt)
        pb = ib_cell[pos]
        # keep each pair only in the first cell both boxes cover (no duplicates)
        ref = np.maximum(a0[pa], b0[pb])
        keep = key == ref[:, 0] + grid.width * ref[:, 1]
        pa, pb = pa[keep], pb[keep]
        hit = (
            (a[pa, 0] <= b[pb, 2])
            & (b[pb, 0] <= a[pa, 2])
            & (a[pa, 1] <= b[pb, 3])
            & (b[pb, 1] <= a[pa, 3])
        )
        if np.any(hit):
            yield pa[hit], pb[hit]


def box_pair_chunks(a: np.ndarray, b: np.ndarray) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Yield blocks ``(ia, ib)`` of overlapping 2-D boxes; together, every pair once.

    Brute force in row blocks while the full comparison is small, else the grid of
    :func:`grid_pair_chunks`; either way the caller can stop after any block.

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
        yield from grid_pair_chunks(a, b)
    else:
        yield from _brute_blocks(a, b)
