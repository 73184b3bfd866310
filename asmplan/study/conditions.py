"""Robot conditions: the plan a study serves for each robot, as an ordinary plan document.

A condition is a robot policy over the assembly's game (either turn model):

- ``robust``: the exact robust policy (the plan as ``asmplan plan`` writes it);
- ``fast-greedy``: at each decision the robots take the move of the cooperative fastest
  line from there, trusting the person to help (:func:`asp.game.play.fast_greedy_policy`);
- ``cp-sat``: the CP-SAT makespan schedule run as a fixed plan: each robot keeps its list
  of operations in the schedule's order, whatever the person does (in the concurrent game
  :func:`asp.concurrent.robustness.schedule_rule`, which also tells the person the schedule's next
  operation);
- ``ignores-person``: a scripted robot, the same rule over a list the study gives
  (``script: {R1: [op, ...], ...}``, the person told the robust line's operations; default:
  the robust plan's own line when the person follows it, kept whatever she does);
- ``{run: DIR}``: a policy learned by ``asmplan train`` on this game (its run folder; in
  the concurrent game learned against the unbounded adversary: :func:`learned_rule`).

For each, :func:`condition_plan` evaluates the policy exactly against a best-response person
(:func:`asp.game.solve.evaluate_policy`) and writes the plan document of that policy: its table
holds every state the robot reaches against any person, and each state's ``bound`` is that
robot's certified worst case from there (not W*), so the advisor, the page and the export
tell the truth about the robot the participant meets. The document says which robot in
``condition`` (``id``, ``robot``, ``label``, ``worst_case``: the certified worst case from the
start, and per deviation budget ``k`` in the concurrent game) and keeps the robust plan's
``robustness`` curve as the reference.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROBOTS = ("robust", "fast-greedy", "cp-sat", "ignores-person")
"""Named robots; a learned one is given as ``{run: DIR}``."""


@dataclass(frozen=True)
class Condition:
    """One robot condition of a study.

    Attributes
    ----------
    id : str
        The researcher's name for it (in the export).
    label : str
        What a participant sees (``Robot A``): never the condition's name.
    robot : str
        One of :data:`ROBOTS`, or ``run`` for a learned policy.
    run : Path or None
        The run folder of a learned policy.
    script : dict or None
        ``ignores-person``: robot -> its operations in order (None: the robust line's).
    """

    id: str
    label: str
    robot: str
    run: Path | None = None
    script: dict | None = None

    def describe(self) -> str:
        return f"learned ({self.run})" if self.robot == "run" else self.robot


def condition_plan(result, condition: Condition) -> dict:
    """The plan document of ``condition``'s robot over a planned assembly.

    Parameters
    ----------
    result : asmplan.pipeline.AssemblyPlan
        Planned with ``keep_game=True`` (either turn model).
    """
    if condition.robot == "robust":
        doc = dict(result.to_dict())
        worst = [{"k": None, "bound": doc["minimax"]}]
        if result.concurrent is not None:
            worst = list(doc["robustness"])
        return _tagged(doc, condition, worst)
    if result.concurrent is not None:
        return _concurrent_plan(result, condition)
    return _alternate_plan(result, condition)


def _tagged(doc: dict, condition: Condition, worst: list[dict]) -> dict:
    doc["condition"] = {
        "id": condition.id,
        "label": condition.label,
        "robot": condition.describe(),
        "worst_case": worst,
    }
    return doc


def _fixed_solution(dag, solution, policy: np.ndarray):
    """A :class:`~asp.game.solve.Solution` whose robot plays ``policy``: values are its certified
    worst case, ``coop`` its best case (for the instruction's ties)."""
    from asp.game.rules import ROBOT
    from asp.game.solve import Solution, evaluate_policy

    ev = evaluate_policy(dag, policy)
    return Solution(
        tct=solution.tct,
        minimax=float(ev.worst[dag.start, ROBOT]),
        robot_policy=policy,
        human_policy=ev.human_best_response,
        value=ev.worst,
        coop=ev.best,
        expected=ev.expected,
    )


# --------------------------------------------------------------------------- alternate


def _alternate_plan(result, condition: Condition) -> dict:
    from asp.graph.game_states import alternate_states

    dag, solution = result.game.dag, result.solution
    describe = alternate_states(result.graph, dag)
    policy = _alternate_policy(result, condition, dag, solution, describe)
    fixed = _fixed_solution(dag, solution, policy)
    doc = dataclasses.replace(result, solution=fixed, played=None).to_dict()
    return _tagged(doc, condition, [{"k": None, "bound": fixed.minimax}])


def _alternate_policy(result, condition, dag, solution, describe) -> np.ndarray:
    from asp.game.play import fast_greedy_policy

    if condition.robot == "fast-greedy":
        return fast_greedy_policy(dag, solution)
    if condition.robot == "run":
        from arl.trainer import load_policies

        return load_policies(dag, condition.run)[0]
    if condition.robot == "cp-sat":
        script = _schedule_script(result.schedule.result.detail.get("schedule") or [])
    else:
        script = condition.script or _line_script(result.to_dict()["robust_plan"])
    return _scripted_policy(dag, describe, script)


def _schedule_script(rows: list[dict]) -> dict[str, list[str]]:
    script: dict[str, list[str]] = {}
    for row in sorted(rows, key=lambda r: (r["start"], r["task"])):
        script.setdefault(str(row["agent"]), []).append(str(row["task"]))
    return script


def _line_script(steps: list[dict]) -> dict[str, list[str]]:
    """Robot -> its operations along a plan line (``robust_plan`` steps)."""
    script: dict[str, list[str]] = {}
    for step in steps:
        for start in step.get("starts") or ():
            script.setdefault(str(start["agent"]), []).append(str(start["operation"]))
    return script


def _scripted_policy(dag, describe, script: dict[str, list[str]]) -> np.ndarray:
    """The alternating game's robot that keeps ``script``: at its turn it does the first
    operation of the script not done that it can, by its agent; if none can be done, its
    first move (it must move when it can)."""
    from asp.game import rules
    from asp.game.rules import ROBOT

    wanted = [(op, agent) for agent, ops in script.items() for op in ops]
    order = {pair: n for n, pair in enumerate(wanted)}
    policy = np.full(dag.n_nodes, rules.PASS, dtype=np.int64)
    for v in range(dag.n_nodes):
        moves = rules.moves(dag, v, ROBOT)
        if not moves:
            continue
        done = set(describe(v)["done"])
        best, rank = moves[0], len(order)
        for e in moves:
            pair = (dag.operations[e], dag.agents[e])
            n = order.get(pair, len(order))
            if pair[0] not in done and n < rank:
                best, rank = e, n
        policy[v] = best
    return policy


# --------------------------------------------------------------------------- concurrent


def _concurrent_plan(result, condition: Condition) -> dict:
    from asp.concurrent.plan import exact_curve
    from asp.concurrent.robustness import certified_worst_case, policy_array, schedule_rule
    from asp.game.play import fast_greedy_policy

    plan = result.concurrent
    compiled = plan.compiled()  # a fixed robot may reach any state: the whole game
    curve = exact_curve(compiled)
    game, solution = curve.game, curve.solution
    rule = None
    if condition.robot == "fast-greedy":
        policy = fast_greedy_policy(game.dag, solution)
    elif condition.robot == "run":
        from arl.trainer import load_policies

        learned = load_policies(compiled.adversary.dag, condition.run)[0]
        rule = learned_rule(compiled.adversary, learned, solution)
        policy = policy_array(game, rule)
    else:
        if condition.robot == "cp-sat":
            rows = result.schedule.result.detail.get("schedule") or []
        else:
            rows = _bar_rows(plan)
            if condition.script:  # the robots keep the script; the person is told the line
                rows = _script_rows(condition.script) + [
                    r for r in rows if r["agent"] not in condition.script
                ]
        rule = schedule_rule(rows)
        policy = policy_array(game, rule)
    fixed = _fixed_solution(game.dag, solution, policy)
    worst = [{"k": k, "bound": certified_worst_case(game, policy, k)} for k in range(curve.k + 1)]
    if rule is not None:
        worst.append({"k": None, "bound": certified_worst_case(compiled.adversary, rule)})
    swapped = dataclasses.replace(curve, solution=fixed)
    doc = dataclasses.replace(result, concurrent=dataclasses.replace(plan, curve=swapped)).to_dict()
    return _tagged(doc, condition, worst)


def learned_rule(adversary, policy: np.ndarray, solution):
    """A learned robot of the concurrent game as a rule for a game with a deviation budget.

    ``asmplan train --turn-model concurrent`` learns on the game against the unbounded
    adversary (``adversary``; ``policy``: its robot edge per node), where the person is told
    nothing. In a game with a budget the same robot node is the same state, running
    operations and pending starts with a budget attached, and each robot edge also tells the
    person what to do: the rule takes the edges that start what the learned robot starts
    there and, of those, tells the person what the robust plan (``solution``, of the game
    with the budget) would tell her given that start (the first edge where the learned game
    has no such node)."""
    from asp.game.rules import HUMAN

    index = {_unbudgeted(key): v for v, key in enumerate(adversary.nodes) if key[0] == "R"}
    robots = set(adversary.model.robots)

    def rule(game, v: int, edges: list[int]) -> int:
        u = index.get(_unbudgeted(game.nodes[v]))
        if u is None or policy[u] < 0:
            return edges[0]
        wanted = adversary.actions[int(policy[u])].ops
        same = [
            e
            for e in edges
            if all(o == wanted[w] for w, o in enumerate(game.actions[e].ops) if w in robots)
        ]
        if not same:
            return edges[0]
        dag = game.dag
        return min(same, key=lambda e: (solution.value[dag.targets[e], HUMAN], e))

    return rule


def _unbudgeted(key: tuple) -> tuple:
    """A game node's key without its deviation budget (``(kind, state, running, budget,
    pending)``)."""
    return (key[0], key[1], key[2], key[4])


def _bar_rows(plan) -> list[dict]:
    """The robust plan's line when the person follows it, as schedule rows."""
    bars, _ = plan.cooperative
    return [{"task": b.operation, "agent": b.agent, "start": b.start} for b in bars]


def _script_rows(script: dict[str, list[str]]) -> list[dict]:
    return [
        {"task": op, "agent": agent, "start": float(n)}
        for agent, ops in script.items()
        for n, op in enumerate(ops)
    ]
