"""The concurrent plan of an assembly: the curve, the CP-SAT comparison, Gantt charts.

:func:`plan_concurrent` does the work ``asmplan plan --turn-model concurrent`` reports:

- the CP-SAT makespan schedule, replayed through the state graph
  (:func:`asp.schedule.assembly_makespan.assembly_makespan`);
- ``W*(k)`` for ``k = 0, 1, ...`` until it reaches ``W*(inf)``, by the on-the-fly search
  (:func:`asp.concurrent.curve.solve_curve`): exact where the search finishes within its
  limits, else a certified interval ``[L(k), U(k)]``, the policy given to the cell being
  the one certified at ``U``;
- the CP-SAT schedule run as a plan that ignores the person and its certified worst case
  under the same budgets (an exact best response of the person to it): what deviations
  cost a plan that does not plan for them;
- the robust plan played when the person follows it and against the worst person.

The game is never compiled in full here; :meth:`ConcurrentPlan.compiled` compiles it on
demand (:func:`asp.concurrent.robustness.robustness`) for what needs every state of it (a
study's fixed robots). :func:`robustness_table` and :func:`plan_entries` turn the plan into
text and ``plan.json`` keys; :func:`asmplan.report.gantt.write_figures` draws the PNGs
``robustness.png``, ``gantt_cooperative.png`` and ``gantt_worst.png``.
"""

from __future__ import annotations

from dataclasses import dataclass

from asp.concurrent.build import DEFAULT_MAX_NODES
from asp.concurrent.curve import Curve, solve_curve
from asp.concurrent.describe import Bar, timeline
from asp.concurrent.model import concurrent_model
from asp.concurrent.robustness import DEFAULT_MAX_K, Robustness, robustness
from asp.concurrent.rules import concurrent_rules
from asp.concurrent.search import Limits
from asp.game.turns import CONCURRENT
from asp.numbers import json_number
from asp.schedule.assembly_makespan import assembly_makespan


