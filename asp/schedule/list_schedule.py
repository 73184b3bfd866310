"""A physically feasible schedule built along a path of the state graph (list scheduling)."""

from __future__ import annotations

from asp.numbers import json_number
from asp.schedule.cpsat import integer_scale
from asp.schedule.makespan import ScheduleProblem
from asp.schedule.replay import ReplayModel, schedule_violation, together_violation


def list_schedule(model: ReplayModel, problem: ScheduleProblem, sequence=None) -> list[dict] | None:
    """A physically feasible schedule built along a path of the state graph (list scheduling).

    The operations are taken one at a time in an order that is a path of the state graph:
    ``sequence`` (operation ids, e.g. the robust plan's principal line), else greedily the
    enabled operation that can finish first. Each starts no earlier than the one before it,
    on the allowed agent that finishes it first, at the earliest time (that start, or a
    completion after it) where it may run next to the operations still running (the rule of
    :func:`asp.schedule.replay.schedule_violation`). Once everything before it has ended it
    always may (it is the path's next step), so the schedule always exists; it is replayed
    once more at the end.

    Parameters
    ----------
    model : ReplayModel
        The concurrent rules the schedule follows (:func:`asp.schedule.replay.replay_model`).
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
        return together_violation(model, cur, set(done), running) is None

    fixed = model.fixed
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
