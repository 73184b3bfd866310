"""Short cuts for the CP-SAT replay loop, read off the state graph.

When a schedule places operation ``b`` right after the done set ``I`` and the state graph
has no such step, the general cut of :func:`asp.schedule.replay.schedule_violation` ("some
operation outside ``I`` precedes one of ``I + {b}``") has about ``|I| x (n - |I|)``
literals. :class:`PlacementCuts` finds a shorter one that holds for every feasible schedule,
from ``B``, the done sets of the co-reachable states with a step ``b`` into a co-reachable
state.

The cut ``(Y, X)``, with ``Y`` outside ``I + {b}`` and ``X`` inside ``I``, holds when no set
``S`` of ``B`` misses all of ``Y`` and contains all of ``X``. Then every feasible schedule
(positive durations) has one of the precedences

- ``y -> x`` for ``y`` in ``Y`` and ``x`` in ``X + {b}``, or
- ``b -> x`` for ``x`` in ``X``.

Proof: if none holds, let ``S`` be the operations that end by the time ``b`` starts, and
every operation that ends by the start of one of ``X``, transitively, and ``X`` itself.
Every ``x`` starts before ``b`` ends, so ``S`` then ``b`` then the rest is an order of
placement consistent with the schedule; the replay makes it a path of the state graph, so
``S`` is in ``B``. No ``y`` ends by the start of ``b`` or of an ``x``, so ``S`` misses ``Y``;
and ``S`` contains ``X``: a contradiction.

With ``X`` empty this is "``b`` needs one of ``Y`` first" (``|Y|`` literals); with ``Y``
empty "``b`` comes before one of ``X``" (``|X|`` literals). ``Y`` all of the outside and
``X = I`` always hold (only ``S = I`` could break it, and ``b`` cannot follow ``I``) unless
``I`` is in ``B`` with other tool values; each is then shrunk greedily (an operation is
dropped while the cut still holds), once dropping from ``X`` first and once from ``Y``
first, and the cut with fewer literals is kept: it names a few operations, the supports
a part waits for or the parts that would block it.

``B`` can hold millions of sets on a large state graph. The shrinking runs on a sample of
them and the result is checked against all; sets that break it join the sample and the
shrinking starts again (a few rounds at most), so a cut costs a few passes over ``B``.

On a graph whose alike operations are in a fixed order (:mod:`asp.graph.fixed_order`), ``B``
holds the sorted states only: the cut is found for the sorted done set and stated again
with counts per position (:meth:`asp.graph.fixed_order.FixedOrder.actual`), so that it holds for
every state of an orbit.
"""

from __future__ import annotations

import bisect
import time

import numba
import numpy as np

from asp.graph.feasibility import WORD_BITS
from asp.graph.together import LiveSteps

SAMPLE = 4096
"""Sets of ``B`` the shrinking starts from (evenly spaced)."""
ADD = 256
"""Most sets that break a shrunk cut added to the sample per round."""
EARLY_S = 0.5
"""Seconds :meth:`PlacementCuts.early` spends on one schedule at most."""
CACHE_ROWS = 8_000_000
"""Most done sets (rows of ``B``) kept between cuts, over all operations (16 bytes each
with two words)."""