@dataclass(frozen=True, eq=False)
class ConcurrentPlan:
    """Everything the concurrent plan reports (module docstring).

    Attributes
    ----------
    spec, graph, step
        What the game was made of (:meth:`compiled` makes it again).
    curve : asp.concurrent.curve.Curve
        ``W*(k)`` exact or as certified intervals, the policy game of the plan's policy
        and its solution (each state's bound is that policy's certified worst case).
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
    graph: object
    step: float | None
    curve: Curve
    schedule: object
    lower_bound: float
    schedule_worst: list
    cooperative: tuple[list[Bar], float]
    worst: tuple[list[Bar], float]

    def compiled(self, max_nodes: int = DEFAULT_MAX_NODES) -> Robustness:
        """The full concurrent game for the plan's budgets, compiled and solved exactly
        (every state, not only those the plan's policy reaches).

        Raises
        ------
        asp.errors.GameError
            The game is over ``max_nodes`` nodes or the memory allowed.
        """
        model = concurrent_model(self.spec, self.graph, step=self.step)
        return robustness(model, max_k=self.curve.k, max_nodes=max_nodes)


def plan_concurrent(
    spec,
    graph,
    *,
    max_k: int = DEFAULT_MAX_K,
    step: float | None = 1.0,
    time_limit: float = 30.0,
    seed: int = 0,
    limits: Limits | None = None,
    schedule: tuple | None = None,
    progress: bool = False,
) -> ConcurrentPlan:
    """Solve the concurrent game of ``spec`` and compare it with CP-SAT (module docstring).

    Parameters
    ----------
    max_k : int
        The largest deviation budget of the curve (it stops earlier once flat).
    step : float or None
        Grid of a person's duration range (:func:`asp.concurrent.concurrent_model`).
    time_limit, seed
        CP-SAT's, when ``schedule`` is not given.
    limits : asp.concurrent.search.Limits, optional
        Memory, positions and seconds of the search (default: its defaults); past them the
        curve is a certified interval.
    schedule : (BaselineResult, float), optional
        The CP-SAT schedule (from :func:`asp.schedule.assembly_makespan.assembly_makespan`)
        and its lower bound, when already computed.
    progress : bool
        The search's progress on stderr.

    Raises
    ------
    ValueError
        ``max_k < 0``, a bad duration or agent (:func:`asp.concurrent.concurrent_model`), or
        a memory limit that certifies no policy (the message names ``--max-memory``).
    """
    if max_k < 0:
        from asp.errors import GameError

        raise GameError(f"--max-k: expected a deviation budget >= 0, got {max_k}")
    rules = concurrent_rules(spec, graph, step=step)
    if schedule is None:
        sched, result = assembly_makespan(spec, graph, time_limit=time_limit, seed=seed)
        schedule = (result, sched.lower_bound)
    result, lower_bound = schedule
    curve = solve_curve(
        rules,
        max_k=max_k,
        limits=limits,
        schedule=result.detail.get("schedule") or None,
        lower=cpsat_lower_bound(result, lower_bound),
        progress=progress,
    )
    game, solution = curve.game, curve.solution
    cooperative = timeline(game, solution.robot_policy, "follow")
    worst = timeline(game, solution.robot_policy, "worst")
    return ConcurrentPlan(
        spec=spec,
        graph=graph,
        step=step,
        curve=curve,
        schedule=result,
        lower_bound=lower_bound,
        schedule_worst=curve.schedule_worst,
        cooperative=cooperative,
        worst=worst,
    )


def cpsat_lower_bound(result, lower_bound: float) -> float:
    """A proven lower bound of ``W*(0)``: the CP-SAT optimum when proven (the cooperative
    makespan: the person follows, so no robust plan does better), else its best bound,
    and never below the state graph's bound ``lower_bound``."""
    best = float(lower_bound or 0.0)
    if result.status == "OPTIMAL" and result.objective is not None:
        return max(best, float(result.objective))
    return best if result.bound is None else max(best, float(result.bound))


def _fmt(x) -> str:
    if x is None:
        return "-"
    x = float(x)
    return f"{x:g}"


def exact_curve(compiled: Robustness) -> Curve:
    """The curve of a compiled, exactly solved game (:meth:`ConcurrentPlan.compiled`) as a
    :class:`~asp.concurrent.curve.Curve`: every value exact, the robust policy's game."""
    values = (*compiled.bounds, compiled.unbounded)
    return Curve(
        lower=values,
        upper=values,
        bounds=values,
        flat=compiled.flat,
        game=compiled.game,
        solution=compiled.solution,
        policy="robust",
        schedule_worst=[],
        stopped=None,
        nodes=0,
        positions=compiled.game.dag.n_nodes,
        seconds=compiled.seconds,
    )


def _value_text(curve: Curve, i: int) -> str:
    """``W*(k)`` of entry ``i``: the value, or ``in [L, U] (gap %)``."""
    lo, hi = curve.lower[i], curve.upper[i]
    if lo == hi:
        return _fmt(lo)
    return f"in [{_fmt(lo)}, {_fmt(hi)}] ({curve.gap(i):.1f} %)"


def robustness_table(plan: ConcurrentPlan) -> str:
    """The curve on one time axis, with the CP-SAT makespan and its certified worst case."""
    res, curve = plan.schedule, plan.curve
    lines = [
        f"CP-SAT makespan (agents in parallel, replayed through the state graph): "
        f"{_fmt(res.objective)} ({res.status}: {res.detail.get('status_note', '')}); "
        f"state-graph lower bound {plan.lower_bound:g}",
        "deviations k | robust plan W*(k) | the plan's policy, certified worst case | "
        "CP-SAT schedule, certified worst case",
    ]
    worst = {r["k"]: r["bound"] for r in plan.schedule_worst}
    for i, row in enumerate(curve.to_list()):
        k = row["k"]
        name = "inf" if k is None else str(k)
        note = " (cooperative)" if k == 0 else (" (fully adversarial)" if k is None else "")
        lines.append(
            f"{name:>12} | {_value_text(curve, i)} | {_fmt(row['bound'])} | "
            f"{_fmt(worst.get(k))}{note}"
        )
    if not curve.certified(len(curve.lower) - 1):
        lines.append(
            f"{'inf':>12} | >= {_fmt(curve.lower[-1])}: no policy certified against the fully "
            "adversarial person in the time allowed (its best responses were cut short)"
        )
    if curve.stopped:
        gaps = curve.largest_gap
        lines.append(
            f"the search stopped at its {curve.stopped} (--search-time-limit, --max-nodes, "
            f"--max-memory give it more): W*(k) lies in [L, U] (largest gap {gaps:.1f} %); "
            f"the plan's policy is the {curve.policy} one, certified at U"
        )
    elif not curve.flat:
        lines.append(
            f"the curve is not flat at k = {curve.k} (--max-k): W*(k) may still rise to "
            f"W*(inf) = {_fmt(curve.upper[-1])}"
        )
    game = curve.game
    lines.append(
        f"concurrent search: {curve.nodes:,} positions expanded, {curve.positions:,} in its "
        f"table; the plan's policy game {game.dag.n_nodes:,} nodes, {game.dag.n_edges:,} "
        f"edges (budgets 0..{curve.k}); solved in {curve.seconds:.2f} s"
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
    the CP-SAT schedule's certified worst case, the two timelines and the search's size.
    Each ``robustness`` row has ``lower``, ``upper`` and ``exact`` (``W*(k)`` in ``[lower,
    upper]``) and ``bound``, the plan's policy's certified worst case. The policy itself is
    the plan file's ``policy`` (:mod:`asmplan.planfile`).
    """
    curve = plan.curve
    game = curve.game
    return {
        "turn_model": CONCURRENT.name,
        "schedule": {**plan.schedule.to_dict(), "lower_bound": plan.lower_bound},
        "robustness": curve.to_list(),
        "concurrent": {
            "flat": curve.flat,
            "plan_budget": curve.k,
            "certified_policy": curve.policy,
            "stopped": curve.stopped,
            "schedule_worst_case": [
                {"k": r["k"], "bound": _plain(r["bound"])} for r in plan.schedule_worst
            ],
            "cooperative": _line(*plan.cooperative),
            "worst": _line(*plan.worst),
            "game_nodes": game.dag.n_nodes,
            "game_edges": game.dag.n_edges,
            "positions_expanded": curve.nodes,
            "table_positions": curve.positions,
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
