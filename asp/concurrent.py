"""The concurrent game: the human and the robots working at once (turn model ``concurrent``).

Semantics (``../shared/DESIGN.md``, "The concurrent game"):

- Each agent (a *worker*) does one operation at a time, taking its duration. An agent of
  side ``any`` (every task of a ``.IN2`` graph) is one worker of each side, ``A:human`` and
  ``A:robot``, as in the CP-SAT schedule.
- A state is the assembly state (done operations and tool values, a node of the state
  graph), and for each busy worker its operation and the time it still needs, and the
  deviations the human side may still make (the budget ``b``; :data:`UNBOUNDED` for the
  fully adversarial human).
- Decisions are taken at events (the start and every completion). The robot side commits
  first: an operation or *wait* for each free robot and, when the budget is finite, an
  instruction (an operation or wait) for each free human. Then the human side, knowing it,
  starts operations on its free humans and picks their durations. A free human following
  its instruction is free of charge; doing anything else is one deviation (at most ``b``).
  A human that deviates or has no instruction does not idle while it has an operation it may
  start. Waiting is allowed only while something runs.
- Two operations run at the same time only if each is feasible whichever finishes first:
  with ``D`` done and the set ``A`` running, every ``D + T`` (``T`` a subset of ``A``) is a
  state of the state graph from which each operation of ``A - T`` is an edge
  (:func:`asp.together.together`, the one place this rule is written: both builders and
  the schedule replay call it), and no
  operation changes a tool another one needs or changes. Every
  state entered must still be completable (the state graph's co-reachable states).
- The human's duration may be a range ``[min, max]``. The adversary picks it on the grid
  ``min, min + step, ..., max`` (``max`` always included; ``step`` defaults to the time
  unit 1). With every duration a whole number of steps this is exact: the game is then in
  discrete time, every event falls on the grid. For real-valued durations it is a lower
  bound of the adversary's supremum (a completion just before another event can be worse
  than one exactly at it). ``step=None`` uses the two end points only (a cheaper lower bound).
- The cost is the makespan. The robot side minimises it, the human side maximises it.

Compilation (the game the existing solver plays): every game state becomes a *robot node*
(the robot side on turn) and every robot commitment a *human node*; a robot edge (cost 0)
is a commitment, a human edge is the human side's reply followed by the wait for the next
event, and costs the time until that event. Robot and human nodes alternate strictly, each
node has moves only for its side, so the alternating turn rules of :mod:`asp.solve` (robot
first, the turn flips every move) play exactly this game, and the makespan is the sum of
the edge costs. One DAG holds every budget ``0..K`` (a state's budget is part of it), with
one start node per budget: ``W*(k)`` is the value at start ``k``. The unbounded adversary
is its own DAG (no instructions).

Exactness of W*(0): with budget 0 and fixed durations the robot side controls every start;
the best makespan over event-driven schedules (each operation starts at time 0 or at a
completion) is the optimum over all schedules (a left shift of any feasible schedule is
event-driven), so ``W*(0)`` equals the CP-SAT optimum on the same rules
(:func:`assembly_makespan`).
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from asp.baseline import (
    AssemblySchedule,
    BaselineResult,
    assembly_schedule,
    integer_scale,
    list_schedule,
    min_makespan,
    schedule_violation,
)
from asp.cuts import PlacementCuts
from asp.dag import HUMAN, ROBOT, GameDAG, from_arrays
from asp.errors import GameError, SpecError
from asp.fixed_order import FixedOrder
from asp.numbers import json_number
from asp.rules import costs_close
from asp.solve import Solution, evaluate_policy, solve
from asp.spec import AssemblySpec
from asp.state_graph import StateGraph
from asp.together import OK, LiveSteps, first_failure

UNBOUNDED = -1
"""Budget of the fully adversarial human (no instructions, every reply allowed)."""
WAIT = -1
"""Operation index of a worker that waits (or has nothing to do)."""
DEFAULT_MAX_NODES = 3_000_000
"""Above this many game nodes the build stops with a ``ValueError``."""
DEFAULT_MAX_K = 12
"""Largest deviation budget tried when looking for the flat part of the curve."""
AUTO_TIME_LIMIT = 10.0
"""Seconds for the whole CP-SAT makespan stage by default (:func:`assembly_makespan` with
``time_limit=None``), its preparation included. A small assembly is proven optimal in well
under a second; on the 72-part cycloidal drive every better schedule came within the first
7 s of the search and the cuts after them gave nothing better (20 s bought nothing)."""
AUTO_PATIENCE = 2.0
"""By default the CP-SAT makespan stage stops once neither a better schedule nor a new cut
has come for this many seconds (or when it is proven optimal)."""
MIN_SOLVE_S = 0.5
"""The least time the automatic budget leaves CP-SAT after a long preparation."""


@dataclass(frozen=True)
class Worker:
    """One worker of the concurrent game: a spec agent on one side."""

    name: str
    agent: str
    side: int


@dataclass(frozen=True, eq=False)
class ConcurrentModel:
    """The spec and state graph compiled for the concurrent game.

    Attributes
    ----------
    graph : StateGraph
    workers : tuple of Worker
        Robots first, then humans.
    scale : int
        Times are integers in units of ``1 / scale`` (see :func:`asp.baseline.integer_scale`).
    choices : list of list of tuple of int, [worker][op]
        The durations (scaled) worker ``w`` may take for operation ``op`` (empty: not
        allowed). A robot has one; a human with a range has the grid points.
    steps : asp.together.LiveSteps
        Transitions of the state graph between co-reachable states, with the tool-change
        time (scaled) the operation adds there.
    succ : dict (state, op) -> (state, change)
        The same as a dictionary (the Python builder's lookups).
    enabled : list of tuple of int
        Per state, the operations with a transition.
    conflict : (n_ops, n_ops) bool
        Tool conflicts: one changes a tool the other needs or changes.
    complete : (N,) bool
    """

    spec: AssemblySpec
    graph: StateGraph
    workers: tuple[Worker, ...]
    scale: int
    choices: list
    steps: LiveSteps
    succ: dict
    enabled: list
    conflict: np.ndarray
    complete: np.ndarray
    _memo: dict = field(default_factory=dict, repr=False)

    @property
    def n_ops(self) -> int:
        return len(self.spec.operations)

    @property
    def robots(self) -> list[int]:
        return [w for w, x in enumerate(self.workers) if x.side == ROBOT]

    @property
    def humans(self) -> list[int]:
        return [w for w, x in enumerate(self.workers) if x.side == HUMAN]

    def compatible(self, state: int, ops: tuple[int, ...]) -> bool:
        """Whether the operations ``ops`` may run together from ``state``
        (:func:`asp.together.together`, the one place this rule is written)."""
        key = (state, ops)
        hit = self._memo.get(key)
        if hit is None:
            hit = first_failure(self.steps, self.conflict, state, ops)[0] == OK
            self._memo[key] = hit
        return hit

    def after(self, state: int, ops) -> int:
        """The state after the operations ``ops`` (compatible) are done on top of ``state``."""
        for o in ops:
            state = self.succ[(state, o)][0]
        return state

    def duration_choices(self, w: int, op: int, state: int) -> tuple[int, ...]:
        """Durations (scaled) worker ``w`` may take for ``op`` started in ``state``."""
        change = self.succ[(state, op)][1]
        return tuple(d + change for d in self.choices[w][op])

    def candidates(self, state: int, w: int, busy: tuple[int, ...]) -> list[int]:
        """Operations worker ``w`` may start in ``state`` next to the busy operations."""
        return [
            o
            for o in self.enabled[state]
            if self.choices[w][o]
            and o not in busy
            and self.compatible(state, tuple(sorted((*busy, o))))
        ]

    def time(self, scaled: float) -> float:
        """A scaled time in the spec's units."""
        return scaled / self.scale

    @property
    def succ_change_max(self) -> int:
        """The longest tool-change time (scaled) any transition adds."""
        return max((c for _, c in self.succ.values()), default=0)

    def kernel_arrays(self) -> tuple:
        """The arrays :func:`asp.concurrent_kernel.build_kernel` takes (its docstring)."""
        n = self.n_ops
        nw = len(self.workers)
        width = max((len(c) for row in self.choices for c in row), default=1)
        dur = np.zeros((nw, n, max(1, width)), dtype=np.int64)
        ndur = np.zeros((nw, n), dtype=np.int64)
        for w, row in enumerate(self.choices):
            for o, c in enumerate(row):
                ndur[w, o] = len(c)
                dur[w, o, : len(c)] = c
        side = np.array([w.side for w in self.workers], dtype=np.int8)
        steps = self.steps
        return (
            steps.indptr,
            steps.dst.astype(np.int64),
            steps.op.astype(np.int64),
            steps.change,
            dur,
            ndur,
            self.conflict,
            self.complete,
            side,
        )


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
    graph's fixed order of alike operations, undone (:mod:`asp.fixed_order`)."""

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
    (:mod:`asp.fixed_order`): an alike operation takes the transition of the next one of
    its chain, so alike operations may run at once and in any order (``fixed_order=False``:
    the graph's transitions as they are).
    """
    fixed = FixedOrder.of_graph(graph) if fixed_order else None
    steps = LiveSteps(graph, label=None if fixed is None else fixed.label)
    positive = all(d > 0 for op in spec.operations for _, d in op.durations)
    short = PlacementCuts(graph, steps, combined=positive, fixed=fixed) if cuts else None
    return ReplayModel(spec, spec_workers(spec), steps, tool_conflicts(spec), short, fixed)


def concurrent_model(
    spec: AssemblySpec, graph: StateGraph, *, step: float | None = 1.0
) -> ConcurrentModel:
    """Compile ``spec`` and its state graph for the concurrent game.

    Parameters
    ----------
    step : float or None
        Grid of the human's durations within a range (module docstring); ``None``: the two
        end points.

    Raises
    ------
    ValueError
        One line naming the spec and the fault: a robot with a duration range, an agent
        with no operation it may do, an operation nobody may do, a bad duration or step.
    """
    where = spec.source or spec.name
    if step is not None and not (math.isfinite(step) and step > 0):
        raise SpecError(f"{where}: duration step: expected a positive number, got {step}")
    workers = spec_workers(spec)
    ops = spec.operations
    ranges = [[None] * len(ops) for _ in workers]
    for i, op in enumerate(ops):
        if not op.durations:
            raise SpecError(f"{where}: operations[{op.id}]: no agent may do this operation")
        for w, x in enumerate(workers):
            if x.agent in op.agents:
                lo, hi = op.duration_range(x.agent)
                if not (math.isfinite(lo) and math.isfinite(hi)) or lo < 0 or lo > hi:
                    raise SpecError(
                        f"{where}: operations[{op.id}].agents.{x.agent}: expected a duration "
                        f">= 0 or a range [min, max] with 0 <= min <= max, got [{lo}, {hi}]"
                    )
                if lo != hi and x.side == ROBOT:
                    raise SpecError(
                        f"{where}: operations[{op.id}].agents.{x.agent}: a duration range is "
                        "for a human; a robot's duration is one number"
                    )
                ranges[w][i] = (lo, hi)
    for a in spec.agents:
        if not any(a.name in op.agents for op in ops):
            raise SpecError(f"{where}: agents.{a.name}: this agent may do no operation")
    numbers = [v for row in ranges for r in row if r is not None for v in r]
    numbers += [t.change_time for t in spec.tools] + ([step] if step is not None else [])
    scale = integer_scale(numbers)
    choices = []
    for row in ranges:
        out = []
        for r in row:
            if r is None:
                out.append(())
                continue
            lo, hi = round(r[0] * scale), round(r[1] * scale)
            if lo == hi:
                out.append((lo,))
            elif step is None:
                out.append((lo, hi))
            else:
                s = max(1, round(step * scale))
                out.append(tuple(range(lo, hi, s)) + (hi,))
        choices.append(out)
    model = graph.model
    change = np.array([round(spec.tool(t).change_time * scale) for t in model.tool_names])

    def change_time(src, op):
        return model.tool_changes(graph.keys[src], op).astype(np.int64) @ change

    steps = LiveSteps(graph, change_time if model.tool_names else None)
    succ = {}
    enabled = [[] for _ in range(graph.n_states)]
    pairs = zip(
        steps.src.tolist(),
        steps.dst.tolist(),
        steps.op.tolist(),
        steps.change.tolist(),
        strict=True,
    )
    for s, d, o, c in pairs:
        succ[(s, o)] = (d, int(c))
        enabled[s].append(o)
    conflict = tool_conflicts(spec)
    return ConcurrentModel(
        spec=spec,
        graph=graph,
        workers=tuple(workers),
        scale=scale,
        choices=choices,
        steps=steps,
        succ=succ,
        enabled=[tuple(e) for e in enabled],
        conflict=conflict,
        complete=graph.complete,
    )


# --------------------------------------------------------------------------- the game


@dataclass(frozen=True)
class Commit:
    """A robot edge: the operation each worker starts (robots) or is told to do (humans).

    ``ops[w]`` is an operation index, :data:`WAIT`, or ``None`` (busy worker, or a human
    without instruction under the unbounded budget).
    """

    ops: tuple


@dataclass(frozen=True)
class Reply:
    """A human edge: the operation and duration (scaled) each free human starts, the
    deviations it costs, and the time until the next event (scaled)."""

    ops: tuple
    durations: tuple
    deviations: int
    delta: int


@dataclass(frozen=True, eq=False)
class ConcurrentGame:
    """The concurrent game compiled into a :class:`GameDAG` (module docstring).

    Attributes
    ----------
    model : ConcurrentModel
    dag : GameDAG
        Robot and human nodes alternate; costs are in the spec's time unit.
    budgets : tuple of int
        The deviation budgets with a start node (:data:`UNBOUNDED` alone for the unbounded
        game).
    starts : dict budget -> node index
    nodes : list of tuple
        Per node: ``(kind, state, running, budget, instructions)``; ``kind`` is ``"R"``,
        ``"H"`` or ``"E"`` (the end); ``running`` per worker ``(op, remaining)`` or
        ``(WAIT, 0)``.
    actions : list of Commit or Reply
        Per edge.
    seconds : float
        Build time.
    """

    model: ConcurrentModel
    dag: GameDAG
    budgets: tuple[int, ...]
    starts: dict
    nodes: list
    actions: list
    seconds: float

    @property
    def unbounded(self) -> bool:
        return self.budgets == (UNBOUNDED,)


LABEL_LIMIT = 200_000
"""Above this many edges the DAG's edge labels are left out (the actions hold the moves)."""


def build_game(
    model: ConcurrentModel,
    budgets: int | None | list,
    *,
    max_nodes: int = DEFAULT_MAX_NODES,
    progress: bool = False,
    compiled: bool | None = None,
) -> ConcurrentGame:
    """Build the concurrent game for the budgets ``0..K`` (``budgets=K``) or unbounded (``None``).

    Parameters
    ----------
    compiled : bool, optional
        Use the numba builder (:mod:`asp.concurrent_kernel`); default whenever its packed
        state key fits. ``False``: the Python builder (the same game, slower).

    Raises
    ------
    ValueError
        A negative budget, or more than ``max_nodes`` nodes (the message names ``--max-k``).
    """
    from asp import concurrent_kernel as kernel

    t0 = time.perf_counter()
    where = model.spec.source or model.spec.name
    if budgets is None:
        levels = [UNBOUNDED]
    else:
        k = int(budgets)
        if k < 0:
            raise GameError(f"k: expected a deviation budget >= 0, got {k}")
        levels = list(range(k + 1))
    too_big = GameError(
        f"{where}: the concurrent game exceeds {max_nodes:,} nodes (budgets "
        f"{'inf' if levels == [UNBOUNDED] else f'{levels[0]}..{levels[-1]}'}); bound the "
        "deviation budget with --max-k, coarsen the human duration grid (--duration-step), "
        "or add precedences"
    )
    longest = max(
        (d + int(model.succ_change_max) for row in model.choices for c in row for d in c),
        default=0,
    )
    fits = kernel.fits(len(model.workers), model.n_ops, longest, model.graph.n_states, levels[-1])
    if compiled is None:
        compiled = fits
    if compiled:
        if not fits:
            raise GameError(f"{where}: the compiled builder's packed state key does not fit")
        arrays = model.kernel_arrays()
        out = kernel.build_kernel(*arrays, np.array(levels, dtype=np.int64), int(max_nodes))
        overflow, rows, starts_a, src, dst, cost, side, e_ops, e_dur, e_dev = out
        if overflow:
            raise too_big
        order = np.argsort(src, kind="stable")
        src, dst, cost, side = src[order], dst[order], cost[order], side[order]
        nodes = _NodeRows(rows, model.humans)
        actions = _ActionRows(side, e_ops[order], e_dur[order], e_dev[order], cost)
        starts = {b: int(starts_a[i]) for i, b in enumerate(levels)}
        end = 0
    else:
        nodes, actions, starts, end, src, dst, cost, side = _build_python(
            model, levels, max_nodes, too_big, progress
        )
    labels = len(actions) <= LABEL_LIMIT
    dag = from_arrays(
        list(range(len(nodes))),
        src,
        dst,
        np.asarray(cost, dtype=np.float64) / model.scale,
        np.asarray(side, dtype=np.int8),
        start=starts[levels[-1]],
        end=end,
        operations=tuple(_edge_ops(model, a) for a in actions) if labels else None,
        agents=tuple(_edge_agents(model, a) for a in actions) if labels else None,
        cost_model="time",
        metadata={
            "generator": "asmplan.concurrent/1",
            "assembly": model.spec.name,
            "source": model.spec.source,
            "turn_model": "concurrent",
            "budgets": [None if b == UNBOUNDED else b for b in levels],
            "workers": {w.name: ("robot" if w.side == ROBOT else "human") for w in model.workers},
        },
    )
    return ConcurrentGame(
        model=model,
        dag=dag,
        budgets=tuple(levels),
        starts=starts,
        nodes=nodes,
        actions=actions,
        seconds=time.perf_counter() - t0,
    )


class _NodeRows(Sequence):
    """The compiled builder's node rows read as the Python builder's node tuples."""

    def __init__(self, rows: np.ndarray, humans: list[int]):
        self.rows = rows
        self.humans = humans
        self.nw = (rows.shape[1] - 3) // 3

    def __len__(self) -> int:
        return int(self.rows.shape[0])

    def __getitem__(self, v):
        row = self.rows[int(v)].tolist()
        nw = self.nw
        kind, state, budget = row[0], row[1], row[2]
        if kind == 2:
            return ("E", -1, (), 0, ())
        ops, rem, instr = row[3 : 3 + nw], row[3 + nw : 3 + 2 * nw], row[3 + 2 * nw :]
        running = tuple((o, r) if o >= 0 else (WAIT, 0) for o, r in zip(ops, rem, strict=True))
        told = ()
        if kind == 1 and budget != UNBOUNDED:
            told = tuple(instr[w] for w in self.humans if ops[w] == WAIT)
        return ("R" if kind == 0 else "H", state, running, budget, told)


class _ActionRows(Sequence):
    """The compiled builder's edge arrays read as :class:`Commit` and :class:`Reply`."""

    def __init__(self, side, ops, durations, deviations, cost):
        self.side, self.ops, self.durations = side, ops, durations
        self.deviations, self.cost = deviations, cost

    def __len__(self) -> int:
        return int(self.side.shape[0])

    def __getitem__(self, e):
        e = int(e)
        ops = tuple(None if o == -2 else o for o in self.ops[e].tolist())
        if self.side[e] == ROBOT:
            return Commit(ops=ops)
        durs = tuple(None if d == -2 else d for d in self.durations[e].tolist())
        return Reply(
            ops=ops, durations=durs, deviations=int(self.deviations[e]), delta=int(self.cost[e])
        )


def _build_python(model: ConcurrentModel, levels, max_nodes, too_big, progress):
    """The Python builder: a depth-first search over the game's nodes (dict of tuples)."""
    nw = len(model.workers)
    idle = tuple((WAIT, 0) for _ in range(nw))
    index: dict = {}
    nodes: list = []
    src, dst, cost, side, actions = [], [], [], [], []
    end_key = ("E", -1, (), 0, ())

    def node(key) -> int:
        v = index.get(key)
        if v is None:
            v = len(nodes)
            if v >= max_nodes:
                raise too_big
            index[key] = v
            nodes.append(key)
            todo.append(v)
        return v

    todo: list[int] = []
    starts = {b: node(("R", 0, idle, b, ())) for b in levels}
    node(end_key)
    while todo:
        v = todo.pop()
        key = nodes[v]
        if key[0] == "R":
            for commit, target in _robot_moves(model, key):
                src.append(v)
                dst.append(node(target))
                cost.append(0)
                side.append(ROBOT)
                actions.append(commit)
        elif key[0] == "H":
            seen = set()
            for reply, target in _human_moves(model, key):
                t = node(target) if target != end_key else index[end_key]
                if (t, reply.delta) in seen:
                    continue
                seen.add((t, reply.delta))
                src.append(v)
                dst.append(t)
                cost.append(reply.delta)
                side.append(HUMAN)
                actions.append(reply)
        if progress and len(nodes) % 200_000 == 0:
            print(f"  concurrent game: {len(nodes):,} nodes ...", file=sys.stderr)
    src_a = np.array(src, dtype=np.int64)
    order = np.argsort(src_a, kind="stable")
    acts = [actions[i] for i in order]
    return (
        nodes,
        acts,
        starts,
        index[end_key],
        src_a[order],
        np.array(dst, dtype=np.int64)[order],
        np.array(cost, dtype=np.int64)[order],
        np.array(side, dtype=np.int8)[order],
    )


def _edge_ops(model: ConcurrentModel, action) -> str:
    ids = model.spec.op_ids
    parts = [ids[o] for o in action.ops if o is not None and o != WAIT]
    return ",".join(parts) if parts else "wait"


def _edge_agents(model: ConcurrentModel, action) -> str:
    return ",".join(
        model.workers[w].name for w, o in enumerate(action.ops) if o is not None and o != WAIT
    )


def _assignments(model: ConcurrentModel, state: int, deciders: list[int], busy: tuple[int, ...]):
    """Every joint choice of an operation or :data:`WAIT` for the workers ``deciders`` in
    ``state``: operations they may do, distinct, and compatible with ``busy`` and each other."""
    out: list[tuple[int, ...]] = []

    def extend(i: int, chosen: list[int], ops: tuple[int, ...]) -> None:
        if i == len(deciders):
            out.append(tuple(chosen))
            return
        w = deciders[i]
        chosen.append(WAIT)
        extend(i + 1, chosen, ops)
        chosen.pop()
        for o in model.enabled[state]:
            if model.choices[w][o] and o not in ops:
                new = tuple(sorted((*ops, o)))
                if model.compatible(state, new):
                    chosen.append(o)
                    extend(i + 1, chosen, new)
                    chosen.pop()

    extend(0, [], busy)
    return out


def _robot_moves(model: ConcurrentModel, key):
    """Every commitment of the robot side at robot node ``key`` and the human node it makes."""
    _, state, running, budget, _ = key
    busy = tuple(o for o, _ in running if o != WAIT)
    free_r = [w for w in model.robots if running[w][0] == WAIT]
    free_h = [w for w in model.humans if running[w][0] == WAIT]
    instruct = budget != UNBOUNDED
    deciders = free_r + (free_h if instruct else [])
    out = [dict(zip(deciders, c, strict=True)) for c in _assignments(model, state, deciders, busy)]
    moves = []
    for chosen in out:
        started = [w for w in free_r if chosen[w] != WAIT]
        something = bool(busy) or bool(started)
        if instruct:
            something = something or any(chosen[w] != WAIT for w in free_h)
        else:
            now = tuple(sorted((*busy, *(chosen[w] for w in started))))
            something = something or any(model.candidates(state, w, now) for w in free_h)
        if not something:
            continue
        new_running = list(running)
        for w in started:
            (d,) = model.duration_choices(w, chosen[w], state)
            new_running[w] = (chosen[w], d)
        instr = tuple(chosen[w] for w in free_h) if instruct else ()
        ops = tuple(chosen.get(w) if w in chosen else None for w in range(len(model.workers)))
        moves.append((Commit(ops=ops), ("H", state, tuple(new_running), budget, instr)))
    return moves


def _human_moves(model: ConcurrentModel, key):
    """Every reply of the human side at human node ``key`` and the robot node after it."""
    _, state, running, budget, instr = key
    free_h = [w for w in model.humans if running[w][0] == WAIT]
    told = dict(zip(free_h, instr, strict=False)) if budget != UNBOUNDED else {}
    busy = tuple(o for o, _ in running if o != WAIT)
    picks = _assignments(model, state, free_h, busy)
    moves = []
    for chosen in picks:
        deviations = sum(
            1 for w, o in zip(free_h, chosen, strict=True) if w in told and told[w] != o
        )
        if budget != UNBOUNDED and deviations > budget:
            continue
        final = tuple(sorted((*busy, *(o for o in chosen if o != WAIT))))
        idle_ok = True
        for w, o in zip(free_h, chosen, strict=True):
            following = w in told and told[w] == WAIT
            if o == WAIT and not following and model.candidates(state, w, final):
                idle_ok = False
                break
        if not idle_ok or not final:
            continue
        started = [(w, o) for w, o in zip(free_h, chosen, strict=True) if o != WAIT]
        grids = [model.duration_choices(w, o, state) for w, o in started]
        for durs in _product(grids):
            new_running = list(running)
            for (w, o), d in zip(started, durs, strict=True):
                new_running[w] = (o, d)
            delta = min(r for o, r in new_running if o != WAIT)
            done = []
            for w, (o, r) in enumerate(new_running):
                if o != WAIT:
                    if r == delta:
                        done.append(o)
                        new_running[w] = (WAIT, 0)
                    else:
                        new_running[w] = (o, r - delta)
            new_state = model.after(state, sorted(done))
            left = budget if budget == UNBOUNDED else budget - deviations
            if model.complete[new_state] and all(o == WAIT for o, _ in new_running):
                target = ("E", -1, (), 0, ())
            else:
                target = ("R", new_state, tuple(new_running), left, ())
            ops = [None] * len(model.workers)
            dd = [None] * len(model.workers)
            for w, o in zip(free_h, chosen, strict=True):
                ops[w] = o
            for (w, _), d in zip(started, durs, strict=True):
                dd[w] = d
            reply = Reply(ops=tuple(ops), durations=tuple(dd), deviations=deviations, delta=delta)
            moves.append((reply, target))
    return moves


def _product(grids):
    if not grids:
        yield ()
        return
    first, rest = grids[0], grids[1:]
    for d in first:
        for tail in _product(rest):
            yield (d, *tail)


# --------------------------------------------------------------------------- solving


@dataclass(frozen=True, eq=False)
class Robustness:
    """The price of robustness: ``W*(k)`` for ``k = 0..K`` and ``W*(inf)``.

    Attributes
    ----------
    bounds : tuple of float
        ``W*(0), W*(1), ..., W*(K)``: at least up to ``k = 2`` and up to a ``k`` with
        ``W*(k) == W*(inf)`` (budgets double until then), or ``max_k``.
    unbounded : float
        ``W*(inf)``, the fully adversarial bound.
    game, solution : ConcurrentGame, Solution
        The game with budgets ``0..K`` and its exact solution: the robust plan is its policy
        from the start of budget ``K`` (it guarantees ``W*(K)`` against any person who
        deviates at most ``K`` times; ``W*(K) == W*(inf)`` when ``flat``).
    adversary, adversary_solution : ConcurrentGame, Solution
        The unbounded game and its solution.
    flat : bool
        Whether ``W*(K) == W*(inf)`` (else ``max_k`` stopped the curve).
    """

    bounds: tuple[float, ...]
    unbounded: float
    game: ConcurrentGame
    solution: Solution
    adversary: ConcurrentGame
    adversary_solution: Solution
    flat: bool
    seconds: float

    @property
    def k(self) -> int:
        """The largest budget of the curve (the robust plan's)."""
        return len(self.bounds) - 1

    def to_list(self) -> list[dict]:
        """``[{"k": 0, "bound": ...}, ..., {"k": None, "bound": W*(inf)}]``."""
        out = [{"k": k, "bound": json_number(b, 6)} for k, b in enumerate(self.bounds)]
        return [*out, {"k": None, "bound": json_number(self.unbounded, 6)}]


def value(game: ConcurrentGame, solution: Solution, budget: int) -> float:
    """``W*(budget)``: the game value at the start node of ``budget``."""
    return float(solution.value[game.starts[budget], ROBOT])


def robustness(
    model: ConcurrentModel,
    *,
    max_k: int = DEFAULT_MAX_K,
    max_nodes: int = DEFAULT_MAX_NODES,
    progress: bool = False,
) -> Robustness:
    """Solve the concurrent game exactly for ``k = 0, 1, ...`` until ``W*(k) == W*(inf)``.

    The curve is non-decreasing and bounded by ``W*(inf)``, which it reaches once the budget
    covers every human decision. Budgets double (2, 4, 8, ...) until the curve is flat;
    ``max_k`` bounds the search, and so does ``max_nodes``: a doubled game over the limit
    leaves the curve as it was (``flat`` False). The first game over the limit is an error
    naming ``--max-k``.
    """
    if max_k < 0:
        raise GameError(f"max_k: expected a deviation budget >= 0, got {max_k}")
    t0 = time.perf_counter()
    adversary = build_game(model, None, max_nodes=max_nodes, progress=progress)
    adv_sol = solve(adversary.dag)
    top = float(adv_sol.value[adversary.starts[UNBOUNDED], ROBOT])
    if progress:
        print(
            f"concurrent game, unbounded adversary: {adversary.dag.n_nodes:,} nodes, "
            f"{adversary.dag.n_edges:,} edges, W*(inf) = {top:g} ({adversary.seconds:.2f} s)",
            file=sys.stderr,
        )
    k = min(2, max_k)
    game = None
    while True:
        try:
            bigger = build_game(model, k, max_nodes=max_nodes, progress=progress)
        except GameError:
            if game is None:
                raise
            break  # the curve so far stands; ``flat`` stays False and the report says so
        game = bigger
        sol = solve(game.dag)
        bounds = [value(game, sol, b) for b in range(k + 1)]
        if progress:
            print(
                f"concurrent game, budgets 0..{k}: {game.dag.n_nodes:,} nodes, "
                f"{game.dag.n_edges:,} edges ({game.seconds:.2f} s)",
                file=sys.stderr,
            )
        flat = _same(bounds[-1], top)
        if flat or k >= max_k:
            break
        k = min(2 * k, max_k)
    return Robustness(
        bounds=tuple(bounds),
        unbounded=top,
        game=game,
        solution=sol,
        adversary=adversary,
        adversary_solution=adv_sol,
        flat=flat,
        seconds=time.perf_counter() - t0,
    )


def _same(a: float, b: float) -> bool:
    return bool(costs_close(a, b))


# --------------------------------------------------------------------------- policies

RobotRule = Callable[[ConcurrentGame, int, list[int]], int]
"""A robot policy as a rule: ``(game, robot node, its edge indices) -> the edge taken``."""


def policy_array(game: ConcurrentGame, rule: RobotRule) -> np.ndarray:
    """(n,) int64 edge per robot node of a robot policy given as a rule."""
    dag = game.dag
    out = np.full(dag.n_nodes, -1, dtype=np.int64)
    for v, key in enumerate(game.nodes):
        if key[0] == "R":
            edges = list(dag.out_edges(v))
            if edges:
                out[v] = rule(game, v, edges)
    return out


def certified_worst_case(game: ConcurrentGame, policy, budget: int | None = None) -> float:
    """The exact worst-case makespan of a robot policy against a best-response human.

    Parameters
    ----------
    policy : (n,) int array of robot edges, or a :data:`RobotRule`
    budget : int, optional
        The start's budget (default: the game's largest, or unbounded).
    """
    if callable(policy):
        policy = policy_array(game, policy)
    b = game.budgets[-1] if budget is None else (UNBOUNDED if game.unbounded else int(budget))
    evaluation = evaluate_policy(game.dag, policy)
    return float(evaluation.worst[game.starts[b], ROBOT])


def schedule_rule(rows: list[dict]) -> RobotRule:
    """The robot policy of a fixed schedule (a plan that ignores what the person does).

    ``rows`` are ``{"task", "agent", "start"}`` (a CP-SAT schedule). Each worker keeps the
    list of its operations in start order and wants the first one not yet done or running
    (the person is told it). At an event the rule takes the commitment in which every free
    worker does what it wants, if that is valid; otherwise (a deviation made the wanted
    operation impossible for now) the valid commitment with the most workers as wanted,
    ties by edge order: the schedule has no answer there, it keeps as much of it as it can.
    """
    order: dict[str, list[str]] = {}
    for row in sorted(rows, key=lambda r: (r["start"], r["task"])):
        order.setdefault(str(row["agent"]), []).append(str(row["task"]))

    def rule(game: ConcurrentGame, v: int, edges: list[int]) -> int:
        model = game.model
        _, state, running, budget, _ = game.nodes[v]
        done = model.graph.key(state)
        busy = {o for o, _ in running if o != WAIT}
        ids = model.spec.op_ids
        want = []
        for w, x in enumerate(model.workers):
            if running[w][0] != WAIT or (x.side == HUMAN and budget == UNBOUNDED):
                want.append(None)
                continue
            nxt = WAIT
            for oid in order.get(x.name, []):
                i = ids.index(oid)
                if not done >> i & 1 and i not in busy:
                    nxt = i
                    break
            want.append(nxt)
        # The closest valid commitment: most workers as wanted, ties by edge order.
        best, best_score = edges[0], -1
        for e in edges:
            ops = game.actions[e].ops
            score = sum(1 for w in range(len(want)) if want[w] is not None and ops[w] == want[w])
            exact = all(want[w] is None or ops[w] == want[w] for w in range(len(want)))
            score += 1000 * exact
            if score > best_score:
                best, best_score = e, score
        return best

    return rule


# --------------------------------------------------------------------------- reading


def state_description(game: ConcurrentGame, v: int) -> dict:
    """The state of node ``v`` as the plan file and the runtime advisor name it.

    Returns
    -------
    dict
        ``{"done": [op ids], "tools": {name: value}, "running": [{"agent", "operation",
        "remaining"}], "budget": k or None, "turn": "robot" | "human" | "end"}``; a human
        node also has ``"instructions": {human: op id or "wait"}``.
    """
    model = game.model
    kind, state, running, budget, instr = game.nodes[v]
    if kind == "E":
        spec = model.spec
        return {
            "done": list(spec.op_ids),
            "tools": {},
            "running": [],
            "budget": None,
            "turn": "end",
        }
    key = model.graph.key(state)
    ids = model.spec.op_ids
    out = {
        "done": model.graph.model.done_ops(key),
        "tools": model.graph.model.tool_state(key),
        "running": [
            {
                "agent": model.workers[w].name,
                "operation": ids[o],
                "remaining": json_number(model.time(r), 6),
            }
            for w, (o, r) in enumerate(running)
            if o != WAIT
        ],
        "budget": None if budget == UNBOUNDED else budget,
        "turn": "robot" if kind == "R" else "human",
    }
    if kind == "H" and budget != UNBOUNDED:
        free_h = [w for w in model.humans if running[w][0] == WAIT]
        # Robots committed at this node are already running; the free humans are told.
        out["instructions"] = {
            model.workers[w].name: ("wait" if o == WAIT else ids[o])
            for w, o in zip(free_h, instr, strict=False)
        }
    return out


def commit_description(game: ConcurrentGame, e: int) -> dict:
    """A robot edge as ``{"start": {robot: op id}, "wait": [robots], "instruct": {human: op
    id or "wait"}}``."""
    model = game.model
    ids = model.spec.op_ids
    action = game.actions[e]
    out: dict = {"start": {}, "wait": [], "instruct": {}}
    for w, o in enumerate(action.ops):
        if o is None:
            continue
        name = model.workers[w].name
        if model.workers[w].side == ROBOT:
            if o == WAIT:
                out["wait"].append(name)
            else:
                out["start"][name] = ids[o]
        else:
            out["instruct"][name] = "wait" if o == WAIT else ids[o]
    return out


def move_starts(game: ConcurrentGame, e: int) -> tuple[list[tuple[str, str, float]], int]:
    """The operations edge ``e`` starts and the deviations it costs.

    Returns
    -------
    starts : list of (op id, worker name, duration)
        A robot edge: the robots' operations (their durations with any tool change); a human
        edge: the humans' operations with the durations the human side picked.
    deviations : int
        Deviations from the instructions (0 for a robot edge).
    """
    model = game.model
    ids = model.spec.op_ids
    action = game.actions[e]
    if isinstance(action, Commit):
        running = game.nodes[int(game.dag.targets[e])][2]
        starts = [
            (ids[o], model.workers[w].name, model.time(running[w][1]))
            for w, o in enumerate(action.ops)
            if o is not None and o != WAIT and model.workers[w].side == ROBOT
        ]
        return starts, 0
    starts = [
        (ids[o], model.workers[w].name, model.time(action.durations[w]))
        for w, o in enumerate(action.ops)
        if o is not None and o != WAIT
    ]
    return starts, int(action.deviations)


@dataclass(frozen=True)
class Bar:
    """One operation on the time axis: who did it, when, and whether it was a deviation."""

    agent: str
    operation: str
    start: float
    end: float
    deviation: bool = False


def timeline(game: ConcurrentGame, robot_policy: np.ndarray, human: str = "worst", budget=None):
    """Play a robot policy from a start and return the bars and the makespan.

    Parameters
    ----------
    human : {"worst", "follow"}
        ``worst``: the exact best-response human (deviations marked); ``follow``: the person
        does what it is told, and of the durations its range allows takes the worst.
    budget : int, optional
        The start's budget (default: the game's largest).
    """
    dag = game.dag
    model = game.model
    b = game.budgets[-1] if budget is None else int(budget)
    worst = evaluate_policy(dag, robot_policy).worst
    v, t = game.starts[b], 0
    bars: list[Bar] = []
    open_: dict[int, tuple[int, int, bool]] = {}  # worker -> (op, start, deviation)
    instructions: tuple = ()
    ids = model.spec.op_ids
    while v != dag.end:
        kind, state, running, budget_left, _ = game.nodes[v]
        if kind == "R":
            e = int(robot_policy[v])
            action = game.actions[e]
            for w, o in enumerate(action.ops):
                if o is not None and o != WAIT and model.workers[w].side == ROBOT:
                    open_[w] = (o, t, False)
            instructions = action.ops
        else:
            edges = list(dag.out_edges(v))
            if human == "follow":
                edges = [e for e in edges if game.actions[e].deviations == 0] or edges
            e = max(edges, key=lambda e: (dag.costs[e] + worst[dag.targets[e], ROBOT], -e))
            action = game.actions[e]
            for w, o in enumerate(action.ops):
                if o is not None and o != WAIT:
                    told = instructions[w] if w < len(instructions) else None
                    dev = budget_left != UNBOUNDED and told is not None and told != o
                    open_[w] = (o, t, dev)
            t += action.delta
            nxt = game.nodes[int(dag.targets[e])]
            now_running = nxt[2] if nxt[0] == "R" else ()
            for w in list(open_):
                if not now_running or now_running[w][0] == WAIT:
                    o, s, dev = open_.pop(w)
                    bars.append(
                        Bar(model.workers[w].name, ids[o], model.time(s), model.time(t), dev)
                    )
        v = int(dag.targets[e])
    bars.sort(key=lambda x: (x.start, x.agent))
    return bars, model.time(t)


# --------------------------------------------------------------------------- CP-SAT


def assembly_makespan(
    spec,
    graph,
    *,
    time_limit: float | None = 60.0,
    workers: int = 1,
    seed: int = 0,
    sequence: Sequence[str] | None = None,
    patience: float | None = None,
    fixed_order: bool = True,
) -> tuple[AssemblySchedule, BaselineResult]:
    """The minimum-makespan schedule of an assembly that respects the state graph.

    Exact by lazy cuts: CP-SAT solves the schedule with the precedences the state graph
    implies (:func:`asp.baseline.assembly_schedule`); each schedule it finds is replayed
    through the state graph (:func:`asp.baseline.schedule_violation`, the concurrent game's
    rule); one that fails adds its cut and CP-SAT solves again (:func:`asp.baseline.min_makespan`).
    Cuts only remove infeasible schedules, so a solve that proves no shorter schedule with
    every cut makes the best passing one ``OPTIMAL``.

    It starts from a list schedule along a path of the state graph
    (:func:`asp.baseline.list_schedule`, greedy, and along ``sequence`` too when given, e.g.
    the robust plan's principal line; the shorter one): physically feasible by
    construction, it is CP-SAT's hint and the fallback. So on a large state graph, where
    CP-SAT cannot prove an optimum in ``time_limit``, the result is still a replayed
    schedule, with status ``FEASIBLE`` and the proven lower bound. ``detail`` holds
    ``cuts``, ``solves``, ``replay``, ``found_by``, ``improvements`` and ``stage_s`` (the
    whole call, seconds).

    Parameters
    ----------
    time_limit : float or None
        Seconds for the CP-SAT loop (after the precedences, the replay tables and the list
        schedules are built). ``None``: the automatic budget, :data:`AUTO_TIME_LIMIT` seconds
        for the whole call, preparation included, with ``patience`` defaulting to
        :data:`AUTO_PATIENCE`.
    patience : float, optional
        Stop once neither a better schedule nor a new cut has come for this many seconds
        (:func:`asp.baseline.min_makespan`).
    fixed_order : bool
        On a graph whose alike operations are in a fixed order (the alternating game's
        reduction), undo it (:mod:`asp.fixed_order`): the schedules of the full graph, alike
        operations at once and in any order. ``False``: the order kept (a conservative
        makespan; for comparison).
    """
    t0 = time.perf_counter()
    if time_limit is None and patience is None:
        patience = AUTO_PATIENCE
    sched = assembly_schedule(spec, graph, fixed_order=fixed_order)
    model = replay_model(spec, graph, fixed_order=fixed_order)

    def replay(rows):
        found = schedule_violation(model, rows)
        return None if found is None else found[1]

    index = {oid: i for i, oid in enumerate(spec.op_ids)}

    def more_cuts(rows):
        start, end = [0.0] * len(index), [0.0] * len(index)
        for r in rows:
            start[index[r["task"]]], end[index[r["task"]]] = float(r["start"]), float(r["end"])
        return model.cuts.early(start, end)

    starts = [list_schedule(model, sched.problem)]
    if sequence is not None:
        starts.append(list_schedule(model, sched.problem, sequence))
    starts = [rows for rows in starts if rows]
    incumbent = min(starts, key=lambda rows: max(float(r["end"]) for r in rows), default=None)
    limit = time_limit
    if limit is None:  # the budget covers the preparation too (at least a moment for CP-SAT)
        limit = max(AUTO_TIME_LIMIT - (time.perf_counter() - t0), MIN_SOLVE_S)
    result = min_makespan(
        sched.problem,
        time_limit=limit,
        workers=workers,
        seed=seed,
        replay=replay,
        incumbent=incumbent,
        patience=patience,
        more_cuts=more_cuts if model.cuts.combined else None,  # positive durations (asp.cuts)
    )
    result.detail["stage_s"] = round(time.perf_counter() - t0, 3)
    return sched, result