class PlacementCuts:
    """Short cuts for ``b`` after a done set (module docstring).

    Parameters
    ----------
    graph : StateGraph
    steps : LiveSteps, optional
        The graph's live transitions (built when not given).
    combined : bool
        Whether cuts with both ``Y`` and ``X`` are allowed (their proof needs every
        operation to take time); else only ``X`` or ``Y`` empty.
    fixed : asp.graph.fixed_order.FixedOrder, optional
        The graph's fixed order of alike operations, undone (``steps`` then has its labels).
    """

    def __init__(self, graph, steps: LiveSteps | None = None, *, combined: bool = True, fixed=None):
        self.graph = graph
        self.combined = combined
        self.fixed = fixed
        label = None if fixed is None else fixed.label
        self.steps = LiveSteps(graph, label=label) if steps is None else steps
        self.n = graph.model.n_ops
        keys = np.asarray(graph.keys, dtype=np.uint64)
        self.width = 1 if keys.ndim == 1 else int(keys.shape[1])
        bits = np.asarray(graph.model.op_bits, dtype=np.uint64).reshape(self.n, -1)
        self.done_bits = np.bitwise_or.reduce(bits, axis=0)
        self._rows: dict[int, np.ndarray] = {}

    def rows(self, b: int) -> np.ndarray:
        """(k, W) uint64: the done words of the sets ``B`` of operation ``b`` (of its label:
        the states with a step of its chain)."""
        b = self.steps.key(b)
        hit = self._rows.get(b)
        if hit is not None:
            return hit
        edges = np.flatnonzero(self.steps.op == b)
        states = np.searchsorted(self.steps.indptr, edges, side="right") - 1
        keys = np.asarray(self.graph.keys[states], dtype=np.uint64).reshape(-1, self.width)
        rows = np.ascontiguousarray(keys & self.done_bits)
        while self._rows and sum(r.shape[0] for r in self._rows.values()) + len(rows) > (
            CACHE_ROWS
        ):
            self._rows.pop(next(iter(self._rows)))
        self._rows[b] = rows
        return rows

    def mask(self, ops) -> np.ndarray:
        """(W,) uint64 bit mask of the operations ``ops``."""
        out = np.zeros(self.width, dtype=np.uint64)
        for o in ops:
            w, k = divmod(int(o), WORD_BITS)
            out[w] |= np.uint64(1) << np.uint64(k)
        return out

    def sets(self, done: set[int], b: int) -> tuple[list[int], list[int]] | None:
        """The shrunk ``(Y, X)`` for ``b`` after ``done`` with the fewest literals, or None
        when even the full sets do not hold (module docstring)."""
        if self.fixed is not None:
            sorted_done, sorted_b = self.fixed.canonical(done, b)
            found = self._sets(sorted_done, sorted_b)
            return None if found is None else self.fixed.actual(*found, done, b)
        return self._sets(done, b)

    def _sets(self, done: set[int], b: int) -> tuple[list[int], list[int]] | None:
        rows = self.rows(b)
        ys = np.array([y for y in range(self.n) if y not in done and y != b], dtype=np.int64)
        xs = np.array(sorted(done), dtype=np.int64)
        if _first_breaking(rows, self.mask(ys), self.mask(xs)) >= 0:
            return None
        found = []
        for x_first in (True, False):
            y, x = self._shrink(rows, ys, xs, x_first)
            if self.combined or not (y and x):
                found.append((len(y) * (len(x) + 1) + len(x), y, x))
        if not found:
            return None
        _, y, x = min(found, key=lambda f: f[0])
        return y, x

    def cut(self, done: set[int], b: int) -> list[tuple[int, int]] | None:
        """The precedences ``(before, after)`` of the short cut, one of which every feasible
        schedule has, or None (module docstring)."""
        found = self.sets(done, b)
        if found is None:
            return None
        ys, xs = found
        return [(y, x) for x in [b, *xs] for y in ys] + [(b, x) for x in xs]

    def early(
        self, start: list[float], end: list[float], seconds: float = EARLY_S
    ) -> list[list[tuple[int, int]]]:
        """Cuts for the operations a schedule starts too early.

        Every feasible schedule may place ``b`` right after the operations that end by the
        time it starts (``D``, a prefix of the operations in order of their ends), so ``D``
        is in ``B``. The state of each prefix is found by one walk along that order; for
        each ``b`` whose ``D`` is a state without a step ``b``, the short cut for ``b``
        after ``D``. Stops after ``seconds`` (reading the done sets ``B`` of an operation
        is the cost; they are kept for the next call).

        Parameters
        ----------
        start, end : list of float, [n_ops]
            The schedule.
        """
        t0 = time.perf_counter()
        order = sorted(range(self.n), key=lambda o: (end[o], start[o], o))
        ends = [end[o] for o in order]
        path = [0]  # path[p]: the state after the first p operations of ``order``
        for o in order:
            nxt = self.steps.get((path[-1], o))
            if nxt is None:
                break
            path.append(nxt[0])
        out = []
        for b in sorted(range(self.n), key=lambda o: (start[o], o)):
            p = bisect.bisect_right(ends, start[b])
            if p >= len(path) or self.steps.get((path[p], b)) is not None:
                continue
            if time.perf_counter() - t0 > seconds:
                break
            cut = self.cut(set(order[:p]) - {b}, b)
            if cut:
                out.append(cut)
        return out

    def _shrink(self, rows, ys, xs, x_first: bool) -> tuple[list[int], list[int]]:
        k = rows.shape[0]
        sample = np.unique(np.linspace(0, k - 1, min(k, SAMPLE)).astype(np.int64))
        while True:
            keep_y, keep_x = _shrink_on(rows[sample], ys, xs, x_first)
            y, x = ys[keep_y], xs[keep_x]
            broken = _breaking(rows, self.mask(y), self.mask(x), ADD)
            if not broken.size:
                return [int(v) for v in y], [int(v) for v in x]
            sample = np.union1d(sample, broken)


