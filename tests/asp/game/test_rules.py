"""The rules of play (asp.game.rules): moves by side, passes, the turn, the cost of a move."""

import numpy as np
import pytest

from asp.game import rules
from asp.game.dag import ANY, HUMAN, ROBOT, from_edges
from tests.asp.random_games import random_game


def _sided():
    # s: robot-only and human-only edges; a: only a robot edge (the human passes there).
    edges = [("s", "a"), ("s", "b"), ("a", "e"), ("b", "e")]
    return from_edges(
        ["s", "a", "b", "e"], edges, sides=[ROBOT, HUMAN, ROBOT, ANY], costs=[2, 1.5, 5, 1]
    )


def test_moves_by_side_and_the_turn_flip():
    dag = _sided()
    s, a, b, e = (dag.index_of(x) for x in "sabe")
    assert rules.moves(dag, s, ROBOT) == [0] and rules.moves(dag, s, HUMAN) == [1]
    assert rules.moves(dag, a, HUMAN) == [] and rules.moves(dag, e, ROBOT) == []
    assert rules.step(dag, s, ROBOT, 0) == (a, HUMAN, 2.0)
    assert rules.step(dag, a, HUMAN, rules.PASS) == (a, ROBOT, rules.PASS_COST)
    assert rules.step(dag, a, ROBOT, 2) == (e, HUMAN, 5.0)
    assert rules.settle(rules.has_move(dag), a, HUMAN, dag.end) == ROBOT
    assert rules.settle(rules.has_move(dag), b, HUMAN, dag.end) == HUMAN


@pytest.mark.parametrize(
    ("node", "player", "edge", "message"),
    [
        ("s", ROBOT, 1, "not a move of the robot"),
        ("s", HUMAN, rules.PASS, "may not pass"),
        ("e", ROBOT, rules.PASS, "game is over"),
        ("a", ROBOT, 3, "not a move"),
    ],
)
def test_illegal_moves_are_refused(node, player, edge, message):
    dag = _sided()
    with pytest.raises(ValueError, match=message):
        rules.step(dag, dag.index_of(node), player, edge)


def test_cost_of_a_move_is_the_edge_cost_in_both_models():
    dag = _sided()
    for model in rules.COST_MODELS:
        g = from_edges(
            dag.node_ids,
            [
                (dag.node_ids[int(u)], dag.node_ids[int(v)])
                for u, v in zip(dag.sources, dag.targets, strict=True)
            ],
            costs=dag.costs,
            sides=dag.sides,
            cost_model=model,
        )
        assert rules.move_costs(g).tolist() == [2.0, 1.5, 5.0, 1.0]


@pytest.mark.parametrize("seed", range(5))
def test_tables_agree_with_the_scalar_rules(seed):
    dag = random_game(seed, n=12)
    masks, counts, tables = rules.move_masks(dag), rules.move_counts(dag), rules.kernel_tables(dag)
    assert np.array_equal(tables.may, masks) and tables.tol == rules.COST_TOL
    for p in rules.PLAYERS:
        indptr, edges = rules.move_table(dag, p)
        for v in range(dag.n_nodes):
            listed = rules.moves(dag, v, p)
            assert listed == edges[indptr[v] : indptr[v + 1]].tolist()
            assert counts[p, v] == len(listed) and (v == dag.end or listed == dag.moves(v, p))
            assert listed == [e for e in dag.out_edges(v) if masks[p, e]]


def test_cost_tolerance():
    assert rules.costs_close(0.1 + 0.2, 0.3) and not rules.costs_close(0.3, 0.3001)
    assert rules.cost_at_most(0.1 + 0.2, 0.3) and not rules.cost_at_most(0.31, 0.3)
    assert rules.cost_at_most(np.array([0.2, 0.30000000001, 0.4]), 0.3).tolist() == [
        True,
        True,
        False,
    ]
    with pytest.raises(ValueError, match="cost_model"):
        rules.check_cost_model("hours")
