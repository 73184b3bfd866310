"""The runtime advisor of the concurrent game: observations follow the game's moves exactly.

Random games are played through the concurrent game itself (``asp.concurrent``) and, as
``started`` / ``finished`` events, through the advisor: at every event the advisor's robots,
time and bound are the game's. The pump plans replay the cooperative line to ``W*(0)``; a
person who deviates gets the replies of the policy table; bad observations change nothing.
"""

from __future__ import annotations

import random

import pytest

from asmplan.advisor import Advisor, ConcurrentAdvisor, ObservationError
from asp.concurrent.describe import commit_description, move_starts, state_description
from asp.game.dag import ROBOT
from tests.asmplan.plans import CELL, CHOICES, concurrent_cell, concurrent_plan, with_ranges
from tests.conftest import REPO

JOBS = {
    "fixed": CELL,
    "ranges": with_ranges(CELL),
    "choices": CHOICES,
    "choices-ranges": with_ranges(CHOICES),
}
PLANS = {name: concurrent_plan(data) for name, data in JOBS.items()}
GAMES = {name: concurrent_cell(data)[1] for name, data in JOBS.items()}


def _running(game, v) -> set:
    return {(r["operation"], r["agent"]) for r in state_description(game, v)["running"]}


def _robots(advice) -> set:
    return {(r["operation"], r["agent"]) for r in advice.robots}


@pytest.mark.parametrize("name", sorted(JOBS))
@pytest.mark.parametrize("seed", range(12))
@pytest.mark.parametrize("informed", [True, False])
def test_random_games_follow_the_game(name, seed, informed):
    """``informed``: the events carry the person's durations and the completion times (what
    the game's robots know), and the advisor is the game, move for move, to the end; without
    them it answers for the worst the observations leave possible."""
    curve = GAMES[name]
    game, sol = curve.game, curve.solution
    dag, policy = game.dag, sol.robot_policy
    rng = random.Random(seed)
    advisor = Advisor(PLANS[name])
    assert isinstance(advisor, ConcurrentAdvisor)
    v, t = game.starts[curve.k], 0.0
    while v != dag.end:
        # The robots commit first: the advisor answers the game's commitment.
        e = int(policy[v])
        advice = advisor.advice()
        assert _robots(advice) == {(o, r) for r, o in commit_description(game, e)["start"].items()}
        assert advice.elapsed == pytest.approx(t)
        assert advice.total_bound == pytest.approx(t + sol.value[v, ROBOT])
        h = int(dag.targets[e])
        # The person replies (a random move of the game); the next completion follows.
        r = rng.choice(list(dag.out_edges(h)))
        starts, _ = move_starts(game, r)
        for op, agent, d in starts:
            event = {"kind": "started", "operation": op, "agent": agent}
            advisor.observe({**event, "duration": d} if informed else event)
        w = int(dag.targets[r])
        t += float(dag.costs[r])
        running = _running(game, h) | {(op, agent) for op, agent, _ in starts}
        ended = running - (_running(game, w) if w != dag.end else set())
        assert ended
        for op, agent in sorted(ended):
            event = {"kind": "finished", "operation": op, "agent": agent}
            advice = advisor.observe({**event, "time": t} if informed else event)
        if not informed:  # durations seen only at their end: the advisor answers for the worst
            assert advice.total_bound >= t + sol.value[w, ROBOT] - 1e-9
            return
        v = w
    assert advisor.finished and advice.elapsed == pytest.approx(t) and advice.bound == 0


def _cooperative(advisor):
    """The person follows every instruction; completions come as late as the plan allows."""
    advice = advisor.advice()
    while not advice.finished:
        busy = {r["agent"] for r in advice.running}
        if advice.instruction and advice.instruction["agent"] not in busy:
            move = advice.instruction
            advice = advisor.observe({"kind": "started", **_pick(move)})
            continue
        f = max(advice.finishes, key=lambda f: (f["worst"], -f["time"]))
        advice = advisor.observe({"kind": "finished", **_pick(f), "time": f["time"]})
    return advice


def _pick(move):
    return {"operation": move["operation"], "agent": move["agent"]}


@pytest.mark.parametrize("name", sorted(JOBS))
def test_following_the_instructions_gives_the_principal_line(name):
    doc = PLANS[name]
    advice = _cooperative(Advisor(doc))
    assert advice.elapsed == pytest.approx(doc["metrics"]["w0"])
    assert advice.deviations == 0 and advice.bound == 0
    assert sorted(advice.done) == sorted(doc["operations"])


@pytest.fixture(scope="module")
def pump_plans():
    from asmplan import pipeline

    out = {}
    for name in ("vacuum_pump", "vacuum_pump_ranges"):
        path = REPO / "examples" / name
        if path.is_dir():
            out[name] = pipeline.plan(path, turn_model="concurrent", time_limit=20).to_dict()
    return out


