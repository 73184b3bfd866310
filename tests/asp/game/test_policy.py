"""The robust policy's table: closed, with the solver's bounds, covering every state the
robust robot reaches against any human."""

from __future__ import annotations

import numpy as np

from asp.game.dag import HUMAN, ROBOT
from asp.game.policy import policy_table
from asp.game.solve import evaluate_policy, solve
from asp.graph.game_dag import game_dag
from asp.graph.state_graph import build_state_graph
from asp.spec import spec_from_dict
from tests.asp.helpers_assembly import CELL


def cell_game(cost: str | None = None):
    """(spec, graph, dag, solution) of the small cell."""
    spec = spec_from_dict(CELL, source="cell.yaml")
    graph = build_state_graph(spec)
    dag = game_dag(graph, cost=cost)
    return spec, graph, dag, solve(dag)


def test_policy_table_is_closed_and_bounds_are_the_solver_values():
    spec, graph, dag, sol = cell_game()
    table = policy_table(dag, sol)
    n = table.node.size
    # Every move leads to a state of the table; the start is state 0.
    assert table.node[0] == dag.start and table.turn[0] == ROBOT
    assert np.all((table.next >= 0) & (table.next < n))
    np.testing.assert_allclose(table.bound, sol.value[table.node, table.turn])
    # Robot states hold the policy's move only; human states every human move.
    for i in range(n):
        v, p = int(table.node[i]), int(table.turn[i])
        moves = table.edge[table.ptr[i] : table.ptr[i + 1]]
        if v == dag.end:
            assert moves.size == 0
        elif p == ROBOT:
            assert moves.tolist() == [int(sol.robot_policy[v])]
        else:
            want = dag.moves(v, HUMAN) or [-1]
            assert moves.tolist() == want
    # The bound is the robust policy's certified worst case.
    worst = evaluate_policy(dag, sol.robot_policy).worst
    np.testing.assert_allclose(table.bound, worst[table.node, table.turn])


def test_policy_covers_every_state_reachable_against_any_human():
    spec, graph, dag, sol = cell_game()
    table = policy_table(dag, sol)
    have = set(zip(table.node.tolist(), table.turn.tolist(), strict=True))
    seen, stack = set(), [(dag.start, ROBOT)]
    while stack:
        v, p = stack.pop()
        if (v, p) in seen:
            continue
        seen.add((v, p))
        if v == dag.end:
            continue
        moves = dag.moves(v, p)
        if p == ROBOT and moves:
            moves = [int(sol.robot_policy[v])]
        stack += [(int(dag.targets[e]), 1 - p) for e in moves] or [(v, 1 - p)]
    assert have == seen
