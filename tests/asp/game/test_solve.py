"""The exact solver: the paper's Figure 4, a brute-force oracle, and invariants."""

import functools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from asp.game.dag import ANY, HUMAN, ROBOT, from_arrays, from_edges
from asp.game.metrics import plan_metrics, simulate_random_human
from asp.game.solve import (
    NO_MOVE,
    as_policy_array,
    certified_worst_case,
    evaluate_policy,
    play,
    robust_path,
    solve,
)
from tests.asp.figures import figure4


def test_figure4_tct_and_minimax():
    dag = figure4()
    sol = solve(dag)
    assert sol.tct == 2  # 1-2-9
    assert sol.minimax == 3  # 1-3-{4,5}-9
    assert dag.node_ids[int(dag.targets[sol.robot_policy[dag.index_of(1)]])] == 3
    assert robust_path(dag, sol) == [1, 3, 4, 9]


def test_figure4_fast_choice_lets_the_human_stretch_it_to_five():
    dag = figure4()
    fast = as_policy_array(dag, {1: 2, 6: 7, 8: 9})
    assert certified_worst_case(dag, fast) == 5  # 1-2-6-7-8-9
    evaluation = evaluate_policy(dag, fast)
    path, cost = play(dag, fast, evaluation.human_best_response)
    assert [dag.node_ids[v] for v in path] == [1, 2, 6, 7, 8, 9] and cost == 5


def test_policy_missing_a_reachable_move_is_an_error():
    dag = figure4()
    with pytest.raises(ValueError, match="no valid move at node 6"):
        evaluate_policy(dag, {1: 2})
    # A hole where the game cannot go does not matter.
    assert certified_worst_case(dag, {1: 3, 4: 9, 5: 9}) == 3


def test_pass_when_the_player_has_no_move():
    # 0 -(human)-> 1 -(robot)-> 2: the robot passes first, then each side moves once.
    dag = from_edges([0, 1, 2], [(0, 1), (1, 2)], sides=[HUMAN, ROBOT], costs=[2, 3])
    sol = solve(dag)
    assert sol.tct == sol.minimax == 5
    assert sol.robot_policy[0] == NO_MOVE


def test_tie_break_prefers_lower_expected_cost_against_random_human():
    # Both robot moves guarantee 3; via node 2 a random human often finishes in 2.
    edges = [(0, 1), (0, 2), (1, 3), (2, 3), (2, 4), (3, 4), (4, 5), (3, 5)]
    dag = from_edges(list(range(6)), edges, costs=[1, 1, 1, 1, 1, 1, 1, 1])
    sol = solve(dag)
    first = dag.node_ids[int(dag.targets[sol.robot_policy[0]])]
    exp = {v: sol.expected[v, HUMAN] for v in (1, 2)}
    assert sol.value[1, HUMAN] + 1 == sol.value[2, HUMAN] + 1 == sol.minimax
    assert first == min(exp, key=lambda v: (exp[v], v))


# ----------------------------------------------------------------- oracle tests


@st.composite
def random_dags(draw, max_nodes=10):
    n = draw(st.integers(2, max_nodes))
    src, dst = [], []
    for u in range(n - 1):
        targets = draw(st.sets(st.integers(u + 1, n - 1), min_size=1, max_size=3))
        for v in sorted(targets):
            src.append(u)
            dst.append(v)
    m = len(src)
    costs = draw(st.lists(st.integers(0, 4), min_size=m, max_size=m))
    sides = draw(st.lists(st.sampled_from([ROBOT, HUMAN, ANY]), min_size=m, max_size=m))
    return from_arrays(
        list(range(n)),
        np.array(src),
        np.array(dst),
        np.array(costs, float),
        np.array(sides),
        start=0,
        end=n - 1,
    )


def brute_force(dag):
    """Plain recursive minimax over (node, player) states, by the DESIGN.md rules."""

    @functools.cache
    def value(v, p, mode):
        if v == dag.end:
            return 0.0
        moves = dag.moves(v, p)
        if not moves:
            return value(v, 1 - p, mode)
        vals = [dag.costs[e] + value(int(dag.targets[e]), 1 - p, mode) for e in moves]
        if mode == "coop" or p == ROBOT:
            return min(vals)
        return max(vals)

    return value(dag.start, ROBOT, "coop"), value(dag.start, ROBOT, "minimax")


@settings(max_examples=150, deadline=None)
@given(random_dags())
def test_solver_matches_brute_force(dag):
    sol = solve(dag)
    tct, minimax = brute_force(dag)
    assert sol.tct == pytest.approx(tct)
    assert sol.minimax == pytest.approx(minimax)


@settings(max_examples=100, deadline=None)
@given(random_dags(), st.integers(0, 2**31 - 1))
def test_game_invariants(dag, seed):
    sol = solve(dag)
    assert sol.minimax >= sol.tct - 1e-9
    assert certified_worst_case(dag, sol.robot_policy) == pytest.approx(sol.minimax)
    metrics = plan_metrics(dag, solution=sol, n_games=200, seed=seed)
    assert metrics.rr_certified == pytest.approx(1.0)
    assert metrics.robust_optimal
    # Any other robot policy is certified no better than W*, and no simulated game against it
    # is longer than its certified worst case.
    rng = np.random.default_rng(seed)
    policy = np.full(dag.n_nodes, NO_MOVE)
    for v in range(dag.n_nodes):
        moves = dag.moves(v, ROBOT)
        if moves:
            policy[v] = rng.choice(moves)
    certified = certified_worst_case(dag, policy)
    assert certified >= sol.minimax - 1e-9
    games = simulate_random_human(dag, policy, n_games=100, seed=seed)
    assert games.max() <= certified + 1e-9