@pytest.mark.parametrize(("name", "w0"), [("vacuum_pump", 215), ("vacuum_pump_ranges", 297)])
def test_pump_cooperative_line_ends_at_w0(pump_plans, name, w0):
    if name not in pump_plans:
        pytest.skip(f"examples/{name} not found")
    doc = pump_plans[name]
    assert doc["robustness"][0] == {"k": 0, "bound": w0, "lower": w0, "upper": w0, "exact": True}
    advice = _cooperative(Advisor(doc))
    assert advice.elapsed == w0 and advice.deviations == 0


@pytest.mark.parametrize("name", ["choices", "choices-ranges"])
def test_a_deviating_person_gets_the_policy_tables_replies(name):
    """The person deviates whenever she may (the worst deviation, at her slowest); after each
    completion the robots' reply is the policy table's commitment at the state reached.
    (On the pump the robust plan leaves the person no deviation at all.)"""
    doc = PLANS[name]
    pol = doc["policy"]
    states, moves = pol["states"], pol["moves"]
    op_of, agent_of = pol["operations"].index, pol["agents"].index
    advisor = Advisor(doc)
    advice = advisor.advice()
    started: set = set()
    deviated = 0
    while not advice.finished:
        i = advice.state
        deviations = [o for o in advice.options if o["deviation"]]
        free = advice.instruction and advice.instruction["agent"] not in {
            r["agent"] for r in advice.running
        }
        if deviations or free:
            move = (
                max(deviations, key=lambda o: (o["worst"], o["operation"])) if deviations else None
            )
            if move is None:
                move = next(o for o in advice.options if not o["deviation"])
            advice = advisor.observe({"kind": "started", **_pick(move), "duration": move["cost"]})
            started.add((op_of(move["operation"]), agent_of(move["agent"]), move["cost"]))
            deviated += bool(deviations)
            assert advice.deviations == deviated
            continue
        f = advice.finishes[0]
        before = advice.elapsed
        advice = advisor.observe({"kind": "finished", **_pick(f), "time": f["time"]})
        if advice.state == i and advice.elapsed == before:
            continue  # it finished with the last completion (reported after it)
        # The move of the table with these starts in which f finishes at f's time:
        (m,) = [
            m
            for m in range(moves["ptr"][i], moves["ptr"][i + 1])
            if {tuple(x) for x in moves["starts"][m]} == started
            and before + moves["cost"][m] == pytest.approx(f["time"])
            and [f["agent"], f["operation"]]
            not in [x[:2] for x in states["running"][moves["next"][m]]]
        ]
        r = moves["next"][m]
        want = {(pol["operations"][o], pol["agents"][a]) for o, a in states["robots"][r]}
        assert _robots(advice) == want
        assert advice.budget == states["budget"][r]
        started = set()
    assert deviated >= 1
    assert advice.elapsed <= doc["minimax"] + 1e-9


BAD = [
    ({"kind": "started", "operation": "zz", "agent": "H"}, "unknown operation 'zz'"),
    ({"kind": "started", "operation": "a", "agent": "R9"}, "unknown agent 'R9'"),
    ({"kind": "started", "operation": "c", "agent": "R1"}, "agent R1 may not do operation c"),
    ({"kind": "started", "operation": "e", "agent": "H"}, "not enabled"),
    ({"kind": "finished", "operation": "b", "agent": "H"}, "is not running"),
    ({"kind": "started", "operation": "b", "agent": "R1"}, "not the plan's move"),
    ({"kind": "finished", "operation": "a", "agent": "H", "time": -1}, "expected a number >= 0"),
]


@pytest.mark.parametrize(("event", "message"), BAD)
def test_bad_observations_name_the_problem_and_change_nothing(event, message):
    advisor = Advisor(PLANS["fixed"])
    before = advisor.advice()
    with pytest.raises(ObservationError, match=message):
        advisor.observe(event)
    assert advisor.advice() == before and advisor.history == []


def test_bad_observations_mid_game_and_replay():
    doc = PLANS["fixed"]
    advisor = Advisor(doc)
    advice = advisor.advice()
    move = advice.instruction or advice.options[0]
    advice = advisor.observe({"kind": "started", **_pick(move)})
    assert move["operation"] == "d"
    with pytest.raises(ObservationError, match="busy with"):
        advisor.observe({"kind": "started", "operation": "c", "agent": "H"})
    with pytest.raises(ObservationError, match="already running"):
        advisor.observe({"kind": "started", **_pick(move)})
    for robot in advice.robots:  # a robot's start confirms the plan's commitment
        advice = advisor.observe({"kind": "started", **_pick(robot)})
        with pytest.raises(ObservationError, match="already running"):
            advisor.observe({"kind": "started", **_pick(robot)})
    assert all(r["confirmed"] for r in advice.robots)
    first = advice.finishes[0]
    advice = advisor.observe({"kind": "finished", **_pick(first)})
    with pytest.raises(ObservationError, match="already done|not running"):
        advisor.observe({"kind": "finished", **_pick(first)})
    assert advisor.advice() == advice
    again = Advisor.replay(doc, advisor.history)
    assert again.advice() == advice
