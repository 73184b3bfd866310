"""The classical baseline with OR-Tools CP-SAT (``../shared/DESIGN.md``, "The classical baseline").

Two models, each laid out as in the CP-SAT examples (data, model, variables, constraints,
objective, solve):

(a) :func:`min_cost_path`: the minimum-cost way through a game DAG, a unit flow with one
    boolean per arc. On a DAG whose edges are all ``ANY`` the arcs are the DAG's edges and
    the optimum is the TCT. With ``ROBOT``/``HUMAN`` edges the path runs over game states
    ``(node, player on turn)``: an edge open to the player on turn flips the turn, and a
    player without a move passes at zero cost (a forced move), so the optimum is the
    cooperative value ``solve(dag).tct`` under the alternating turn model.

(b) :func:`min_makespan`: the minimum-makespan schedule when agents work in parallel: an
    optional interval per (task, allowed agent) with exactly one present, no overlap per
    agent, precedence as ``end <= start``, renewable resources as cumulative constraints
    (PSPLIB) and tool states as sequence-dependent setups (see :func:`min_makespan`).

CP-SAT works on integers: costs and durations are scaled by the smallest power of ten
(up to 10**6) that makes them integral, and scaled back in the results.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numba
import numpy as np

from asp import rules
from asp.dag import GameDAG
from asp.errors import ScheduleError
from asp.feasibility import WORD_BITS
from asp.numbers import json_number, plain
from asp.rules import HUMAN, ROBOT
from asp.together import OK, TOOL, first_failure

MAX_SCALE_DIGITS = 6


@dataclass(frozen=True)
class Task:
    """A task to schedule.

    Attributes
    ----------
    id, description : str
    modes : tuple of (agent, duration)
        Who may do it and how long it takes; agent ``""`` uses no agent (PSPLIB jobs).
    demands : tuple of int
        Demand on each renewable resource of the problem (same order).
    requires, sets : tuple of (tool, value)
        Tool state needed during the task / left after it.
    """

    id: str
    modes: tuple[tuple[str, float], ...]
    demands: tuple[int, ...] = ()
    requires: tuple[tuple[str, str], ...] = ()
    sets: tuple[tuple[str, str], ...] = ()
    description: str = ""


@dataclass(frozen=True)
class ScheduleProblem:
    """Tasks, precedences ``(before, after)`` (task indices), resources and tool states.

    ``start_order`` (task index pairs ``(a, b)``: ``start[a] <= start[b]``) breaks the
    symmetry of interchangeable tasks (:meth:`asp.fixed_order.FixedOrder.start_order`).
    """

    name: str
    tasks: tuple[Task, ...]
    precedences: tuple[tuple[int, int], ...] = ()
    resources: tuple[tuple[str, int], ...] = ()
    tool_initial: tuple[tuple[str, str], ...] = ()
    credit: str = ""
    start_order: tuple[tuple[int, int], ...] = ()


@dataclass(frozen=True)
class BaselineResult:
    """Outcome of a CP-SAT solve.

    Attributes
    ----------
    kind : str
        ``"path"`` or ``"schedule"``.
    status : str
        CP-SAT status name (``OPTIMAL``, ``FEASIBLE``, ``INFEASIBLE``, ``UNKNOWN``, ...).
    objective, bound : float or None
        Best objective found and the proven bound (original units).
    wall_s : float
        Wall time of the solve, seconds.
    detail : dict
        ``path`` (node ids) and ``edges`` for a path; ``schedule`` (one dict per task with
        ``task, agent, start, end``) and the lower bounds for a schedule.
    """

    kind: str
    name: str
    status: str
    objective: float | None
    bound: float | None
    wall_s: float
    detail: dict = field(default_factory=dict)
    credit: str = ""

    def to_dict(self) -> dict:
        out = {
            "kind": self.kind,
            "name": self.name,
            "status": self.status,
            "objective": json_number(_significant(self.objective)),
            "bound": json_number(_significant(self.bound)),
            "wall_s": round(self.wall_s, 3),
        }
        out.update(self.detail)
        if self.credit:
            out["credit"] = self.credit
        return out


def _significant(x, digits: int = 12):
    """``x`` to ``digits`` significant digits (a tiny cost stays visible, unlike round(x, 6))."""
    return None if x is None else float(f"{float(x):.{digits}g}")


EXACT_HEADROOM = 2**53
"""Scaled sums stay below this: integers there are exact in float64 and well inside CP-SAT's
int64."""


def exact_scale(values, n_terms: int) -> tuple[int, bool]:
    """The power of ten making every value an integer, as CP-SAT needs, and whether it is exact.

    The smallest ``10**k`` that makes every value integral (to the relative cost tolerance,
    :data:`asp.rules.COST_TOL`; a nonzero value never becomes 0) while
    ``n_terms`` of the largest value, scaled, stay within :data:`EXACT_HEADROOM`; if none
    does, the largest such scale and ``False``: the values are then rounded to ``1 / scale``.
    """
    arr = np.abs(np.asarray(values, dtype=np.float64))
    top = float(arr.max()) if arr.size else 0.0
    best = 1
    for k in range(19):
        scale = 10**k
        if k and top * scale * max(n_terms, 1) > EXACT_HEADROOM:
            break
        best = scale
        scaled = arr * scale
        if np.all(np.abs(scaled - np.round(scaled)) <= rules.COST_TOL * scaled):
            return scale, True
    return best, False


def integer_scale(values) -> int:
    """Smallest power of ten (<= 10**6) making every value integral (else 10**6, rounded)."""
    arr = np.asarray(list(values), dtype=np.float64)
    for k in range(MAX_SCALE_DIGITS + 1):
        scaled = arr * 10**k
        if np.all(
            np.abs(scaled - np.round(scaled)) <= rules.COST_TOL * np.maximum(1.0, np.abs(scaled))
        ):
            return 10**k
    return 10**MAX_SCALE_DIGITS


def _solver(time_limit: float, workers: int, seed: int):
    from ortools.sat.python import cp_model

    if workers < 1:
        raise ScheduleError(f"workers: expected a positive integer, got {workers}")
    if not time_limit > 0:
        raise ScheduleError(f"time_limit: expected a positive number of seconds, got {time_limit}")
    solver = cp_model.CpSolver()
    solver.parameters.max_time_in_seconds = float(time_limit)
    solver.parameters.num_workers = int(workers)
    solver.parameters.random_seed = int(seed)
    return solver


def _status(solver, status) -> tuple[str, bool]:
    from ortools.sat.python import cp_model

    return solver.status_name(status), status in (cp_model.OPTIMAL, cp_model.FEASIBLE)


# --------------------------------------------------------------------------- (a) path


def path_arcs(dag: GameDAG) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, int, list]:
    """The arcs the path model runs over.

    Returns
    -------
    tail, head : (a,) int64
        Arc end points: node indices when every edge is ``ANY``, else game states
        ``2 * node + player``.
    cost : (a,) float64
    edge : (a,) int64
        The DAG edge of each arc, or -1 for a pass.
    source : int
        The start (state).
    sinks : list of int
        The end node (or its two game states).
    """
    src = dag.sources
    move_cost = rules.move_costs(dag)
    may = rules.move_masks(dag)
    if dag.n_edges == 0 or np.all(may.all(axis=0)):  # every edge open to both: no turns
        return (
            src,
            dag.targets.copy(),
            move_cost.copy(),
            np.arange(dag.n_edges, dtype=np.int64),
            dag.start,
            [dag.end],
        )
    tails, heads, costs, edges = [], [], [], []
    can_move = rules.has_move(dag)
    for p in rules.PLAYERS:
        e = np.flatnonzero(may[p])
        tails.append(2 * src[e] + p)
        heads.append(2 * dag.targets[e] + rules.other(p))
        costs.append(move_cost[e])
        edges.append(e)
        passing = np.flatnonzero(~can_move[p])
        passing = passing[passing != dag.end]
        tails.append(2 * passing + p)
        heads.append(2 * passing + rules.other(p))
        costs.append(np.full(passing.size, rules.PASS_COST))
        edges.append(np.full(passing.size, rules.PASS, dtype=np.int64))
    return (
        np.concatenate(tails),
        np.concatenate(heads),
        np.concatenate(costs),
        np.concatenate(edges),
        2 * dag.start + rules.FIRST_PLAYER,
        [2 * dag.end + ROBOT, 2 * dag.end + HUMAN],
    )


def min_cost_path(
    dag: GameDAG, *, time_limit: float = 60.0, workers: int = 1, seed: int = 0
) -> BaselineResult:
    """Minimum-cost path from start to end of a game DAG with CP-SAT.

    Equals ``asp.solve.solve(dag).tct`` (the cooperative value under the turn model).
    """
    from ortools.sat.python import cp_model

    name = str(dag.metadata.get("assembly", dag.metadata.get("source", "game DAG")))
    credit = str(dag.metadata.get("credit", ""))
    if dag.start == dag.end:  # nothing to do: the empty path, cost 0
        detail = {"arcs": 0, "scale": 1, "path": [plain(dag.node_ids[dag.start])], "edges": []}
        if dag.operations is not None:
            detail["operations"] = []
        return BaselineResult("path", name, "OPTIMAL", 0.0, 0.0, 0.0, detail, credit)

    # Data: the arcs (DAG edges, or game-state moves and passes) and integer costs, scaled
    # exactly when int64 allows (else rounded, and the result says so).
    tail, head, cost, edge, source, sinks = path_arcs(dag)
    scale, exact = exact_scale(cost, tail.size)
    icost = np.round(cost * scale).astype(np.int64)

    # Model.
    model = cp_model.CpModel()

    # Variables: use[a] is true iff the path takes arc a.
    use = [model.new_bool_var(f"use_{a}") for a in range(tail.size)]

    # Constraints: a unit of flow leaves the source, reaches one sink and is conserved
    # everywhere else. The arc graph is acyclic (passes only where a player has no move,
    # and then the other player has one), so the flow is a simple path.
    out_arcs: dict[int, list[int]] = {}
    in_arcs: dict[int, list[int]] = {}
    for a, (u, v) in enumerate(zip(tail.tolist(), head.tolist(), strict=True)):
        out_arcs.setdefault(u, []).append(a)
        in_arcs.setdefault(v, []).append(a)
    sink_set = set(sinks)
    for u in set(out_arcs) | set(in_arcs):
        if u in sink_set:
            continue
        outflow = sum(use[a] for a in out_arcs.get(u, []))
        inflow = sum(use[a] for a in in_arcs.get(u, []))
        model.add(outflow - inflow == (1 if u == source else 0))
    model.add(sum(use[a] for s in sinks for a in in_arcs.get(s, [])) == 1)

    # Objective: total cost of the arcs taken.
    model.minimize(sum(int(c) * x for c, x in zip(icost.tolist(), use, strict=True)))

    # Solve.
    solver = _solver(time_limit, workers, seed)
    t0 = time.perf_counter()
    status = solver.solve(model)
    wall = time.perf_counter() - t0
    status_name, found = _status(solver, status)
    detail: dict = {"arcs": int(tail.size), "scale": scale}
    if not exact:
        detail["rounded"] = True  # costs rounded to 1/scale: optimality is up to that rounding
    objective = bound = None
    if found:
        taken = {int(tail[a]): a for a in range(tail.size) if solver.boolean_value(use[a])}
        # The objective is the exact cost of the path found (the float costs, summed).
        objective = math.fsum(float(cost[a]) for a in taken.values())
        bound = min(solver.best_objective_bound / scale, objective)
        state, nodes, edges = source, [], []
        game_states = len(sinks) == 2
        while state not in sink_set:
            a = taken[state]
            node = state // 2 if game_states else state
            if edge[a] >= 0:
                nodes.append(dag.node_ids[node])
                edges.append(int(edge[a]))
            state = int(head[a])
        nodes.append(dag.node_ids[dag.end])
        detail.update(path=[plain(x) for x in nodes], edges=edges)
        if dag.operations is not None:
            detail["operations"] = [dag.edge_label(e) for e in edges]
    return BaselineResult(
        kind="path",
        name=name,
        status=status_name,
        objective=objective,
        bound=bound,
        wall_s=wall,
        detail=detail,
        credit=credit,
    )


# --------------------------------------------------------------------------- (b) schedule


def min_makespan(
    problem: ScheduleProblem,
    *,
    time_limit: float = 60.0,
    workers: int = 1,
    seed: int = 0,
    replay=None,
    incumbent: list[dict] | None = None,
    patience: float | None = None,
    more_cuts=None,
) -> BaselineResult:
    """Minimum-makespan schedule with CP-SAT.

    ``replay`` (optional) checks a schedule: ``replay(rows)`` returns ``None`` when the
    schedule is physically feasible, else a cut, a list of ``(y, x)`` task-index pairs of
    which at least one must become a precedence (``end[y] <= start[x]``) in every feasible
    schedule. Every solution CP-SAT finds is replayed as it comes; the first that fails
    stops the solve, its cut is added (a lazy constraint) and CP-SAT solves again, hinted
    with the best schedule that passed and bound to beat it (:class:`_ReplayLoop`). A
    schedule that does not pass is never reported. The status is ``OPTIMAL`` only when a
    solve with every cut proves that no shorter schedule exists; ``FEASIBLE`` is the best
    schedule that passed within ``time_limit`` (``bound`` is then a proven lower bound).

    ``incumbent`` (optional): rows ``{"task", "agent", "start", "end"}`` of a schedule to
    start from, e.g. :func:`list_schedule` along a state-graph path (replayed like any
    other; kept only if it passes). With it a result never lacks a schedule.
    ``detail["found_by"]`` says which schedule is reported (``CP-SAT`` or the incumbent's
    source), ``detail["cuts"]`` and ``detail["solves"]`` how the loop went,
    ``detail["improvements"]`` when each better schedule came (``[seconds, makespan]``).

    ``more_cuts`` (optional): ``more_cuts(rows)`` of a schedule that failed the replay
    returns further cuts (each a list of pairs as above, each holding for every feasible
    schedule), added with the replay's own, so one solve rules out several faults.

    ``patience`` (optional, seconds): stop once neither a better schedule nor a new cut
    has come for that long (the status is then ``FEASIBLE`` unless proven); ``time_limit``
    still caps the whole loop. Without it the loop runs until proven or ``time_limit``.

    Tool states as sequence-dependent setups: for a tool ``T``, a *setter* is a task that
    sets ``T`` and a *user* a task that requires a value of ``T``. Every setter is ordered
    (a disjunction, one boolean ``before[s, u]``) against every other setter and every user,
    so no tool change overlaps another change or a task that relies on the tool. A user
    ``u`` that needs ``T = v`` sees the value of the last setter that ends before it starts
    (or the initial value if none does), so:

    - if the initial value is not ``v``, some setter of ``v`` ends before ``u`` starts;
    - if a setter ``s`` of another value ends before ``u``, some setter ``s'`` of ``v`` lies
      between them: ``before[s, s'] and before[s', u]``.

    A task that both requires and sets a tool (``R1.bit: hex -> cross``) is a user at its
    start and a setter at its end.
    """
    from ortools.sat.python import cp_model

    # Data: integer durations, the horizon.
    tasks = problem.tasks
    all_durations = [d for t in tasks for _, d in t.modes]
    scale = integer_scale(all_durations) if all_durations else 1
    dur = [[round(d * scale) for _, d in t.modes] for t in tasks]
    horizon = max(1, sum(max(d) for d in dur))
    if horizon > EXACT_HEADROOM:
        raise ScheduleError(
            f"{problem.name}: durations too large for CP-SAT: their sum {horizon / scale:g} "
            f"(in units of 1/{scale}) exceeds 2**53 units"
        )
    if len(problem.resources) and any(len(t.demands) != len(problem.resources) for t in tasks):
        raise ScheduleError(f"{problem.name}: every task needs one demand per resource")

    # Model.
    model = cp_model.CpModel()

    # Variables: start[i], end[i] of task i; present[i][m] true iff task i is done in mode m
    # (by that mode's agent); interval[i][m] the (optional) fixed-size interval of that mode,
    # starting at start[i]. A task of several modes also has one interval of variable size
    # (the chosen mode's duration) that ties end[i] to start[i]. The optional intervals must
    # not share end[i]: OR-Tools 9.15 then proves a wrong optimum (a 3-task job at 4 where 3
    # exists; tests/asp/test_baseline.py::test_modes_of_different_lengths_share_no_end).
    start = [model.new_int_var(0, horizon, f"start_{t.id}") for t in tasks]
    end = [model.new_int_var(0, horizon, f"end_{t.id}") for t in tasks]
    present: list[list] = []
    interval: list[list] = []
    for i, t in enumerate(tasks):
        if len(t.modes) == 1:
            lits = [model.new_constant(1)]
            ivs = [model.new_interval_var(start[i], dur[i][0], end[i], f"iv_{t.id}")]
        else:
            lits = [model.new_bool_var(f"mode_{t.id}_{a}") for a, _ in t.modes]
            ivs = [
                model.new_optional_fixed_size_interval_var(start[i], d, lit, f"iv_{t.id}_{a}")
                for (a, _), d, lit in zip(t.modes, dur[i], lits, strict=True)
            ]
            size = model.new_int_var(min(dur[i]), max(dur[i]), f"size_{t.id}")
            model.add(size == sum(d * lit for d, lit in zip(dur[i], lits, strict=True)))
            model.new_interval_var(start[i], size, end[i], f"iv_{t.id}")
            # Constraint: exactly one mode (agent) does the task.
            model.add_exactly_one(lits)
        present.append(lits)
        interval.append(ivs)

    # Constraints: no overlap per agent.
    by_agent: dict[str, list] = {}
    for i, t in enumerate(tasks):
        for m, (a, _) in enumerate(t.modes):
            if a:
                by_agent.setdefault(a, []).append(interval[i][m])
    for ivs in by_agent.values():
        if len(ivs) > 1:
            model.add_no_overlap(ivs)
    # Redundant: at most one task per agent at any time, all agents together, each task
    # at least its shortest mode long. It gives the solver the pooled-work bound when tasks
    # may go to several agents.
    pooled_work = 0
    if len(by_agent) > 1 and not problem.resources:
        shortest = [
            model.new_fixed_size_interval_var(start[i], min(dur[i]), f"min_{t.id}")
            for i, t in enumerate(tasks)
        ]
        model.add_cumulative(shortest, [1] * len(tasks), len(by_agent))
        pooled_work = -(-sum(min(d) for d in dur) // len(by_agent))

    # Constraints: precedence, end <= start.
    for a, b in problem.precedences:
        model.add(end[a] <= start[b])
    # Constraints: interchangeable tasks start in order (symmetry breaking).
    for a, b in problem.start_order:
        model.add(start[a] <= start[b])

    # Constraints: renewable resources (cumulative).
    for r, (_, capacity) in enumerate(problem.resources):
        ivs = [interval[i][0] for i, t in enumerate(tasks) if t.demands[r] > 0]
        demands = [t.demands[r] for t in tasks if t.demands[r] > 0]
        if ivs:
            model.add_cumulative(ivs, demands, capacity)

    # Constraints: tool states (sequence-dependent setups, see the docstring).
    _tool_constraints(model, problem, start, end)

    # Objective: the makespan.
    makespan = model.new_int_var(min(pooled_work, horizon), horizon, "makespan")
    model.add_max_equality(makespan, end)
    model.minimize(makespan)

    # Solve, replay, cut (see the docstring).
    loop = _ReplayLoop(
        model=model,
        tasks=tasks,
        scale=scale,
        start=start,
        end=end,
        present=present,
        makespan=makespan,
        replay=replay,
        more_cuts=more_cuts,
    )
    if incumbent:
        loop.offer(incumbent, source="list schedule along a state-graph path")
    status, detail_loop, wall = loop.run(time_limit, workers, seed, patience)
    detail: dict = {"tasks": len(tasks), "scale": scale, **detail_loop}
    best = loop.best
    objective = None if best is None else best[0] / scale
    bound = None if loop.bound is None else loop.bound / scale
    if objective is not None and bound is not None:
        bound = min(bound, objective)
    if best is not None:
        detail["schedule"] = best[1]
    return BaselineResult(
        kind="schedule",
        name=problem.name,
        status=status,
        objective=objective,
        bound=bound,
        wall_s=wall,
        detail=detail,
        credit=problem.credit,
    )


class _ReplayLoop:
    """CP-SAT with lazy cuts from a replay, keeping the best schedule that passes.

    Each solution CP-SAT finds is replayed as it comes (a solution callback). One that
    passes becomes the incumbent (when shorter); the first that fails stops the search,
    its cut is added and CP-SAT solves again, hinted with the incumbent and bound to beat
    it (``makespan <= incumbent - 1``). Without a replay every solution passes. An
    incumbent given beforehand (:meth:`offer`) is the fallback and, after the first cut,
    the hint.

    Status: ``OPTIMAL`` when a solve ends proven (OPTIMAL, or INFEASIBLE below the
    incumbent) without a failing solution: cuts only remove infeasible schedules, so the
    incumbent is then the optimum of the physically feasible ones. ``FEASIBLE`` when time
    runs out with an incumbent; ``INFEASIBLE`` when the model has no schedule at all, else
    ``UNKNOWN`` (no schedule). Every reported schedule passed the replay.
    """

    def __init__(
        self, *, model, tasks, scale, start, end, present, makespan, replay, more_cuts=None
    ):
        self.model, self.tasks, self.scale = model, tasks, scale
        self.start, self.end, self.present, self.makespan = start, end, present, makespan
        self.replay = replay
        self.more_cuts = more_cuts
        self.added: set[frozenset] = set()  # the cuts in the model
        self.best: tuple[int, list[dict]] | None = None  # (scaled makespan, rows)
        self.source = ""
        self.bound: int | None = None
        self.cuts = 0
        self.solves = 0
        self.failed = 0  # schedules that failed the replay
        self.prec: dict[tuple[int, int], object] = {}
        self.modes: list[int] | None = None  # the incumbent's mode per task
        self.t0 = time.perf_counter()
        self.progress_at = 0.0  # seconds after t0 of the last better schedule or new cut
        self.improvements: list[list[float]] = []  # [seconds, makespan] of each better one
        self.stalled = False  # stopped by the patience

    def rows(self, value, boolean) -> tuple[list[dict], list[int]]:
        """The schedule rows of a solution (``value``/``boolean`` read it) and its modes."""
        rows, modes = [], []
        for i, t in enumerate(self.tasks):
            m = next(m for m, lit in enumerate(self.present[i]) if boolean(lit))
            modes.append(m)
            rows.append(
                {
                    "task": t.id,
                    "agent": t.modes[m][0],
                    "start": json_number(value(self.start[i]) / self.scale, 6),
                    "end": json_number(value(self.end[i]) / self.scale, 6),
                }
            )
        rows.sort(key=lambda r: (r["start"], r["end"], r["task"]))
        return rows, modes

    def offer(self, rows: list[dict], *, source: str, modes=None) -> list | None:
        """Replay ``rows``; keep them when they pass and beat the incumbent; the cut if not."""
        cut = self.replay(rows) if self.replay is not None else None
        if cut is not None:
            self.failed += 1
            return cut
        span = round(max((float(r["end"]) for r in rows), default=0.0) * self.scale)
        if self.best is None or span < self.best[0]:
            if modes is None:
                agent = {r["task"]: r["agent"] for r in rows}
                modes = [[a for a, _ in t.modes].index(agent[t.id]) for t in self.tasks]
            self.best, self.source, self.modes = (span, rows), source, list(modes)
            self.progress_at = time.perf_counter() - self.t0
            self.improvements.append([round(self.progress_at, 3), span / self.scale])
        return None

    def precedes(self, y: int, x: int):
        if (y, x) not in self.prec:
            lit = self.model.new_bool_var(f"prec_{self.tasks[y].id}_{self.tasks[x].id}")
            self.model.add(self.end[y] <= self.start[x]).only_enforce_if(lit)
            self.prec[y, x] = lit
        return self.prec[y, x]

    def add_cut(self, cut) -> None:
        """Add the cut "one of these precedences ``(y, x)``" (once)."""
        key = frozenset(cut)
        if not key or key in self.added:
            return
        self.added.add(key)
        self.cuts += 1
        self.progress_at = time.perf_counter() - self.t0
        self.model.add_bool_or([self.precedes(y, x) for y, x in sorted(key)])

    def hint(self) -> None:
        self.model.clear_hints()
        if self.best is None:
            return
        by_task = {r["task"]: r for r in self.best[1]}
        for i, t in enumerate(self.tasks):
            r = by_task[t.id]
            self.model.add_hint(self.start[i], round(float(r["start"]) * self.scale))
            self.model.add_hint(self.end[i], round(float(r["end"]) * self.scale))
            if len(self.present[i]) > 1:
                for m, lit in enumerate(self.present[i]):
                    self.model.add_hint(lit, m == self.modes[i])

    def run(
        self, time_limit: float, workers: int, seed: int, patience: float | None = None
    ) -> tuple[str, dict, float]:
        from ortools.sat.python import cp_model

        loop = self
        t0 = self.t0 = time.perf_counter()
        self.progress_at = 0.0
        self.improvements = [[0.0, self.best[0] / self.scale]] if self.best else []
        proven = infeasible = False
        last = "UNKNOWN"
        while True:
            elapsed = time.perf_counter() - t0
            left = time_limit - elapsed
            if patience is not None and self.best is not None:
                wait = self.progress_at + patience - elapsed
                self.stalled = wait < left  # this solve stops by the patience, if it does
                left = min(left, wait)
            if left <= 0:
                break
            if self.solves and self.best is not None:
                # After a cut: only a shorter schedule is of use now, and the best one so
                # far is CP-SAT's hint. (The first solve is plain CP-SAT, so a job it solves
                # outright gets the optimum it always got: which of several optima it
                # returns decides how that schedule fares against a deviating person.)
                self.model.add(self.makespan <= self.best[0] - 1)
                self.hint()

            class Replayed(cp_model.CpSolverSolutionCallback):
                def __init__(self):
                    super().__init__()
                    self.cut = None
                    self.failed_rows = None

                def on_solution_callback(self):
                    rows, modes = loop.rows(self.value, self.boolean_value)
                    cut = loop.offer(rows, source="CP-SAT", modes=modes)
                    if cut is not None:
                        self.cut, self.failed_rows = cut, rows
                        self.stop_search()

            callback = Replayed()
            solver = _solver(left, workers, seed)
            began = time.perf_counter() - t0
            status = solver.solve(self.model, callback)
            self.solves += 1
            last = solver.status_name(status)
            if status in (cp_model.OPTIMAL, cp_model.FEASIBLE):
                bound = int(round(solver.best_objective_bound))
                if self.best is not None:
                    bound = min(bound, self.best[0])
                self.bound = bound if self.bound is None else max(self.bound, bound)
            if callback.cut is None:
                proven = status in (cp_model.OPTIMAL, cp_model.INFEASIBLE)
                infeasible = status == cp_model.INFEASIBLE and self.best is None
                if not proven and patience is not None and self.progress_at > began:
                    continue  # stopped by the patience while still improving: go on
                break
            if not callback.cut:
                self.stalled = False
                break  # a failure no precedence can mend: nothing more to try
            self.add_cut(callback.cut)
            if self.more_cuts is not None:
                for cut in self.more_cuts(callback.failed_rows):
                    self.add_cut(cut)
        wall = time.perf_counter() - t0
        if self.best is not None and proven:
            status_name = "OPTIMAL"
            self.bound = self.best[0]
        elif self.best is not None:
            status_name = "FEASIBLE"
        else:
            status_name = "INFEASIBLE" if infeasible else last
            if status_name in ("OPTIMAL", "FEASIBLE", "INFEASIBLE"):
                status_name = "UNKNOWN"  # stopped by a cut, or proven only below a bound
        detail: dict = {}
        if self.replay is not None:
            detail["cuts"] = self.cuts
            detail["solves"] = self.solves
            if self.best is not None:
                detail["replay"] = "passed"
                detail["found_by"] = self.source
            elif status_name == "UNKNOWN":
                detail["replay"] = "no physically feasible schedule found within the time limit"
            detail["improvements"] = self.improvements
        detail["status_note"] = self.note(status_name, time_limit, patience)
        return status_name, detail, wall

    def note(self, status: str, time_limit: float, patience: float | None = None) -> str:
        """One line saying what the status means for this result."""
        checked = " that replays through the state graph" if self.replay is not None else ""
        cuts = f", {self.cuts} cuts" if self.replay is not None else ""
        if status == "OPTIMAL":
            return f"proven optimal: no shorter schedule{checked} exists{cuts}"
        if status == "FEASIBLE":
            low = f"; the optimum is at least {self.bound / self.scale:g}" if self.bound else ""
            replayed = ", replayed through the state graph" if self.replay is not None else ""
            within = (
                f"in {time.perf_counter() - self.t0:.1f} s (no better schedule nor cut for "
                f"{patience:g} s)"
                if self.stalled
                else f"within {time_limit:g} s"
            )
            return (
                f"not proven optimal {within}: the best schedule found "
                f"(by {self.source}{cuts}){replayed}{low}"
            )
        if status == "INFEASIBLE":
            return "no schedule satisfies the constraints"
        return f"no schedule{checked} found within {time_limit:g} s{cuts}"


def _tool_constraints(model, problem: ScheduleProblem, start, end) -> None:
    tasks = problem.tasks
    initial = dict(problem.tool_initial)
    tools = sorted({t for task in tasks for t, _ in (*task.requires, *task.sets)})
    for tool in tools:
        setters = {i: v for i, task in enumerate(tasks) for t, v in task.sets if t == tool}
        users = {i: v for i, task in enumerate(tasks) for t, v in task.requires if t == tool}
        if tool not in initial:
            raise ScheduleError(f"{problem.name}: tool {tool!r} has no initial value")
        # Variables: before[(s, u)] true iff setter s ends before task u starts (else u ends
        # before s starts). One boolean per unordered pair of setters.
        before: dict[tuple[int, int], object] = {}

        def order(s: int, u: int, tool=tool, before=before, setters=setters):
            if (s, u) in before:
                return before[s, u]
            if (u, s) in before and u in setters:
                return before[u, s].Not()
            lit = model.new_bool_var(f"before_{tool}_{tasks[s].id}_{tasks[u].id}")
            model.add(end[s] <= start[u]).only_enforce_if(lit)
            model.add(end[u] <= start[s]).only_enforce_if(lit.Not())
            before[s, u] = lit
            return lit

        for s in setters:
            for u in set(setters) | set(users):
                if u != s:
                    order(s, u)
        for u, v in users.items():
            good = [s for s, w in setters.items() if w == v and s != u]
            if initial[tool] != v:
                if not good:
                    raise ScheduleError(
                        f"{problem.name}: task {tasks[u].id} needs {tool} = {v} but no other "
                        "task sets it"
                    )
                model.add_bool_or([order(s, u) for s in good])
            for s, w in setters.items():
                if s == u or w == v:
                    continue
                # Variables: between[s, s2, u] true iff setter s2 (of v) lies between s and u.
                between = []
                for s2 in good:
                    if s2 == s:
                        continue
                    z = model.new_bool_var(f"between_{tool}_{tasks[s2].id}_{tasks[u].id}")
                    model.add_implication(z, order(s, s2))
                    model.add_implication(z, order(s2, u))
                    between.append(z)
                model.add_bool_or(between).only_enforce_if(order(s, u))


# --------------------------------------------------------------------------- assemblies


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

    A graph whose alike operations are in a fixed order (:mod:`asp.fixed_order`) gives the
    full graph's precedences instead (the chains are none) and the order in which the
    blocks of a class start (``start_order``, symmetry breaking); ``fixed_order=False``
    keeps the chains as precedences (the conservative schedule, for comparison).
    """
    from asp.fixed_order import FixedOrder

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


