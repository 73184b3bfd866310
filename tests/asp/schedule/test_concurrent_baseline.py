"""CP-SAT makespan respects the state graph and agrees with the concurrent game's W*(0)."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings

from asp.concurrent.build import build_game
from asp.concurrent.model import concurrent_model
from asp.concurrent.robustness import value
from asp.game.solve import solve
from asp.graph.feasibility import load_relations
from asp.graph.state_graph import build_state_graph
from asp.schedule.assembly import assembly_schedule
from asp.schedule.assembly_makespan import assembly_makespan
from asp.schedule.makespan import min_makespan
from asp.schedule.replay import schedule_violation
from asp.spec import load_spec, spec_from_dict
from tests.asp.concurrent.test_concurrent import random_jobs
from tests.asp.helpers_assembly import relations

PUMP = Path(__file__).resolve().parents[3] / "examples" / "vacuum_pump"


def w0(spec, graph, max_nodes: int = 2_000_000) -> float:
    game = build_game(concurrent_model(spec, graph), 0, max_nodes=max_nodes)
    return value(game, solve(game.dag), 0)


def bridge():
    """Base B, two posts L and R on it, a top T resting on either post (an OR, not a
    precedence): T may go on once L or R is there, never first."""
    rel = relations(
        ("B", "L", "R", "T"),
        contacts=[("L", "B", "-z"), ("R", "B", "-z"), ("T", "L", "-z"), ("T", "R", "-z")],
    )
    spec = spec_from_dict(
        {
            "name": "bridge",
            "parts": ["B", "L", "R", "T"],
            "base_part": "B",
            "agents": {"H": {"side": "human"}, "R1": {"side": "robot"}},
            "operations": [
                {"id": "L", "agents": {"R1": 5}, "part": "L"},
                {"id": "R", "agents": {"R1": 5}, "part": "R"},
                {"id": "T", "agents": {"H": 8}, "part": "T"},
            ],
        }
    )
    return spec, build_state_graph(spec, rel)


def test_relaxed_schedule_is_caught_and_cut():
    spec, graph = bridge()
    model = concurrent_model(spec, graph).replay  # the concurrent rules, for the replay
    # Fixed precedences alone allow T at time 0 (makespan 10): the replay rejects it.
    relaxed = min_makespan(assembly_schedule(spec, graph).problem, time_limit=10)
    assert relaxed.objective == 10
    found = schedule_violation(model, relaxed.detail["schedule"])
    assert found is not None and "operation T cannot follow the start" in found[0]
    _, result = assembly_makespan(spec, graph, time_limit=10)
    assert result.status == "OPTIMAL" and result.objective == 13
    assert result.detail["cuts"] >= 1 and result.detail["replay"] == "passed"
    assert schedule_violation(model, result.detail["schedule"]) is None
    assert w0(spec, graph) == 13


def test_pump_cp_sat_equals_cooperative_optimum():
    spec = load_spec(PUMP)
    graph = build_state_graph(spec, load_relations(spec))
    _, result = assembly_makespan(spec, graph, time_limit=30)
    assert result.status == "OPTIMAL" and result.detail["replay"] == "passed"
    assert result.objective == w0(spec, graph) == 215


def test_every_salbp_graph_that_fits(shared_data):
    checked = []
    for path in sorted((shared_data / "salbp").glob("*.IN2")):
        spec = load_spec(path)
        try:
            graph = build_state_graph(spec, max_states=5_000)
            cooperative = w0(spec, graph, max_nodes=2_000_000)
        except ValueError as exc:
            assert "exceeds" in str(exc)
            continue
        _, result = assembly_makespan(spec, graph, time_limit=30)
        assert result.status == "OPTIMAL", path.name
        assert result.objective == cooperative, path.name
        checked.append(path.name)
    assert len(checked) >= 6 and "SAWYER30.IN2" in checked, checked


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(random_jobs())
def test_random_jobs_cp_sat_equals_cooperative_optimum(data):
    ops, agents = data
    spec = spec_from_dict({"name": "job", "agents": agents, "operations": ops})
    graph = build_state_graph(spec)
    _, result = assembly_makespan(spec, graph, time_limit=20)
    assert result.status == "OPTIMAL"
    assert result.objective == pytest.approx(w0(spec, graph))
