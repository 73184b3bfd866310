"""The curve W*(k) searched then certified: intervals around the exact values, whatever
stops the search (time, positions), and the value-only certificates."""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from asp.concurrent.curve import solve_curve
from asp.concurrent.rules import concurrent_rules
from asp.concurrent.search import Limits
from tests.asp.concurrent.test_rules import job, oracle_values, random_jobs
from tests.asp.concurrent.test_search import start_values, top_budget

SETTINGS = settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@SETTINGS
@given(random_jobs(humans=(1, 2), ranges=True), st.sampled_from([1e-4, 1e-3, 0.02, 1.0]))
def test_a_time_limit_anywhere_gives_intervals_around_the_exact_values(data, seconds):
    """W*(inf) first in half the time, then the finite budgets, W*(inf) again in what is
    left: each interval holds the exact value, L and U never fall with k, and the policy
    handed over is certified at U(K)."""
    ops, agents = data
    spec, graph = job(ops, agents=agents)
    rules = concurrent_rules(spec, graph)
    top = top_budget(agents, ops)
    want = [w / rules.scale for w in oracle_values(spec, graph, top)]
    curve = solve_curve(rules, max_k=top, limits=Limits(time_limit=seconds))
    for k in range(curve.k + 1):
        assert curve.lower[k] <= want[k] <= curve.upper[k], (k, curve.lower, want, curve.upper)
    assert curve.lower[-1] <= want[-1] <= curve.upper[-1]
    assert list(curve.lower) == sorted(curve.lower)
    assert list(curve.upper) == sorted(curve.upper)
    assert start_values(curve.game, [curve.k])[0] == curve.upper[curve.k]
    for row in curve.to_list():  # JSON numbers, or null where no policy is certified
        assert row["upper"] is None or np.isfinite(row["upper"])
