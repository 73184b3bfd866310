"""The concurrent plan of an assembly: the curve, the CP-SAT comparison, Gantt charts.

:func:`plan_concurrent` does the work ``asmplan plan --turn-model concurrent`` reports:

- the CP-SAT makespan schedule, replayed through the state graph
  (:func:`asp.schedule.assembly_makespan.assembly_makespan`);
- ``W*(k)`` for ``k = 0, 1, ...`` until it reaches ``W*(inf)``
  (:func:`asp.concurrent.robustness.robustness`);
- the CP-SAT schedule run as a plan that ignores the person (:func:`asp.concurrent.schedule_rule`)
  and its certified worst case under the same budgets: what deviations cost a plan that
  does not plan for them;
- the robust plan played when the person follows it and against the worst person.

:func:`robustness_table` and :func:`plan_entries` turn it into text and ``plan.json``
keys; :func:`asmplan.report.gantt.write_figures` draws the PNGs ``robustness.png``,
``gantt_cooperative.png`` and ``gantt_worst.png``.
"""

from __future__ import annotations

from dataclasses import dataclass

from asp.concurrent.build import DEFAULT_MAX_NODES
from asp.concurrent.describe import Bar, timeline
from asp.concurrent.model import concurrent_model
from asp.concurrent.robustness import (
    DEFAULT_MAX_K,
    Robustness,
    certified_worst_case,
    policy_array,
    robustness,
    schedule_rule,
)
from asp.numbers import json_number
from asp.schedule.assembly_makespan import assembly_makespan


@dataclass(frozen=True, eq=False)
class ConcurrentPlan:
    """Everything the concurrent plan reports (module docstring).

    Attributes
    ----------
    curve : Robustness
    schedule : BaselineResult
        The CP-SAT makespan schedule (``status``, ``objective``, ``detail["schedule"]``).
    lower_bound : float
        The state graph's lower bound on any makespan.
    schedule_worst : list of {"k", "bound"}
        The CP-SAT schedule's certified worst case for each budget of the curve and
        unbounded (``k`` None); empty without a schedule.
    cooperative, worst : (list of Bar, float)
        The robust plan when the person follows it, and against the worst person.
    """

    spec: object
    curve: Robustness
    schedule: object
    lower_bound: float
    schedule_worst: list
    cooperative: tuple[list[Bar], float]
    worst: tuple[list[Bar], float]


def plan_concurrent(
    spec,
    graph,
    *,
    max_k: int = DEFAULT_MAX_K,
    step: float | None = 1.0,
    time_limit: float = 30.0,
    seed: int = 0,
    max_nodes: int = DEFAULT_MAX_NODES,
    schedule: tuple | None = None,
    progress: bool = False,
) -> ConcurrentPlan:
    """Solve the concurrent game of ``spec`` and compare it with CP-SAT (module docstring).

    Parameters
    ----------
    schedule : (BaselineResult, float), optional
        The CP-SAT schedule (from :func:`asp.schedule.assembly_makespan.assembly_makespan`)
        and its lower bound, when already computed.

    Raises
    ------
    ValueError
        ``max_k < 0``, a bad duration or agent (:func:`asp.concurrent.concurrent_model`), or
        a game over ``max_nodes`` nodes (the message names ``--max-k``).
    """
    if max_k < 0:
        from asp.errors import GameError

        raise GameError(f"--max-k: expected a deviation budget >= 0, got {max_k}")
    model = concurrent_model(spec, graph, step=step)
    if schedule is None:
        sched, result = assembly_makespan(spec, graph, time_limit=time_limit, seed=seed)
        schedule = (result, sched.lower_bound)
    result, lower_bound = schedule
    curve = robustness(model, max_k=max_k, max_nodes=max_nodes, progress=progress)
    game, solution = curve.game, curve.solution
    schedule_worst = []
    rows = result.detail.get("schedule")
    if rows:
        rule = schedule_rule(rows)
        policy = policy_array(game, rule)
        for k in range(curve.k + 1):
            schedule_worst.append({"k": k, "bound": certified_worst_case(game, policy, k)})
        top = certified_worst_case(curve.adversary, rule)
        schedule_worst.append({"k": None, "bound": top})
    cooperative = timeline(game, solution.robot_policy, "follow")
    worst = timeline(game, solution.robot_policy, "worst")
    return ConcurrentPlan(
        spec=spec,
        curve=curve,
        schedule=result,
        lower_bound=lower_bound,
        schedule_worst=schedule_worst,
        cooperative=cooperative,
        worst=worst,
    )


