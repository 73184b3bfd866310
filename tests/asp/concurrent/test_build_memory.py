"""The full builder's memory bound (issue 26 item 3): checked as it builds, one message."""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings

from asp.concurrent.build import build_game, game_bytes
from asp.concurrent.model import concurrent_model
from asp.errors import GameLimit
from tests.asp.concurrent.test_rules import job, random_jobs

RANGES = [
    {"id": "a", "agents": {"H": [1, 40]}},
    {"id": "b", "agents": {"H": [1, 40], "R1": 5}},
    {"id": "c", "agents": {"R1": 3, "H": [2, 30]}, "after": ["a"]},
    {"id": "d", "agents": {"H": [1, 20]}, "after": ["b"]},
]
AGENTS = {"H": {"side": "human"}, "R1": {"side": "robot"}}


def ranges_model(step=0.5):
    spec, graph = job(RANGES, agents=AGENTS)
    return concurrent_model(spec, graph, step=step)


@pytest.mark.parametrize("compiled", [True, False])
def test_a_build_over_its_memory_stops_with_the_estimate_and_the_flags(compiled):
    model = ranges_model()
    game = build_game(model, 1, compiled=compiled)
    need = game_bytes(game.dag.n_nodes, game.dag.n_edges, compiled=compiled)
    with pytest.raises(GameLimit) as info:
        build_game(model, 1, compiled=compiled, max_memory=need // 20)
    text = str(info.value)
    assert "\n" not in text
    for words in ("--max-memory", "--duration-step", "GB available", "needs more than"):
        assert words in text, text
    # Enough memory: the same game as without a limit.
    again = build_game(model, 1, compiled=compiled, max_memory=2 * need)
    assert (again.dag.n_nodes, again.dag.n_edges) == (game.dag.n_nodes, game.dag.n_edges)


def test_the_estimate_grows_with_the_game():
    assert game_bytes(10, 10) < game_bytes(10, 11) < game_bytes(11, 11)
    assert game_bytes(10, 10) < game_bytes(10, 10, compiled=False)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(random_jobs(humans=(1, 2), ranges=True))
def test_every_game_over_its_memory_stops_and_every_one_within_is_whole(data):
    ops, agents = data
    spec, graph = job(ops, agents=agents)
    model = concurrent_model(spec, graph)
    full = build_game(model, 2)
    need = game_bytes(full.dag.n_nodes, full.dag.n_edges)
    with pytest.raises(GameLimit, match="--max-memory"):
        build_game(model, 2, max_memory=need - 1)
    game = build_game(model, 2, max_memory=need)
    assert (game.dag.n_nodes, game.dag.n_edges) == (full.dag.n_nodes, full.dag.n_edges)