@numba.njit(cache=True)
def _breaks(row, ymask, xmask) -> bool:  # pragma: no cover - compiled
    """Whether the done set ``row`` misses all of ``Y`` and contains all of ``X``."""
    for w in range(row.shape[0]):
        if row[w] & ymask[w] or (row[w] & xmask[w]) != xmask[w]:
            return False
    return True


@numba.njit(cache=True)
def _first_breaking(rows, ymask, xmask) -> int:  # pragma: no cover - compiled
    """The first row that breaks the cut ``(Y, X)``, or -1."""
    for r in range(rows.shape[0]):
        if _breaks(rows[r], ymask, xmask):
            return r
    return -1


@numba.njit(cache=True)
def _breaking(rows, ymask, xmask, most):  # pragma: no cover - compiled
    """Up to ``most`` rows that break the cut ``(Y, X)``."""
    out = np.empty(most, dtype=np.int64)
    m = 0
    for r in range(rows.shape[0]):
        if _breaks(rows[r], ymask, xmask):
            out[m] = r
            m += 1
            if m == most:
                break
    return out[:m]


@numba.njit(cache=True)
def _has(row, o) -> bool:  # pragma: no cover - compiled
    return (row[o // WORD_BITS] >> np.uint64(o % WORD_BITS)) & np.uint64(1) == np.uint64(1)


@numba.njit(cache=True)
def _shrink_on(rows, ys, xs, x_first):  # pragma: no cover - compiled
    """Greedy shrinking of ``(Y, X)`` on ``rows`` (every row must keep missing some ``y``
    or some ``x``): which of ``ys`` and ``xs`` stay."""
    k = rows.shape[0]
    cy = np.zeros(k, dtype=np.int64)  # how many of Y the row has
    cx = np.zeros(k, dtype=np.int64)  # how many of X the row misses
    for r in range(k):
        for y in ys:
            if _has(rows[r], y):
                cy[r] += 1
        for x in xs:
            if not _has(rows[r], x):
                cx[r] += 1
    keep_y = np.ones(ys.size, dtype=np.bool_)
    keep_x = np.ones(xs.size, dtype=np.bool_)
    for phase in range(2):
        drop_x = (phase == 0) == x_first
        items = xs if drop_x else ys
        for i in range(items.size):
            o = items[i]
            ok = True
            for r in range(k):
                if _has(rows[r], o) != drop_x:  # the row counts on o
                    if drop_x and cx[r] == 1 and cy[r] == 0:
                        ok = False
                        break
                    if not drop_x and cy[r] == 1 and cx[r] == 0:
                        ok = False
                        break
            if not ok:
                continue
            for r in range(k):
                if _has(rows[r], o) != drop_x:
                    if drop_x:
                        cx[r] -= 1
                    else:
                        cy[r] -= 1
            if drop_x:
                keep_x[i] = False
            else:
                keep_y[i] = False
    return keep_y, keep_x
