"""The runtime advisor: legal games keep the solver's bound; bad observations change nothing."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from asmplan.advisor import Advisor, ObservationError, placed_parts
from asp.game.dag import HUMAN, ROBOT
from tests.asmplan.plans import cell_game, cell_plan

PLANS = {cost: cell_plan(cost) for cost in ("time", "steps")}
GAMES = {cost: cell_game(cost) for cost in ("time", "steps")}


def _node_turn(doc, advice):
    pol = doc["policy"]["states"]
    return pol["node"][advice.state], ROBOT if advice.turn == "robot" else HUMAN


@pytest.mark.parametrize("cost", ["time", "steps"])
@settings(max_examples=60, deadline=None)
@given(data=st.data())
def test_random_legal_games_keep_the_bound(cost, data):
    doc = PLANS[cost]
    _, _, dag, sol = GAMES[cost]
    advisor = Advisor(doc)
    minimax = doc["minimax"]
    advice = advisor.advice()
    while not advice.finished:
        v, p = _node_turn(doc, advice)
        assert advice.bound == pytest.approx(sol.value[dag.index_of(v), p])
        assert advice.elapsed + advice.bound <= minimax + 1e-9
        if advice.turn == "robot":
            (move,) = advice.robots
        else:
            move = data.draw(st.sampled_from(advice.options))
            worst = advice.elapsed + move["cost"]
            assert move["worst"] >= worst
        split = data.draw(st.booleans())
        event = {"operation": move["operation"], "agent": move["agent"]}
        if split:
            before = advice.total_bound
            running = advisor.observe({**event, "kind": "started"})
            assert running.robots == [] and running.instruction is None
            assert running.running[-1]["operation"] == move["operation"]
            if advice.turn == "robot":
                assert running.total_bound == pytest.approx(before)
        advice = advisor.observe({**event, "kind": "finished"})
    assert advice.bound == 0
    assert advice.elapsed <= minimax + 1e-9
    assert sorted(advice.done) == sorted(doc["operations"])


def test_following_the_instructions_gives_w0():
    doc = PLANS["time"]
    advisor = Advisor(doc)
    advice = advisor.advice()
    while not advice.finished:
        move = advice.robots[0] if advice.turn == "robot" else advice.instruction
        advice = advisor.observe({"kind": "finished", **_pick(move)})
    assert advice.elapsed == pytest.approx(doc["metrics"]["w0"])


def _pick(move):
    return {"operation": move["operation"], "agent": move["agent"]}


BAD = [
    ({"kind": "finished", "operation": "zz", "agent": "H"}, "unknown operation 'zz'"),
    ({"kind": "finished", "operation": "a", "agent": "R9"}, "unknown agent 'R9'"),
    ({"kind": "finished", "operation": "c", "agent": "R1"}, "agent R1 may not do operation c"),
    ({"kind": "finished", "operation": "e", "agent": "R1"}, "not the plan's move"),
    ({"kind": "finished", "operation": "c", "agent": "H"}, "robots' turn"),
    ({"kind": "ended", "operation": "a", "agent": "H"}, "expected 'started' or 'finished'"),
    ({"operation": "a"}, "missing kind, agent"),
    ("a", "expected an object"),
]


@pytest.mark.parametrize(("event", "message"), BAD)
def test_bad_observations_name_the_problem_and_change_nothing(event, message):
    advisor = Advisor(PLANS["time"])
    before = advisor.advice()
    with pytest.raises(ObservationError, match=message):
        advisor.observe(event)
    assert advisor.advice() == before
    assert advisor.history == []


def test_bad_observations_mid_game():
    doc = PLANS["time"]
    advisor = Advisor(doc)
    first = advisor.advice().robots[0]
    advisor.observe({"kind": "started", **_pick(first)})
    with pytest.raises(ObservationError, match="still running"):
        advisor.observe({"kind": "started", **_pick(first)})
    with pytest.raises(ObservationError, match="is not running"):
        advisor.observe({"kind": "finished", "operation": "d", "agent": "H"})
    advice = advisor.observe({"kind": "finished", **_pick(first)})
    assert advice.turn == "human"
    with pytest.raises(ObservationError, match="already done"):
        advisor.observe({"kind": "finished", **_pick(first)})
    with pytest.raises(ObservationError, match="person's turn"):
        advisor.observe({"kind": "started", "operation": "b", "agent": "R1"})
    with pytest.raises(ObservationError, match="not enabled"):
        advisor.observe({"kind": "started", "operation": "e", "agent": "H"})
    assert advisor.advice() == advice
    assert len(advisor.history) == 2


def test_replay_restores_the_state():
    doc = PLANS["time"]
    advisor = Advisor(doc)
    for _ in range(3):
        a = advisor.advice()
        move = a.robots[0] if a.turn == "robot" else a.options[-1]
        advisor.observe({"kind": "finished", **_pick(move)})
    again = Advisor.replay(doc, advisor.history)
    assert again.advice() == advisor.advice()


@pytest.mark.parametrize(
    ("done", "expected"),
    [
        ([], []),
        (["1"], ["base"]),
        # a unit's members are placed in its workspace, then inserted with it: each once
        (["1", "2", "3", "U"], ["base", "shaft", "bearing"]),
        (["1", "2", "U", "3"], ["base", "shaft", "bearing"]),
    ],
)
def test_placed_parts_lists_each_part_once_in_order(done, expected):
    operations = {
        "1": {"parts": ["base"]},
        "2": {"parts": ["shaft"]},
        "3": {"parts": ["bearing"]},
        "U": {"parts": ["shaft", "bearing"]},
    }
    assert placed_parts(operations, done) == expected
