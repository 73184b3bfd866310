"""The scheduling problem of an assembly spec: tasks, precedences and lower bounds.

:func:`assembly_schedule` turns the spec's operations into the tasks of
:func:`asp.schedule.makespan.min_makespan`, with the precedences the state graph implies
(:func:`implied_predecessors`) and its lower bounds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from asp.graph.feasibility import WORD_BITS
from asp.graph.fixed_order import FixedOrder
from asp.schedule.makespan import ScheduleProblem, Task


@dataclass(frozen=True)
class AssemblySchedule:
    """The schedule problem of an assembly and its state-graph lower bounds.

    Attributes
    ----------
    problem : ScheduleProblem
    chain_bound : float
        Longest chain of (minimum) durations through the precedences implied by the state
        graph.
    load_bound : float
        Largest total duration of the operations only one agent may do, or the total
        work shared evenly over all agents, whichever is larger. An agent open to either
        side (``side: any``, e.g. every ``.IN2`` task) counts as one worker of each side.
    """

    problem: ScheduleProblem
    chain_bound: float
    load_bound: float

    @property
    def lower_bound(self) -> float:
        return max(self.chain_bound, self.load_bound)


def assembly_schedule(spec, graph=None, *, fixed_order: bool = True) -> AssemblySchedule:
    """The scheduling problem of an assembly spec.

    Precedences are the explicit ``after`` ones plus, when the state graph is given, every
    precedence it implies (operation ``a`` before ``b`` when every completable state with
    ``b`` done has ``a`` done: geometry and tool logic that act as plain precedence).
    Geometric alternatives that are not plain precedences (``a`` or ``c`` before ``b``) are
    relaxed. Under the tool model the bit-change times are part of the changing operations.

    A graph whose alike operations are in a fixed order (:mod:`asp.graph.fixed_order`) gives the
    full graph's precedences instead (the chains are none) and the order in which the
    blocks of a class start (``start_order``, symmetry breaking); ``fixed_order=False``
    keeps the chains as precedences (the conservative schedule, for comparison).
    """
    ops = spec.operations
    n = len(ops)
    index = {op.id: i for i, op in enumerate(ops)}
    fixed = None if graph is None or not fixed_order else FixedOrder.of_graph(graph)
    chained = set() if fixed is None else fixed.chain_pairs()
    pred = [
        {index[a] for a in op.after if (index[a], b) not in chained} for b, op in enumerate(ops)
    ]
    if graph is not None:
        implied = implied_predecessors(graph)
        if fixed is not None:
            implied = fixed.implied(implied)
        for b, mask in enumerate(implied):
            pred[b] |= {a for a in range(n) if mask >> a & 1}
    change = {t.name: t.change_time for t in spec.tools}
    either = {a.name for a in spec.agents if a.side == "any"}
    tasks = []
    for op in ops:
        extra = sum(change[t] for t, _ in op.sets)
        # An agent open to either side stands for one worker of each side in parallel.
        modes = []
        for a, d in op.durations:
            names = (f"{a}:human", f"{a}:robot") if a in either else (a,)
            modes += [(name, d + extra) for name in names]
        tasks.append(
            Task(
                id=op.id,
                modes=tuple(modes),
                requires=op.requires,
                sets=op.sets,
                description=op.description,
            )
        )
    precedences = tuple((a, b) for b in range(n) for a in sorted(pred[b]))
    problem = ScheduleProblem(
        name=spec.name,
        tasks=tuple(tasks),
        precedences=precedences,
        tool_initial=tuple((t.name, t.initial) for t in spec.tools),
        credit=spec.credit,
        start_order=() if fixed is None else fixed.start_order(),
    )
    shortest = [min(d for _, d in t.modes) for t in tasks]
    finish = [0.0] * n
    for b in _topo(pred):
        finish[b] = shortest[b] + max((finish[a] for a in pred[b]), default=0.0)
    # Load bounds: the work of an agent that alone may do its tasks, and all the work
    # shared out evenly over every agent.
    load: dict[str, float] = {}
    for t in tasks:
        if len(t.modes) == 1:
            load[t.modes[0][0]] = load.get(t.modes[0][0], 0.0) + t.modes[0][1]
    agents = {a for t in tasks for a, _ in t.modes}
    shared = sum(shortest) / len(agents) if agents else 0.0
    return AssemblySchedule(
        problem=problem,
        chain_bound=max(finish, default=0.0),
        load_bound=max([shared, *load.values()]),
    )


def implied_predecessors(graph) -> list[int]:
    """Per operation, the bitmask of operations done in every completable state where it is.

    One pass over the live states' keys (:func:`_common_done`), a few operations per state
    and operation.
    """
    model = graph.model
    n = model.n_ops
    keys = np.ascontiguousarray(graph.keys, dtype=np.uint64).reshape(graph.keys.shape[0], -1)
    done_bits = np.bitwise_or.reduce(np.asarray(model.op_bits, dtype=np.uint64), axis=0)
    common, seen = _common_done(keys, graph.coreachable(), done_bits, n)
    out = []
    for b in range(n):
        mask = sum(int(w) << (WORD_BITS * k) for k, w in enumerate(common[b].tolist()))
        out.append(mask & ~(1 << b) if seen[b] else 0)
    return out


@numba.njit(cache=True)
def _common_done(keys, alive, done_bits, n):  # pragma: no cover - compiled
    """(n, W) uint64 AND of the done words of the live states with operation ``b`` done, and
    (n,) bool whether any has it."""
    width = keys.shape[1]
    common = np.full((n, width), np.uint64(0xFFFFFFFFFFFFFFFF), dtype=np.uint64)
    seen = np.zeros(n, dtype=np.bool_)
    one = np.uint64(1)
    for s in range(keys.shape[0]):
        if not alive[s]:
            continue
        for w in range(width):
            x = keys[s, w] & done_bits[w]
            for k in range(64):
                if (x >> np.uint64(k)) & one:
                    b = w * 64 + k
                    if b < n:
                        seen[b] = True
                        for v in range(width):
                            common[b, v] &= keys[s, v] & done_bits[v]
    return common, seen


def _topo(pred: list[set[int]]) -> list[int]:
    order, seen = [], set()

    def visit(b: int) -> None:
        stack = [(b, iter(sorted(pred[b])))]
        seen.add(b)
        while stack:
            node, it = stack[-1]
            nxt = next((a for a in it if a not in seen), None)
            if nxt is None:
                stack.pop()
                order.append(node)
            else:
                seen.add(nxt)
                stack.append((nxt, iter(sorted(pred[nxt]))))

    for b in range(len(pred)):
        if b not in seen:
            visit(b)
    return order
