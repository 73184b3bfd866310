"""Metrics: exact random-human distribution against the seeded simulation, RR, tax."""

import numpy as np
import pytest

from asp.metrics import (
    plan_metrics,
    random_cost_distribution,
    resilience_ratio,
    simulate_random_human,
)
from asp.solve import as_policy_array, solve
from asp.synth import synthetic_dag
from tests.asp.figures import SOLVE_KEYS, figure4


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
