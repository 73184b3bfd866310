"""The certificate of any robot policy: the full enumeration's best response (the oracle)."""

from __future__ import annotations

from unittest.mock import patch

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from asp.concurrent.build import build_game
from asp.concurrent.certify import certify
from asp.concurrent.model import concurrent_model
from asp.concurrent.robustness import certified_worst_case
from asp.concurrent.rules import Position, concurrent_rules
from asp.concurrent.search import GREEDY, Search
from asp.errors import GameError, GameLimit
from tests.asp.concurrent.test_rules import job, random_jobs

SETTINGS = settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def hashed_policy(salt: int):
    """A fixed robot policy that looks at the position but not its budget: the commitment of
    least hash of (salt, state, running, ops), so it does not depend on the list's order."""

    def choose(pos: Position, commits) -> int:
        scores = [hash((salt, pos.state, pos.running, c.ops)) for c in commits]
        return scores.index(min(scores))

    return choose


def oracle(rules, spec, graph, choose, top: int) -> list[float]:
    """The policy's worst case per budget ``0..top`` in the fully enumerated game."""
    model = concurrent_model(spec, graph)
    game = build_game(model, top)

    def rule(game, v, edges):
        _, state, running, budget, _ = game.nodes[v]
        pos = Position(state, min(budget, rules.budget_cap(Position(state, 0, running))), running)
        commits = rules.commits(pos)
        want = commits[choose(pos, commits)].ops
        return next(e for e in edges if game.actions[e].ops == want)

    return [certified_worst_case(game, rule, k) for k in range(top + 1)]


@SETTINGS
@given(random_jobs(humans=(1, 2), ranges=True), st.integers(0, 3))
def test_certificate_is_the_full_enumerations_best_response(data, salt):
    ops, agents = data
    spec, graph = job(ops, agents=agents)
    rules = concurrent_rules(spec, graph)
    top = min(3, sum(1 for a in agents.values() if a["side"] == "human") * len(ops))
    choose = hashed_policy(salt)
    cert = certify(rules, choose, [*range(top + 1), None])
    got = [cert.worst[k] for k in range(top + 1)]
    assert got == oracle(rules, spec, graph, choose, top)
    # A policy blind to the budget: never falls as k grows, k = inf at the top.
    assert got == sorted(got)
    assert cert.worst[None] >= got[-1]
    # No policy beats the game's value.
    search = Search(rules)
    for k in range(top + 1):
        assert cert.worst[k] * rules.scale >= search.value(k)


@SETTINGS
@given(random_jobs(humans=(1, 2)))
def test_certificate_agrees_with_the_searchs_greedy_policy_game(data):
    from asp.concurrent.search import commit_bound
    from asp.game.solve import solve

    ops, agents = data
    spec, graph = job(ops, agents=agents)
    rules = concurrent_rules(spec, graph)
    budgets = [None, 0, 1]

    def greedy(pos, commits):  # the search's greedy rule, written on the public moves
        bounds = [commit_bound(rules.tables, pos.row(), _row(rules, c)) for c in commits]
        return bounds.index(min(bounds))

    cert = certify(rules, greedy, budgets)
    game = Search(rules).policy_game(budgets, GREEDY)
    sol = solve(game.dag)
    for b, s in game.starts.items():
        assert cert.worst[None if b < 0 else b] == float(sol.value[s, 0])


def _row(rules, commit):
    import numpy as np

    from asp.concurrent.rules import NONE

    return np.array([NONE if o is None else o for o in commit.ops], dtype=np.int64)


def test_bad_choice_and_limits_are_errors():
    spec, graph = job(
        [
            {"id": "a", "agents": {"H1": 2, "R1": 3}, "after": []},
            {"id": "b", "agents": {"H1": 2, "R1": 1}, "after": ["a"]},
        ],
        agents={"H1": {"side": "human"}, "R1": {"side": "robot"}},
    )
    rules = concurrent_rules(spec, graph)
    with pytest.raises(GameError, match="commitment index"):
        certify(rules, lambda pos, commits: len(commits), [0])
    with pytest.raises(GameLimit, match="exceeds 2 nodes"):
        certify(rules, lambda pos, commits: 0, [0], max_nodes=2)
    with pytest.raises(GameError, match="budget"):
        certify(rules, lambda pos, commits: 0, [-1])
    cert = certify(rules, lambda pos, commits: 0, [0, None])
    assert [row["k"] for row in cert.to_list()] == [0, None]
    assert cert.nodes == cert.game.dag.n_nodes


def test_the_policy_game_is_refused_past_its_memory_limit(monkeypatch):
    """Issue 26 item 3: the policy game is bounded like every compiled game (the one rule,
    asp.heap.memory_budget, by default): past the limit, one line naming --max-memory, the
    estimate and the memory available, before the node over it is added."""
    from asp import heap
    from asp.concurrent.build import PY_NODE_BYTES

    spec, graph = job(
        [
            {"id": "a", "agents": {"H1": 2, "R1": 3}, "after": []},
            {"id": "b", "agents": {"H1": 2, "R1": 1}, "after": ["a"]},
            {"id": "c", "agents": {"H1": 2, "R1": 2}, "after": ["a"]},
        ],
        agents={"H1": {"side": "human"}, "R1": {"side": "robot"}},
    )
    rules = concurrent_rules(spec, graph)
    whole = certify(rules, lambda pos, commits: 0, [0, None])
    assert whole.nodes > 4
    with pytest.raises(GameLimit) as info:
        certify(rules, lambda pos, commits: 0, [0, None], max_memory=4 * PY_NODE_BYTES)
    text = str(info.value)
    assert "\n" not in text and "--max-memory limit of 0.00 GB" in text, text
    assert "the policy game" in text and "GB available" in text and "needs more than" in text
    monkeypatch.setattr(heap, "available_memory", lambda: 16 * PY_NODE_BYTES)  # the default
    with pytest.raises(GameLimit, match="--max-memory"):
        certify(rules, lambda pos, commits: 0, [0, None])


@SETTINGS
@given(random_jobs(humans=(1, 2), ranges=True), st.sampled_from(["greedy", "schedule", "hybrid"]))
def test_value_only_best_response_is_the_compiled_one(data, policy):
    """The best response that keeps values only gives every budget's value of the policy
    game solved in full, for each fixed policy (the hybrid one after a search stopped
    early, so its table has moves at some positions only)."""
    from asp.concurrent.certify import best_response_values
    from asp.concurrent.search import HYBRID, SCHEDULE, Limits
    from asp.game.solve import solve
    from asp.schedule.assembly_makespan import assembly_makespan

    ops, agents = data
    spec, graph = job(ops, agents=agents)
    rules = concurrent_rules(spec, graph)
    kind = {"greedy": GREEDY, "schedule": SCHEDULE, "hybrid": HYBRID}[policy]
    rows = None
    if kind == SCHEDULE:
        rows = assembly_makespan(spec, graph, time_limit=5)[1].detail["schedule"]
    search = Search(rules, Limits(max_nodes=5), schedule=rows)
    search.value(0)
    budgets = [None, 0, 1, 2]
    game = search.policy_game(budgets, kind, rows)
    sol = solve(game.dag)
    want = {None if b < 0 else b: float(sol.value[s, 0]) for b, s in game.starts.items()}
    got = best_response_values(search, kind, budgets, schedule=rows)
    assert got == want
    # a memo that grows many times gives the same values; one too small gives none
    with patch("asp.concurrent.certify.FIRST_POSITIONS", 16):
        assert best_response_values(search, kind, budgets, schedule=rows) == want
    assert best_response_values(search, kind, budgets, schedule=rows, memory=400) in (None, want)
