"""The minimum-cost way through a game DAG with OR-Tools CP-SAT (``../shared/DESIGN.md``,
"The classical baseline").

:func:`min_cost_path`: a unit flow with one boolean per arc, laid out as in the CP-SAT
examples (data, model, variables, constraints, objective, solve). On a DAG whose edges are
all ``ANY`` the arcs are the DAG's edges and the optimum is the TCT. With ``ROBOT``/``HUMAN``
edges the path runs over game states ``(node, player on turn)``: an edge open to the player
on turn flips the turn, and a player without a move passes at zero cost (a forced move), so
the optimum is the cooperative value ``solve(dag).tct`` under the alternating turn model.
"""

from __future__ import annotations

import math
import time

import numpy as np

from asp.game import rules
from asp.game.dag import GameDAG
from asp.game.rules import HUMAN, ROBOT
from asp.numbers import plain
from asp.schedule.cpsat import BaselineResult, exact_scale, new_solver


def _status(solver, status) -> tuple[str, bool]:
    from ortools.sat.python import cp_model

    return solver.status_name(status), status in (cp_model.OPTIMAL, cp_model.FEASIBLE)


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

    Equals ``asp.game.solve.solve(dag).tct`` (the cooperative value under the turn model).
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
    solver = new_solver(time_limit, workers, seed)
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