# --------------------------------------------------------------------------- physical replay


def schedule_violation(model, rows: list[dict]) -> tuple[str, list[tuple[int, int]]] | None:
    """Replay a schedule through the state graph; ``None`` if it is physically feasible.

    The rule is the concurrent game's (:func:`asp.together.together`):
    at every start time ``t``, with ``D`` the operations ended by ``t`` and ``A`` those
    running, every ``D + T`` (``T`` a subset of ``A``) is a state of the state graph from
    which every other operation of ``A`` is a transition, and no two running operations
    conflict on a tool. Equivalently: every order of placement consistent with the schedule
    (``y`` before ``x`` whenever ``y`` ends by the time ``x`` starts) is a path of the state
    graph, whichever of two overlapping operations finishes first.

    On a graph whose alike operations are in a fixed order (``model.fixed``), the order is
    undone (:mod:`asp.fixed_order`): each block of alike operations must be done in its
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
    fixed = getattr(model, "fixed", None)
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
        found = _together_violation(model, state, done, running)
        if isinstance(found, tuple):
            a, b = found
            return f"operations {ids[a]} and {ids[b]} overlap but share a tool", [(a, b), (b, a)]
        if found is not None:
            return _cannot_follow(model, *found)
    return None


def _cannot_follow(model, done: set[int], b: int) -> tuple[str, list[tuple[int, int]]]:
    """The violation "``b`` cannot follow the done set" and its cut (see
    :func:`schedule_violation`): some operation outside ``done`` precedes one of
    ``done + {b}``, or a shorter cut from ``model.cuts`` (:class:`asp.cuts.PlacementCuts`)."""
    ids = model.spec.op_ids
    where = "{" + " ".join(ids[i] for i in sorted(done)) + "}" if done else "the start"
    short = getattr(model, "cuts", None)
    cut = short.cut(done, b) if short is not None else None
    if cut is None:
        first = done | {b}
        cut = [(y, x) for x in sorted(first) for y in range(len(ids)) if y not in done and y != x]
    return f"operation {ids[b]} cannot follow {where}", cut


def _together_violation(model, state: int, done: set[int], running: list[int]):
    """Whether the operations ``running`` may run together from ``state`` (``done`` done):
    :func:`asp.together.together`.

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


