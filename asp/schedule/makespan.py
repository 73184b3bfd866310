"""The minimum-makespan schedule with OR-Tools CP-SAT (``../shared/DESIGN.md``, "The
classical baseline").

:func:`min_makespan`, laid out as in the CP-SAT examples (data, model, variables,
constraints, objective, solve): the minimum-makespan schedule when agents work in parallel:
an optional interval per (task, allowed agent) with exactly one present, no overlap per
agent, precedence as ``end <= start``, renewable resources as cumulative constraints
(PSPLIB) and tool states as sequence-dependent setups (see :func:`min_makespan`). With a
replay (:mod:`asp.schedule.replay`) it solves with lazy cuts (:class:`_ReplayLoop`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from asp.errors import ScheduleError
from asp.numbers import json_number
from asp.schedule.cpsat import (
    EXACT_HEADROOM,
    BaselineResult,
    integer_scale,
    new_solver,
    search_seconds,
    wall_safety,
)


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
    symmetry of interchangeable tasks (:meth:`asp.graph.fixed_order.FixedOrder.start_order`).
    """

    name: str
    tasks: tuple[Task, ...]
    precedences: tuple[tuple[int, int], ...] = ()
    resources: tuple[tuple[str, int], ...] = ()
    tool_initial: tuple[tuple[str, str], ...] = ()
    credit: str = ""
    start_order: tuple[tuple[int, int], ...] = ()


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

    Both are search seconds, CP-SAT's deterministic time (:mod:`asp.schedule.cpsat`), counted
    over the loop's solves, so the result is the same on every run at any load (one
    worker); the wall clock stops the loop only as a safety net
    (:func:`asp.schedule.cpsat.wall_safety` of ``time_limit``), and then
    ``detail["wall_stop"]`` says so.

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
    # exists; tests/asp/schedule/test_baseline.py::test_modes_of_different_lengths_share_no_end).
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
        self.work = 0.0  # search seconds of the solves so far (CP-SAT's deterministic clock)
        self.progress_at = 0.0  # search seconds at the last better schedule or new cut
        self.improvements: list[list[float]] = []  # [wall seconds, makespan] of each better one
        self.stalled = False  # stopped by the patience
        self.wall_stop = False  # stopped by the wall-clock safety net

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

    def offer(
        self, rows: list[dict], *, source: str, modes=None, work: float | None = None
    ) -> list | None:
        """Replay ``rows``; keep them when they pass and beat the incumbent; the cut if not
        (``work``: the search seconds when they came, default the solves' so far)."""
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
            self.progress_at = self.work if work is None else work
            self.improvements.append([round(time.perf_counter() - self.t0, 3), span / self.scale])
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
        self.progress_at = self.work
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
        wall_limit = wall_safety(time_limit)
        self.work = self.progress_at = 0.0
        self.improvements = [[0.0, self.best[0] / self.scale]] if self.best else []
        proven = infeasible = False
        last = "UNKNOWN"
        while True:
            elapsed = self.work
            left = time_limit - elapsed
            if patience is not None and self.best is not None:
                wait = self.progress_at + patience - elapsed
                self.stalled = wait < left  # this solve stops by the patience, if it does
                left = min(left, wait)
            if left <= 0:
                break
            wall_left = wall_limit - (time.perf_counter() - t0)
            if wall_left <= 0:
                self.wall_stop = True
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
                    work = loop.work + search_seconds(self.deterministic_time)
                    cut = loop.offer(rows, source="CP-SAT", modes=modes, work=work)
                    if cut is not None:
                        self.cut, self.failed_rows = cut, rows
                        self.stop_search()

            callback = Replayed()
            solver = new_solver(left, workers, seed, wall_limit=wall_left)
            began = self.work
            status = solver.solve(self.model, callback)
            self.solves += 1
            self.work += search_seconds(solver.deterministic_time)
            last = solver.status_name(status)
            if callback.cut is None and status not in (cp_model.OPTIMAL, cp_model.INFEASIBLE):
                self.wall_stop = solver.wall_time >= 0.95 * wall_left  # the net, not the work
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
        if self.wall_stop:
            detail["wall_stop"] = round(wall_limit, 3)
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
                f"in {self.work:.1f} s (no better schedule nor cut for {patience:g} s)"
                if self.stalled and not self.wall_stop
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
