"""The CP-SAT makespan stage of an assembly: the shortest schedule that replays through the
state graph (exact by lazy cuts, started from list schedules).
"""

from __future__ import annotations

import time
from collections.abc import Sequence

from asp.schedule.assembly import AssemblySchedule, assembly_schedule
from asp.schedule.cpsat import BaselineResult
from asp.schedule.list_schedule import list_schedule
from asp.schedule.makespan import min_makespan
from asp.schedule.replay import replay_model, schedule_violation

AUTO_TIME_LIMIT = 10.0
"""Search seconds (CP-SAT's deterministic time) for the makespan stage's search by default
(:func:`assembly_makespan` with ``time_limit=None``; :mod:`asp.schedule.cpsat`: the same
answer at any load). A small assembly is proven optimal in well under a second; on the
72-part cycloidal drive every better schedule came within the first 7 s of the search and
the cuts after them gave nothing better (20 s bought nothing)."""


AUTO_PATIENCE = 2.0
"""By default the CP-SAT makespan stage stops once neither a better schedule nor a new cut
has come for this many search seconds (or when it is proven optimal)."""


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
    implies (:func:`asp.schedule.assembly.assembly_schedule`); each schedule it finds is replayed
    through the state graph (:func:`asp.schedule.replay.schedule_violation`, the concurrent game's
    rule); one that fails adds its cut and CP-SAT solves again
    (:func:`asp.schedule.makespan.min_makespan`).
    Cuts only remove infeasible schedules, so a solve that proves no shorter schedule with
    every cut makes the best passing one ``OPTIMAL``.

    It starts from a list schedule along a path of the state graph
    (:func:`asp.schedule.list_schedule.list_schedule`, greedy, and along ``sequence`` too
    when given, e.g. the robust plan's principal line; the shorter one): physically feasible by
    construction, it is CP-SAT's hint and the fallback. So on a large state graph, where
    CP-SAT cannot prove an optimum in ``time_limit``, the result is still a replayed
    schedule, with status ``FEASIBLE`` and the proven lower bound. ``detail`` holds
    ``cuts``, ``solves``, ``replay``, ``found_by``, ``improvements`` and ``stage_s`` (the
    whole call, seconds).

    Parameters
    ----------
    time_limit : float or None
        Search seconds (CP-SAT's deterministic time) for the CP-SAT loop (after the precedences,
        the replay tables and the list schedules are built; the wall clock only as a safety
        net, :func:`asp.schedule.cpsat.wall_safety`). ``None``: the automatic budget,
        :data:`AUTO_TIME_LIMIT`, with ``patience`` defaulting to :data:`AUTO_PATIENCE`.
    patience : float, optional
        Stop once neither a better schedule nor a new cut has come for this many search
        seconds (:func:`asp.schedule.makespan.min_makespan`).
    fixed_order : bool
        On a graph whose alike operations are in a fixed order (the alternating game's
        reduction), undo it (:mod:`asp.graph.fixed_order`): the schedules of the full graph, alike
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
    result = min_makespan(
        sched.problem,
        time_limit=AUTO_TIME_LIMIT if time_limit is None else time_limit,
        workers=workers,
        seed=seed,
        replay=replay,
        incumbent=incumbent,
        patience=patience,
        more_cuts=more_cuts if model.cuts.combined else None,  # positive durations (cuts.py)
    )
    result.detail["stage_s"] = round(time.perf_counter() - t0, 3)
    return sched, result