def _fmt(x) -> str:
    if x is None:
        return "-"
    x = float(x)
    return f"{x:g}"


def robustness_table(plan: ConcurrentPlan) -> str:
    """The curve on one time axis, with the CP-SAT makespan and its certified worst case."""
    res = plan.schedule
    lines = [
        f"CP-SAT makespan (agents in parallel, replayed through the state graph): "
        f"{_fmt(res.objective)} ({res.status}: {res.detail.get('status_note', '')}); "
        f"state-graph lower bound {plan.lower_bound:g}",
        "deviations k | robust plan W*(k) | CP-SAT schedule, certified worst case",
    ]
    worst = {r["k"]: r["bound"] for r in plan.schedule_worst}
    for row in plan.curve.to_list():
        k = row["k"]
        name = "inf" if k is None else str(k)
        note = " (cooperative)" if k == 0 else (" (fully adversarial)" if k is None else "")
        lines.append(f"{name:>12} | {_fmt(row['bound']):>17} | {_fmt(worst.get(k)):>8}{note}")
    if not plan.curve.flat:
        lines.append(
            f"the curve is not flat at k = {plan.curve.k} (--max-k, or the next budget's game "
            f"was over the node limit): W*(k) may still rise to W*(inf) = "
            f"{plan.curve.unbounded:g}"
        )
    game = plan.curve.game
    lines.append(
        f"concurrent game: {game.dag.n_nodes:,} nodes, {game.dag.n_edges:,} edges (budgets "
        f"0..{plan.curve.k}), unbounded {plan.curve.adversary.dag.n_nodes:,} nodes; "
        f"solved in {plan.curve.seconds:.2f} s"
    )
    return "\n".join(lines)


def timeline_text(bars: list[Bar], makespan: float) -> str:
    """One line per operation: start, end, agent, operation; deviations marked."""
    lines = [
        f"  {b.start:>7g} .. {b.end:<7g} {b.agent:<8s} {b.operation}"
        + ("   <- deviation from the plan" if b.deviation else "")
        for b in bars
    ]
    lines.append(f"  makespan {makespan:g}")
    return "\n".join(lines)


def plan_entries(plan: ConcurrentPlan) -> dict:
    """The ``plan.json`` keys of the concurrent plan.

    ``turn_model``, ``schedule`` (the CP-SAT result, ``objective`` and ``status``),
    ``robustness`` (``[{"k": 0, "bound": ...}, ..., {"k": None, ...}]``) and ``concurrent``:
    the CP-SAT schedule's certified worst case, the two timelines and the game's size. The
    robust policy itself is the plan file's ``policy`` (:mod:`asmplan.planfile`).
    """
    curve = plan.curve
    game = curve.game
    return {
        "turn_model": "concurrent",
        "schedule": {**plan.schedule.to_dict(), "lower_bound": plan.lower_bound},
        "robustness": curve.to_list(),
        "concurrent": {
            "flat": curve.flat,
            "plan_budget": curve.k,
            "schedule_worst_case": [
                {"k": r["k"], "bound": _plain(r["bound"])} for r in plan.schedule_worst
            ],
            "cooperative": _line(*plan.cooperative),
            "worst": _line(*plan.worst),
            "game_nodes": game.dag.n_nodes,
            "game_edges": game.dag.n_edges,
            "unbounded_game_nodes": curve.adversary.dag.n_nodes,
            "seconds": round(curve.seconds, 3),
        },
    }


def _plain(x):
    return json_number(float(x), 6)


def _line(bars: list[Bar], makespan: float) -> dict:
    return {
        "makespan": _plain(makespan),
        "bars": [
            {
                "agent": b.agent,
                "operation": b.operation,
                "start": _plain(b.start),
                "end": _plain(b.end),
                "deviation": b.deviation,
            }
            for b in bars
        ],
    }
