"""The concurrent game read back: states, commitments and moves as the plan file and the
runtime advisor name them, and a policy played out as bars on the time axis (:func:`timeline`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from asp.concurrent.build import ActionRows, Commit, ConcurrentGame
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

    Each part of a state (its done operations and tools, what is running, its budget and
    instructions) and each move is named once per distinct value (the rod tower's 391 k
    table states have 4.4 k assembly states and 1.8 k running patterns): a ``*_of`` array
    gives, per table state or move, the index of its value in the matching list.

    Attributes
    ----------
    operations, agents : tuple of str
        The operation ids and worker names.
    cost_model : str
        The game's cost model.
    done_tools : list of (list of op id, dict)
        Distinct ``done`` and ``tools`` of :func:`state_description`, in the order the
        table first reaches them; ``state_of`` (n_states,) int64 indexes it.
    running : list of list of dict
        Distinct ``running`` of :func:`state_description`; ``running_of`` indexes it.
    budget_told : list of (int or None, dict)
        Distinct ``budget`` and ``instructions`` (``{}`` when the state has none);
        ``told_of`` indexes it.
    starts : list of (list of (op id, worker name, duration), int)
        Distinct :func:`move_starts` of the table's moves (``([], 0)`` for a pass);
        ``move_of`` (n_moves,) int64 indexes it.
    commits : dict of int to dict
        A planned robot move's index in ``starts`` -> its ``instruct``
        (:func:`commit_description`).
    cost : (n_moves,) float64
        Each move's cost (0 for a pass).
    """

    operations: tuple[str, ...]
    agents: tuple[str, ...]
    cost_model: str
    done_tools: list
    state_of: np.ndarray
    running: list
    running_of: np.ndarray
    budget_told: list
    told_of: np.ndarray
    starts: list
    move_of: np.ndarray
    commits: dict
    cost: np.ndarray


def policy_names(game: ConcurrentGame, table) -> PolicyNames:
    """The states, moves and commitments of a policy table (:class:`asp.game.policy.PolicyTable`)
    of ``game``, each distinct one named once (:class:`PolicyNames`) by
    :func:`state_description`, :func:`move_starts` and :func:`commit_description` of a node
    or edge that has it."""
    dag = game.dag
    nodes, edges = table.node, table.edge
    state_key, running_key, told_key = _node_keys(game, nodes)

    (first_state, state_of), (first_running, running_of), (first_told, told_of) = (
        _first_distinct(key) for key in (state_key, running_key, told_key)
    )
    # One pass: each table state that first has one of the three parts described once.
    wanted = np.unique(np.concatenate([first_state, first_running, first_told]))
    described = {i: state_description(game, int(nodes[i])) for i in wanted.tolist()}
    done_tools = [(described[i]["done"], described[i]["tools"]) for i in first_state.tolist()]
    running = [described[i]["running"] for i in first_running.tolist()]
    budget_told = [
        (described[i]["budget"], described[i].get("instructions", {})) for i in first_told.tolist()
    ]

    first, move_of = _first_distinct(_move_keys(game, edges))
    starts = [([], 0) if e < 0 else move_starts(game, e) for e in edges[first].tolist()]
    commits: dict[int, dict] = {}
    ptr, moves = table.ptr.tolist(), move_of.tolist()
    for i, t in enumerate(table.turn.tolist()):
        lo, hi = ptr[i], ptr[i + 1]
        if t == ROBOT and hi > lo and edges[lo] >= 0 and moves[lo] not in commits:
            commits[moves[lo]] = commit_description(game, int(edges[lo]))["instruct"]
    cost = rules.move_costs(dag, np.maximum(edges, 0)) * (edges >= 0)
    return PolicyNames(
        operations=tuple(game.model.spec.op_ids),
        agents=tuple(w.name for w in game.model.workers),
        cost_model=dag.cost_model,
        done_tools=done_tools,
        state_of=state_of,
        running=running,
        running_of=running_of,
        budget_told=budget_told,
        told_of=told_of,
        starts=starts,
        move_of=move_of,
        commits=commits,
        cost=cost,
    )


def _node_keys(game: ConcurrentGame, nodes: np.ndarray):
    """Per node of ``nodes``, the keys its parts are named by (2-D int arrays, a row each):
    ``(kind, state)`` for its done operations and tools, ``(kind, running)`` for what is
    running, ``(kind, budget, running operations, instructions)`` for its budget and
    instructions. A game of the Python builder (no node rows) keys every node by itself."""
    rows = getattr(game.nodes, "rows", None)
    if rows is None:
        own = np.asarray(nodes, dtype=np.int64)[:, None]
        return own, own, own
    nw = game.nodes.nw
    r = rows[nodes]
    running = np.hstack([r[:, :1], r[:, 3 : 3 + 2 * nw]])
    told = np.hstack([r[:, [0, 2]], r[:, 3 : 3 + nw], r[:, 3 + 2 * nw :]])
    return r[:, :2], running, told


def _move_keys(game: ConcurrentGame, edges: np.ndarray) -> np.ndarray:
    """Per edge of ``edges`` (``-1``: a pass), the key its :func:`move_starts` is named by
    (a row each): whether it passes, its side, operations, durations and deviations and, a
    robot edge, the remaining times at its target (its operations' durations). A game of
    the Python builder keys every edge by itself."""
    actions, rows = game.actions, getattr(game.nodes, "rows", None)
    if not isinstance(actions, ActionRows) or rows is None:
        return np.asarray(edges, dtype=np.int64)[:, None]
    nw = game.nodes.nw
    e = np.maximum(edges, 0)
    side = actions.side[e].astype(np.int64)
    remaining = rows[game.dag.targets[e], 3 + nw : 3 + 2 * nw] * (side == ROBOT)[:, None]
    head = np.stack([edges < 0, side, actions.deviations[e]], axis=1).astype(np.int64)
    return np.hstack([head, actions.ops[e], actions.durations[e], remaining])


def _first_distinct(keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distinct rows of ``keys`` in the order they first appear.

    Returns
    -------
    first : (n_distinct,) int64
        The index of each distinct row's first occurrence.
    inverse : (n_rows,) int64
        Each row's index among the distinct rows.
    """
    code, size = np.zeros(keys.shape[0], dtype=np.int64), 1
    for column in keys.T:  # each row as one integer, a digit per column (radix: its range)
        low = int(column.min(initial=0))
        radix = int(column.max(initial=0)) - low + 1
        if radix > keys.shape[0]:  # sparse values: their ranks instead
            column, low = np.unique(column, return_inverse=True)[1].ravel(), 0
            radix = int(column.max(initial=0)) + 1
        if size * radix >= 1 << 62:  # number the codes so far 0.. so that they stay int64
            _, code = np.unique(code, return_inverse=True)
            code, size = code.ravel().astype(np.int64), int(code.max(initial=0)) + 1
        code = code * radix + (column.astype(np.int64) - low)
        size *= radix
    _, first, inverse = np.unique(code.ravel(), return_index=True, return_inverse=True)
    order = np.argsort(first, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    return first[order], rank[inverse.ravel()]


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
