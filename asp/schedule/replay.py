"""The physical replay: a schedule played through the state graph by the concurrent rules.

:class:`ReplayModel` is what the replay needs of the concurrent rules (the workers, the
state graph's transitions, the tool conflicts, the short cuts and the fixed order of alike
operations); :func:`schedule_violation` replays a schedule and names the first fault with
its cut, for the lazy cuts of :func:`asp.schedule.makespan.min_makespan`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from asp.game.dag import HUMAN, ROBOT
from asp.graph.fixed_order import FixedOrder
from asp.graph.state_graph import StateGraph
from asp.graph.together import OK, TOOL, LiveSteps, first_failure
from asp.schedule.cuts import PlacementCuts
from asp.spec import AssemblySpec


@dataclass(frozen=True)
class Worker:
    """One worker of the concurrent game: a spec agent on one side."""

    name: str
    agent: str
    side: int


def spec_workers(spec: AssemblySpec) -> tuple[Worker, ...]:
    """The workers of the concurrent game: robots first, then humans; an agent of side
    ``any`` is one worker of each side (``A:robot``, ``A:human``), as in the CP-SAT schedule."""
    workers = []
    for side in (ROBOT, HUMAN):
        for a in spec.agents:
            if a.side == "any":
                name = f"{a.name}:{'robot' if side == ROBOT else 'human'}"
                workers.append(Worker(name=name, agent=a.name, side=side))
            elif (a.side == "robot") == (side == ROBOT):
                workers.append(Worker(name=a.name, agent=a.name, side=side))
    return tuple(workers)


def tool_conflicts(spec: AssemblySpec) -> np.ndarray:
    """(n_ops, n_ops) bool: one operation changes a tool the other needs or changes."""
    ops = spec.operations
    n = len(ops)
    tools_set = [{t for t, _ in o.sets} for o in ops]
    tools_used = [{t for t, _ in (*o.sets, *o.requires)} for o in ops]
    conflict = np.zeros((n, n), dtype=bool)
    for a in range(n):
        for b in range(n):
            if a != b and (tools_set[a] & tools_used[b] or tools_set[b] & tools_used[a]):
                conflict[a, b] = True
    return conflict


@dataclass(frozen=True, eq=False)
class ReplayModel:
    """What a schedule replay needs of the concurrent rules: the spec, the workers, the
    state graph's transitions, the tool conflicts, (optionally) the short cuts and the
    graph's fixed order of alike operations, undone (:mod:`asp.graph.fixed_order`)."""

    spec: AssemblySpec
    workers: tuple[Worker, ...]
    steps: LiveSteps
    conflict: np.ndarray
    cuts: PlacementCuts | None = None
    fixed: FixedOrder | None = None


def replay_model(
    spec: AssemblySpec, graph: StateGraph, *, cuts: bool = True, fixed_order: bool = True
) -> ReplayModel:
    """The :class:`ReplayModel` of a spec and its state graph (with the short cuts).

    On a graph whose alike operations are in a fixed order, the replay undoes it
    (:mod:`asp.graph.fixed_order`): an alike operation takes the transition of the next one of
    its chain, so alike operations may run at once and in any order (``fixed_order=False``:
    the graph's transitions as they are).
    """
    fixed = FixedOrder.of_graph(graph) if fixed_order else None
    steps = LiveSteps(graph, label=None if fixed is None else fixed.label)
    positive = all(d > 0 for op in spec.operations for _, d in op.durations)
    short = PlacementCuts(graph, steps, combined=positive, fixed=fixed) if cuts else None
    return ReplayModel(spec, spec_workers(spec), steps, tool_conflicts(spec), short, fixed)


