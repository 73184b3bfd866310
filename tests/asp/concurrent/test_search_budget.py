"""The concurrent search stops on its budget of positions, the wall clock only a safety net
(issue 26 item 7): ``time_limit`` is search seconds, counted in positions expanded
(:data:`asp.concurrent.search.POSITIONS_PER_SECOND`), so a stopped search is the same on
every run at any load; the wall clock stops it only at
:func:`asp.schedule.cpsat.wall_safety` of it, and then says so (``wall_stop``)."""

from __future__ import annotations

import pytest

from asp.concurrent import search as search_module
from asp.concurrent.curve import solve_curve
from asp.concurrent.rules import concurrent_rules
from asp.concurrent.search import POSITIONS_PER_SECOND, Limits, Search, work_positions
from tests.conftest import REPO

RANGES = REPO / "examples" / "vacuum_pump_ranges"


@pytest.fixture(scope="module")
def rules():
    """The pump with the person's duration ranges on a grid of 5 ms: 53,380 positions to
    search until flat, more than one look at the clock (every 32,768)."""
    from asmplan import pipeline

    assembly = pipeline.load(RANGES)
    graph = pipeline.state_graph(assembly)
    return concurrent_rules(graph.spec, graph, step=0.005)


def test_the_search_stops_at_its_budget_of_positions_and_resumes(rules):
    search = Search(rules, Limits(time_limit=0.05))
    assert search.budget == work_positions(0.05) == round(0.05 * POSITIONS_PER_SECOND)
    assert search.value(0) is None and search.stopped == "time limit"
    assert search.nodes == search.budget and search.wall_stop is None
    search.resume(2 * search.budget)  # a phase's share: on where it stopped
    assert search.stopped is None
    assert search.value(0) is None and search.nodes == 2 * search.budget


def test_two_stopped_curves_are_the_same(rules):
    """The budget binds (search and certificates): the same curve, positions, policy."""
    runs = [solve_curve(rules, max_k=2, limits=Limits(time_limit=0.5)) for _ in range(2)]
    first, second = ((c.lower, c.upper, c.bounds, c.policy, c.nodes, c.positions) for c in runs)
    assert first == second
    assert runs[0].stopped == "time limit" and runs[0].nodes == work_positions(0.5)
    assert runs[0].wall_stop is None


def test_the_wall_clock_safety_net_stops_it_and_says_so(rules, monkeypatch):
    monkeypatch.setattr(search_module, "wall_safety", lambda seconds: 0.0)
    curve = solve_curve(rules, max_k=2, limits=Limits(time_limit=100))
    # W*(0) = W*(inf) = 297 (flat) in 23,379 positions; the robust policy's game searches on
    # and is stopped at the first look at the clock (TICK + 1 positions): another policy
    assert curve.wall_stop == 0.0 and curve.nodes == 32_768
    assert curve.stopped is None and all(curve.exact) and curve.policy != "robust"
    assert curve.lower[0] == curve.upper[-1] == 297
