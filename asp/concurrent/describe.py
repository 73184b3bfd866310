"""The concurrent game read back: states, commitments and moves as the plan file and the
runtime advisor name them, and a policy played out as bars on the time axis (:func:`timeline`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from asp.concurrent.build import Commit, ConcurrentGame
from asp.concurrent.model import UNBOUNDED, WAIT
from asp.game import rules
from asp.game.dag import ROBOT
from asp.game.solve import evaluate_policy
from asp.numbers import json_number


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
    ids = model.op_ids
    done, tools = model.state_names(state)
    out = {
        "done": list(done),
        "tools": dict(tools),
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
    ids = model.op_ids
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
    ids = model.op_ids
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


@dataclass(frozen=True, eq=False)
class PolicyNames:
    """A concurrent game's robust policy table named: what the plan file writes of it.

    Attributes
    ----------
    operations, agents : tuple of str
        The operation ids and worker names.
    cost_model : str
        The game's cost model.
    states : dict of int to dict
        Each game node of the table -> :func:`state_description`.
    starts : list of (list of (op id, worker name, duration), int)
        Each move of the table -> :func:`move_starts` (``([], 0)`` for a pass).
    commits : dict of int to dict
        Each robot state's planned edge -> its ``instruct`` (:func:`commit_description`).
    cost : (n_moves,) float64
        Each move's cost (0 for a pass).
    """

    operations: tuple[str, ...]
    agents: tuple[str, ...]
    cost_model: str
    states: dict
    starts: list
    commits: dict
    cost: np.ndarray


def policy_names(game: ConcurrentGame, table) -> PolicyNames:
    """The states, moves and commitments of a policy table (:class:`asp.game.policy.PolicyTable`)
    of ``game``, named once (:class:`PolicyNames`)."""
    dag = game.dag
    states: dict[int, dict] = {}
    for v in table.node.tolist():
        if v not in states:
            states[v] = state_description(game, v)
    edges = table.edge.tolist()
    starts = [([], 0) if e < 0 else move_starts(game, e) for e in edges]
    commits: dict[int, dict] = {}
    ptr = table.ptr.tolist()
    for i, t in enumerate(table.turn.tolist()):
        lo, hi = ptr[i], ptr[i + 1]
        if t == ROBOT and hi > lo and edges[lo] >= 0 and edges[lo] not in commits:
            commits[edges[lo]] = commit_description(game, edges[lo])["instruct"]
    cost = rules.move_costs(dag, np.maximum(table.edge, 0)) * (table.edge >= 0)
    return PolicyNames(
        operations=tuple(game.model.spec.op_ids),
        agents=tuple(w.name for w in game.model.workers),
        cost_model=dag.cost_model,
        states=states,
        starts=starts,
        commits=commits,
        cost=cost,
    )


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
    ids = model.op_ids
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