def schedule_violation(
    model: ReplayModel, rows: list[dict]
) -> tuple[str, list[tuple[int, int]]] | None:
    """Replay a schedule through the state graph; ``None`` if it is physically feasible.

    The rule is the concurrent game's (:func:`asp.graph.together.together`):
    at every start time ``t``, with ``D`` the operations ended by ``t`` and ``A`` those
    running, every ``D + T`` (``T`` a subset of ``A``) is a state of the state graph from
    which every other operation of ``A`` is a transition, and no two running operations
    conflict on a tool. Equivalently: every order of placement consistent with the schedule
    (``y`` before ``x`` whenever ``y`` ends by the time ``x`` starts) is a path of the state
    graph, whichever of two overlapping operations finishes first.

    On a graph whose alike operations are in a fixed order (``model.fixed``), the order is
    undone (:mod:`asp.graph.fixed_order`): each block of alike operations must be done in its
    order (a derived precedence, its own cut), then the transitions are looked up by label.

    Returns
    -------
    (message, cut) or None
        ``message`` names the operation and the state it cannot follow; ``cut`` is a list of
        ``(y, x)`` operation-index pairs of which every feasible schedule has at least one as
        a precedence. With ``I`` the done set and ``b`` the operation that cannot follow it,
        a feasible schedule never has ``I`` closed under precedence with ``b`` among the
        first operations after it (the order ``I``, ``b`` would be a placement order), so some
        operation outside ``I`` precedes one of ``I + {b}``.
    """
    ids = model.spec.op_ids
    index = {oid: i for i, oid in enumerate(ids)}
    start = {index[r["task"]]: float(r["start"]) for r in rows}
    end = {index[r["task"]]: float(r["end"]) for r in rows}
    n = len(ids)
    if len(start) != n:
        missing = [ids[i] for i in range(n) if i not in start]
        return f"operation {missing[0]} is not scheduled", []
    workers = {w.name for w in model.workers}
    for r in rows:
        if r["agent"] not in workers:
            return f"operation {r['task']}: unknown agent {r['agent']!r}", []
    fixed = model.fixed
    if fixed is not None:  # relabelling needs each block of alike operations in its order
        for b in range(n):
            for a in fixed.block_before(b):
                if end[a] > start[b]:
                    return f"operation {ids[b]} starts before {ids[a]} ends", [(a, b)]
    state, done = 0, set()
    by_end = sorted(range(n), key=lambda i: (end[i], start[i]))
    for t in [*sorted(set(start.values())), math.inf]:
        for i in by_end:
            if end[i] <= t and i not in done:
                nxt = model.steps.get((state, i))
                if nxt is None:
                    return _cannot_follow(model, done, i)
                state = nxt[0]
                done.add(i)
        running = sorted(i for i in range(n) if start[i] <= t < end[i])
        found = together_violation(model, state, done, running)
        if isinstance(found, tuple):
            a, b = found
            return f"operations {ids[a]} and {ids[b]} overlap but share a tool", [(a, b), (b, a)]
        if found is not None:
            return _cannot_follow(model, *found)
    return None


def _cannot_follow(model: ReplayModel, done: set[int], b: int) -> tuple[str, list[tuple[int, int]]]:
    """The violation "``b`` cannot follow the done set" and its cut (see
    :func:`schedule_violation`): some operation outside ``done`` precedes one of
    ``done + {b}``, or a shorter cut from ``model.cuts``
    (:class:`asp.schedule.cuts.PlacementCuts`)."""
    ids = model.spec.op_ids
    where = "{" + " ".join(ids[i] for i in sorted(done)) + "}" if done else "the start"
    cut = model.cuts.cut(done, b) if model.cuts is not None else None
    if cut is None:
        first = done | {b}
        cut = [(y, x) for x in sorted(first) for y in range(len(ids)) if y not in done and y != x]
    return f"operation {ids[b]} cannot follow {where}", cut


def together_violation(model: ReplayModel, state: int, done: set[int], running: list[int]):
    """Whether the operations ``running`` may run together from ``state`` (``done`` done):
    :func:`asp.graph.together.together`.

    Returns
    -------
    None, tuple or list
        None if they may; ``(a, b)``: two of them share a tool; ``[done set, b]``: ``b``
        cannot follow that done set (some order of the running ones reaches it).
    """
    code, x, y = first_failure(model.steps, model.conflict, state, running)
    if code == OK:
        return None
    if code == TOOL:
        return (running[x], running[y])
    return [set(done) | {running[k] for k in range(len(running)) if x >> k & 1}, running[y]]
