"""Metrics: exact random-human distribution against the seeded simulation, RR, tax."""

import numpy as np
import pytest

from asp.game.dag import from_arrays
from asp.game.metrics import (
    plan_metrics,
    probability_within,
    random_cost_distribution,
    resilience_ratio,
    simulate_random_human,
)
from asp.game.play import fast_greedy_policy
from asp.game.solve import as_policy_array, solve
from asp.game.synth import synthetic_dag
from tests.asp.figures import SOLVE_KEYS, figure4
from tests.asp.random_games import random_game


def test_figure4_fast_policy_distribution_is_exact():
    dag = figure4()
    fast = as_policy_array(dag, {1: 2, 6: 7, 8: 9})
    # The human ends at once (1-2-9: cost 2) or takes the long way (cost 5), half each.
    assert random_cost_distribution(dag, fast) == pytest.approx({2.0: 0.5, 5.0: 0.5})
    m = plan_metrics(dag, robot_policy=fast, wcpl=2)
    assert m.certified_wcpl == 5 and not m.robust_optimal
    assert m.avg_random == pytest.approx(3.5) and m.max_random == 5 and m.min_random == 2
    assert m.rr == pytest.approx(0.5) and m.rr_certified == pytest.approx(1.0)
    assert m.adversarial_tax == pytest.approx(1.5)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_simulation_agrees_with_exact_distribution(seed):
    dag = synthetic_dag(20, 10, 4, seed=seed)
    sol = solve(dag)
    dist = random_cost_distribution(dag, sol.robot_policy)
    assert sum(dist.values()) == pytest.approx(1.0)
    games = simulate_random_human(dag, sol.robot_policy, n_games=4000, seed=seed)
    mean = sum(c * p for c, p in dist.items())
    std = np.sqrt(sum((c - mean) ** 2 * p for c, p in dist.items()))
    assert abs(games.mean() - mean) <= 5 * std / np.sqrt(len(games)) + 1e-9
    assert mean == pytest.approx(sol.expected[dag.start, 0])
    for threshold in (mean, sol.minimax - 1):
        p = resilience_ratio(dist, threshold)
        sd = np.sqrt(p * (1 - p) / len(games))
        assert abs(resilience_ratio(games, threshold) - p) <= 5 * sd + 1e-9


def test_simulation_is_seeded():
    dag = synthetic_dag(10, 10, 4, seed=5)
    policy = solve(dag).robot_policy
    a = simulate_random_human(dag, policy, n_games=50, seed=9)
    b = simulate_random_human(dag, policy, n_games=50, seed=9)
    assert a.tolist() == b.tolist()


def test_metrics_keys_and_bad_game_count():
    dag = figure4()
    keys = plan_metrics(dag).to_dict().keys()
    for key in SOLVE_KEYS:
        assert key in keys
    with pytest.raises(ValueError, match="n_games"):
        simulate_random_human(dag, solve(dag).robot_policy, n_games=0)


def _brute_force_rr(dag, policy, bound):
    """P(cost <= bound) by enumerating every line (sides read directly, not via asp.game.rules)."""

    def go(v, p, spent, prob):
        if v == dag.end:
            return prob if spent <= bound + 1e-9 * (1 + abs(spent) + abs(bound)) else 0.0
        lo, hi = int(dag.indptr[v]), int(dag.indptr[v + 1])
        moves = [e for e in range(lo, hi) if int(dag.sides[e]) in (2, p)]
        if not moves:
            return go(v, 1 - p, spent, prob)
        if p == 0:
            moves = [int(policy[v])]
        share = prob / len(moves)
        return sum(
            go(int(dag.targets[e]), 1 - p, spent + float(dag.costs[e]), share) for e in moves
        )

    return go(dag.start, 0, 0.0, 1.0)


@pytest.mark.parametrize("seed", range(12))
def test_exact_rr_matches_brute_force_on_fractional_games(seed):
    dag = random_game(seed, n=9)
    sol = solve(dag)
    for policy in (sol.robot_policy, fast_greedy_policy(dag, sol)):
        dist = random_cost_distribution(dag, policy)
        bounds = sorted(dist) + [min(dist) - 0.05, sol.minimax, sol.tct, max(dist) + 1]
        bounds += [c + 0.01 for c in dist] + [c - 0.01 for c in dist]
        for b in bounds:
            want = _brute_force_rr(dag, policy, b)
            assert probability_within(dag, policy, b) == pytest.approx(want, abs=1e-12)
            assert resilience_ratio(dist, b) == pytest.approx(want, abs=1e-12)


def test_capped_rr_falls_back_to_the_simulation():
    dag = random_game(3, n=40)
    sol = solve(dag)
    middle = (sol.tct + sol.minimax) / 2
    assert probability_within(dag, sol.robot_policy, middle, max_entries=1) is None
    assert random_cost_distribution(dag, sol.robot_policy, max_entries=1) is None
    exact = plan_metrics(dag, solution=sol, wcpl=middle)
    assert exact.exact_distribution
    assert exact.rr == pytest.approx(_brute_force_rr(dag, sol.robot_policy, middle), abs=1e-12)


def test_fractional_110_node_graph_is_exact_and_bounded():
    """Issue 14: a 110-node graph with fractional costs once took 114 s and 5.3 GB."""
    dag = synthetic_dag(20, 10, 4, seed=1)
    rng = np.random.default_rng(0)
    costs = np.round(rng.uniform(0.1, 3.0, dag.n_edges), 3)
    dag = from_arrays(
        dag.node_ids, dag.sources, dag.targets, costs, dag.sides, start=dag.start, end=dag.end
    )
    sol = solve(dag)
    m = plan_metrics(dag, solution=sol)
    assert m.exact_distribution and m.rr == m.rr_certified == 1.0
    assert m.max_random == m.certified_wcpl and m.min_random <= m.avg_random <= m.max_random
    lower = plan_metrics(dag, solution=sol, wcpl=(m.avg_random + m.max_random) / 2)
    assert 0.0 < lower.rr < 1.0 or not lower.exact_distribution


def test_adversarial_tax_is_undefined_when_cooperation_costs_nothing():
    """Issue 14, item 9: the tax was 1.0 when TCT = 0 and W* > 0."""
    import json

    from asp.game.dag import HUMAN, ROBOT, from_edges
    from asp.game.metrics import adversarial_tax

    dag = from_edges(
        ["s", "m", "x", "t"],
        [("s", "m"), ("m", "t"), ("m", "x"), ("x", "t")],
        costs=[0, 0, 5, 0],
        sides=[ROBOT, HUMAN, HUMAN, ROBOT],
    )
    m = plan_metrics(dag, n_games=10)
    assert (m.tct, m.minimax) == (0, 5)
    assert m.adversarial_tax is None
    assert json.loads(json.dumps(m.to_dict(), allow_nan=False))["adversarial_tax"] is None
    assert adversarial_tax(0, 0) == 1.0 and adversarial_tax(2, 3) == 1.5