def list_schedule(model, problem: ScheduleProblem, sequence=None) -> list[dict] | None:
    """A physically feasible schedule built along a path of the state graph (list scheduling).

    The operations are taken one at a time in an order that is a path of the state graph:
    ``sequence`` (operation ids, e.g. the robust plan's principal line), else greedily the
    enabled operation that can finish first. Each starts no earlier than the one before it,
    on the allowed agent that finishes it first, at the earliest time (that start, or a
    completion after it) where it may run next to the operations still running
    (:func:`schedule_violation`'s rule). Once everything before it has ended it always may
    (it is the path's next step), so the schedule always exists; it is replayed once more
    at the end.

    Parameters
    ----------
    model
        What :func:`schedule_violation` takes (``spec``, ``workers``, ``steps``, ``conflict``).
    problem : ScheduleProblem
        Its tasks are the spec's operations (same ids), with their modes and durations.

    Returns
    -------
    list of dict or None
        Rows ``{"task", "agent", "start", "end"}`` sorted by start; None when ``sequence``
        is not a path of the state graph or the result fails the replay (zero durations).
    """
    ids = model.spec.op_ids
    index = {oid: i for i, oid in enumerate(ids)}
    scale = integer_scale([d for t in problem.tasks for _, d in t.modes] or [1])
    modes = {index[t.id]: [(a, round(d * scale)) for a, d in t.modes] for t in problem.tasks}
    n = len(ids)
    order = None
    if sequence is not None:
        order = [index.get(o, -1) for o in sequence]
        if sorted(order) != list(range(n)):
            return None  # not a complete sequence of these operations
    start: dict[int, int] = {}  # times in units of 1 / scale
    end: dict[int, int] = {}
    agent_of: dict[int, str] = {}
    free: dict[str, int] = {}
    state, last = 0, 0

    def fits(x: int, t: int, d: int) -> bool:
        done = sorted((i for i in start if end[i] <= t), key=lambda i: (end[i], start[i]))
        cur = 0
        for i in done:
            nxt = model.steps.get((cur, i))
            if nxt is None:
                return False
            cur = nxt[0]
        running = sorted([i for i in start if start[i] <= t < end[i]] + ([x] if d > 0 else []))
        return _together_violation(model, cur, set(done), running) is None

    fixed = getattr(model, "fixed", None)
    for step in range(n):
        if order is not None:
            cands = [order[step]]
        else:  # of alike operations, the first one not placed
            cands = [
                o
                for o in range(n)
                if o not in start and (fixed is None or not fixed.waiting(o, start))
            ]
        best = None
        for o in cands:
            nxt = model.steps.get((state, o))
            if nxt is None:
                if order is not None:
                    return None
                continue
            ready = 0  # each block of alike operations in its order
            if fixed is not None:
                before = fixed.block_before(o)
                if any(a not in start for a in before):
                    if order is not None:
                        return None
                    continue
                ready = max((end[a] for a in before), default=0)
            for agent, d in modes[o]:
                lo = max(last, free.get(agent, 0), ready)
                times = [lo, *sorted({e for e in end.values() if e > lo})]
                t = next(t for t in times if fits(o, t, d))
                key = (t + d, t, o, agent, nxt[0])
                best = key if best is None or key < best else best
        if best is None:
            return None
        _, t, o, agent, state = best
        _, d = next(m for m in modes[o] if m[0] == agent)
        start[o], end[o], agent_of[o] = t, t + d, agent
        free[agent], last = t + d, t
    rows = [
        {
            "task": ids[i],
            "agent": agent_of[i],
            "start": json_number(start[i] / scale, 6),
            "end": json_number(end[i] / scale, 6),
        }
        for i in range(n)
    ]
    rows.sort(key=lambda r: (r["start"], r["end"], r["task"]))
    return rows if schedule_violation(model, rows) is None else None
