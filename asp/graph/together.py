"""Which operations may run at the same time: one rule, written once.

``../shared/DESIGN.md`` ("The concurrent game"): two operations may run at the same time
only if each is feasible whichever finishes first (both orders are edges of the state
graph) and neither changes a tool the other needs. For a set ``A`` running on top of state
``s``: every ``s + T`` (``T`` a subset of ``A``) is a co-reachable state from which every
other operation of ``A`` is a transition into a co-reachable state, and no two operations of
``A`` conflict on a tool. :func:`together` is that rule; the concurrent game's Python
builder (:meth:`asp.concurrent.model.ConcurrentModel.compatible`), its compiled builder
(:mod:`asp.concurrent.kernel`) and the CP-SAT schedule replay
(:func:`asp.schedule.replay.schedule_violation`, and the list schedule built on it) all call it.

The transitions are :class:`LiveSteps`: the state graph's transitions between co-reachable
states in CSR form (per state, its out-transitions in the state graph's order), with the
tool-change time each adds. On a graph whose alike operations are in a fixed order, the
schedule replay looks transitions up by *label* (:mod:`asp.graph.fixed_order`: an alike operation
takes the transition of the next one of its chain).
"""

from __future__ import annotations

import numba
import numpy as np

from asp.graph.state_graph import sorted_bounds

OK = 0
""":func:`together`: the operations may run together."""
TOOL = 1
""":func:`together`: ``ops[x]`` and ``ops[y]`` conflict on a tool."""
ORDER = 2
""":func:`together`: after the subset ``x`` (a bit mask over ``ops``), ``ops[y]`` is no
transition."""


class LiveSteps:
    """The state graph's transitions between co-reachable states, in CSR form.

    Attributes
    ----------
    indptr : (N + 1,) int64
        Out-transitions of state ``s``: ``indptr[s]:indptr[s + 1]`` (the state graph's order).
    dst, op : (E,) int
        Target state and operation of each transition.
    change : (E,) int64
        Tool-change time each transition adds (zeros unless given).
    label : (n_ops,) int64 or None
        With labels, ``op`` holds the label of each transition's operation and an operation
        ``o`` is looked up as ``label[o]`` (:mod:`asp.graph.fixed_order`).
    """

    def __init__(self, graph, change=None, label=None):
        """``change(src, op)``: the tool-change time of the live transitions with those
        sources and operations (optional; default 0); ``label``: see the attribute."""
        alive = graph.coreachable()
        if alive.all():  # no dead ends (a reduced graph drops them): the graph's own arrays
            src, self.dst, self.op = graph.src, graph.dst, graph.op
        else:
            keep = alive[graph.src] & alive[graph.dst]
            src, self.dst, self.op = graph.src[keep], graph.dst[keep], graph.op[keep]
        self.label = None if label is None else np.asarray(label, dtype=np.int64)
        if self.label is not None:
            self.op = self.label.astype(self.op.dtype)[self.op]
        self.change = np.zeros(self.dst.size, dtype=np.int64)
        if change is not None and src.size:
            self.change = np.asarray(change(src, self.op), dtype=np.int64)
        # the state graph's transitions are sorted by source (bincount would count an int64
        # copy of every transition)
        if src.size > 1 and not np.all(src[1:] >= src[:-1]):
            raise ValueError("LiveSteps: the state graph's transitions are not sorted by source")
        self.indptr = sorted_bounds(src, np.arange(graph.n_states + 1))

    @property
    def n_states(self) -> int:
        return int(self.indptr.size - 1)

    @property
    def src(self) -> np.ndarray:
        """(E,) int64: the source state of each transition."""
        return np.repeat(np.arange(self.n_states, dtype=np.int64), np.diff(self.indptr))

    def get(self, key):
        """``(next state, change)`` of operation ``o`` in state ``s`` (``key = (s, o)``), or
        None when it is no live transition (a dict's ``get``)."""
        s, o = key
        e = edge(int(s), self.key(o), self.indptr, self.op)
        return None if e < 0 else (int(self.dst[e]), int(self.change[e]))

    def key(self, o) -> int:
        """What operation ``o`` is looked up as in ``op`` (its label)."""
        return int(o) if self.label is None else int(self.label[o])

    def arrays(self) -> tuple:
        """``(indptr, dst, op)``, as :func:`together` takes them."""
        return self.indptr, self.dst, self.op


@numba.njit(cache=True)
def edge(s, o, indptr, op):  # pragma: no cover - compiled
    """The transition of operation ``o`` out of state ``s``, or -1."""
    for e in range(indptr[s], indptr[s + 1]):
        if op[e] == o:
            return e
    return -1


@numba.njit(cache=True)
def together(s, ops, m, indptr, dst, op, conflict):  # pragma: no cover - compiled
    """Whether ``ops[:m]`` may run together on top of state ``s`` (module docstring):
    :func:`together_as` with each operation looked up as itself."""
    return together_as(s, ops, ops, m, indptr, dst, op, conflict)


@numba.njit(cache=True)
def together_as(s, ops, keys, m, indptr, dst, op, conflict):  # pragma: no cover - compiled
    """Whether ``ops[:m]`` may run together on top of state ``s`` (module docstring), the
    transition of ``ops[i]`` looked up as ``keys[i]`` (its label, :class:`LiveSteps`).

    Returns
    -------
    (code, x, y)
        ``(OK, 0, 0)``; ``(TOOL, x, y)``: ``ops[x]`` and ``ops[y]`` conflict on a tool (or are
        the same operation); ``(ORDER, mask, y)``: ``ops[y]`` is no transition after the
        operations of bit mask ``mask`` are done on top of ``s``. Subsets are visited in
        increasing mask order, so ``mask`` is the first failing one.
    """
    for i in range(m):
        for j in range(i + 1, m):
            if ops[i] == ops[j] or conflict[ops[i], ops[j]]:
                return TOOL, i, j
    reached = np.empty(1 << m, np.int64)
    reached[0] = s
    for mask in range(1 << m):  # every subset after its smaller subsets
        cur = reached[mask]
        for i in range(m):
            if not (mask >> i) & 1:
                e = edge(cur, keys[i], indptr, op)
                if e < 0:
                    return ORDER, mask, i
                reached[mask | (1 << i)] = dst[e]
    return OK, 0, 0


def first_failure(steps: LiveSteps, conflict: np.ndarray, state: int, ops) -> tuple[int, int, int]:
    """:func:`together` on a sequence of operation indices (Python callers)."""
    arr = np.asarray(ops, dtype=np.int64)
    keys = arr if steps.label is None else steps.label[arr]
    return together_as(int(state), arr, keys, arr.size, *steps.arrays(), conflict)
