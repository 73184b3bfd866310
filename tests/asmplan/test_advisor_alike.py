"""The runtime advisor follows alike parts placed out of the plan's canonical order.

The plans come from state graphs reduced by symmetry (the policy knows one order of each
class of interchangeable operations; ``plan.json``'s ``interchangeable`` lists the classes).
A cell that places the pins of a ring (or a pin with its roller) in any order is followed in
both turn models, the advice names the physical operations with every alike one that is as
good, and the cost stays within the plan's guaranteed bound: it is the cost of the canonical
order itself.
"""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from asmplan.advisor import Advisor, ObservationError
from asmplan.planfile import validate_plan
from tests.asmplan.plans import alike_plan
from tests.asp.graph.test_symmetry import pinned_disc
from tests.asp.helpers_assembly import pin_roller_ring

SPECS = {"disc": pinned_disc(3, 2), "ring": pin_roller_ring(3)}
TURN_MODELS = ("alternate", "concurrent")
PLANS = {(name, t): alike_plan(*SPECS[name], t) for name in SPECS for t in TURN_MODELS}
PINS = ["pin0", "pin1", "pin2"]


def play(doc: dict, order: list[str], *, follow: bool = False, split: bool = False) -> Advisor:
    """Play a plan to the end: the robots do what they are told, the person does, of what
    she may do (every option's alike operations), the first in ``order``, else the
    instruction; with ``follow``, the instruction, as the first of its alike operations in
    ``order``. Every advice keeps the plan's bound. ``split``: alternate starts before
    finishes."""
    advisor = Advisor(doc)
    advice = advisor.advice()
    bound = doc["minimax"] + 1e-9
    while not advice.finished:
        assert advice.total_bound <= bound
        if advice.turn_model == "alternate" and advice.turn == "robot":
            move = advice.robots[0]
        elif advice.turn_model == "concurrent" and any(not r["confirmed"] for r in advice.robots):
            move = next(r for r in advice.robots if not r["confirmed"])
            advice = advisor.observe({"kind": "started", **_event(move)})
            continue
        elif advice.options:
            move = _choose(advice, order, follow)
            if advice.turn_model == "concurrent":
                advice = advisor.observe({"kind": "started", **_event(move)})
                continue
        else:
            advice = advisor.observe({"kind": "finished", **_event(advice.finishes[0])})
            continue
        if split:
            advisor.observe({"kind": "started", **_event(move)})
        advice = advisor.observe({"kind": "finished", **_event(move)})
    assert advice.elapsed <= bound
    assert sorted(advice.done) == sorted(doc["operations"])
    return advisor


def _event(move: dict) -> dict:
    return {"operation": move["operation"], "agent": move["agent"]}


def _choose(advice, order: list[str], follow: bool) -> dict:
    """The option of the first operation in ``order`` the person may do (``follow``: the
    instruction's alike operations only), as that operation."""
    told = advice.instruction or advice.options[0]
    may = {op: o for o in ([told] if follow else advice.options) for op in o["alike"]}
    for op in order:
        if op in may:
            return {**may[op], "operation": op}
    return told


def _person_order(advisor: Advisor, ops: list[str]) -> list[str]:
    """The person's operations among ``ops``, in the order she did them."""
    seen = []
    for ev in advisor.history:
        if ev.agent == "H" and ev.operation in ops and ev.operation not in seen:
            seen.append(ev.operation)
    return seen


# --------------------------------------------------------------------------- the plan file


@pytest.mark.parametrize("turn_model", TURN_MODELS)
def test_the_plan_lists_the_classes_the_reduction_used(turn_model):
    disc, ring = PLANS["disc", turn_model], PLANS["ring", turn_model]
    assert disc["interchangeable"] == [[[p] for p in PINS], [["screw0"], ["screw1"]]]
    assert ring["interchangeable"] == [[[f"pin{k}", f"roller{k}"] for k in range(3)]]
    validate_plan(disc)
    validate_plan(ring)


# --------------------------------------------------------------------------- table


CASES = [
    # (plan, the person's order of preference among the alike operations)
    ("disc", ["pin2", "pin1", "pin0", "screw1", "screw0"]),
    ("disc", ["pin1", "pin2", "pin0", "screw1"]),
    ("ring", ["pin2", "roller2", "pin0", "roller0", "pin1", "roller1"]),
    ("ring", ["pin1", "pin2", "roller2", "roller1", "pin0", "roller0"]),
]


@pytest.mark.parametrize("turn_model", TURN_MODELS)
@pytest.mark.parametrize(("name", "order"), CASES)
def test_alike_operations_out_of_canonical_order(turn_model, name, order):
    """The person does what she likes among the alike operations (the bound holds: ``play``
    checks it), or what she is told with the alike part she likes: then the cost is the
    canonical line's (a symmetry keeps every cost)."""
    doc = PLANS[name, turn_model]
    canonical = play(doc, [])  # the instructions, in the plan's own order
    pins = [op for op in order if op.startswith("pin")]
    for follow in (False, True):
        advisor = play(doc, order, follow=follow)
        person = _person_order(advisor, order)
        assert person[0] == order[0]  # not the plan's first: it is pin0
        assert [p for p in person if p in pins] == [p for p in pins if p in person]
        if follow:
            assert advisor.advice().elapsed == pytest.approx(canonical.advice().elapsed)
        else:
            assert person == [op for op in order if op in person]
        # replaying the physical events gives the same state
        again = Advisor.replay(doc, advisor.history)
        assert again.advice() == advisor.advice()


def test_the_instruction_lists_every_alike_part_and_the_advice_is_physical():
    advisor = Advisor(PLANS["disc", "alternate"])
    advice = advisor.observe({"kind": "finished", **_event(advisor.advice().robots[0])})
    assert advice.turn == "human"
    assert advice.instruction["alike"] == PINS
    assert advice.instruction["alike_parts"] == PINS
    [option] = advice.options  # one option for the three alike pins
    assert option["alike"] == PINS
    advice = advisor.observe({"kind": "finished", "operation": "pin2", "agent": "H"})
    assert "pin2" in advice.done and "pin2" in advice.parts and "pin0" not in advice.done
    robot = advice.robots[0]["operation"]
    assert robot in ("pin0", "pin1")  # the robot's next pin, a physical one still missing


@pytest.mark.parametrize("turn_model", TURN_MODELS)
def test_a_roller_goes_with_its_own_pin(turn_model):
    """Blocks map together: once pin2 stands for the plan's first pin, roller2 stands for
    the first roller, and a roller whose pin is not in is refused, naming it."""
    advisor = Advisor(PLANS["ring", turn_model])
    started = set()

    def do(op, agent="H"):
        if turn_model == "concurrent" and op not in started:
            started.add(op)
            return advisor.observe({"kind": "started", "operation": op, "agent": agent})
        return advisor.observe({"kind": "finished", "operation": op, "agent": agent})

    advice = advisor.advice()
    if turn_model == "alternate" and advice.turn == "robot":
        advice = do(advice.robots[0]["operation"], "R")
    with pytest.raises(ObservationError, match="roller1"):
        do("roller1")
    assert advisor.advice() == advice  # unchanged
    do("pin1")
    if turn_model == "concurrent":
        while "pin1" not in advisor.advice().done:
            f = advisor.advice().finishes[0]
            advisor.observe({"kind": "finished", "operation": f["operation"], "agent": f["agent"]})
    k = advisor._alike.canonical("pin1")
    assert advisor._alike.canonical("roller1") == k.replace("pin", "roller")


def test_a_finish_maps_as_its_start():
    advisor = Advisor(PLANS["disc", "alternate"])
    advisor.observe({"kind": "finished", **_event(advisor.advice().robots[0])})
    advice = advisor.observe({"kind": "started", "operation": "pin2", "agent": "H"})
    assert [r["operation"] for r in advice.running] == ["pin2"]
    with pytest.raises(ObservationError, match="pin0"):
        advisor.observe({"kind": "finished", "operation": "pin0", "agent": "H"})
    advice = advisor.observe({"kind": "finished", "operation": "pin2", "agent": "H"})
    assert advice.done == ["disc", "pin2"]


def test_the_concurrent_robots_are_told_physical_pins():
    advisor = Advisor(PLANS["disc", "concurrent"])
    play_until = advisor.advice()
    while "disc" not in play_until.done:
        robots = [r for r in play_until.robots if not r["confirmed"]]
        if robots:
            play_until = advisor.observe({"kind": "started", **_event(robots[0])})
        else:
            play_until = advisor.observe({"kind": "finished", **_event(play_until.finishes[0])})
    # the person takes the pin the robot was told: the robot's stays its own
    robot_pin = next(r["operation"] for r in play_until.robots if r["operation"] in PINS)
    advice = advisor.observe({"kind": "started", "operation": robot_pin, "agent": "R"})
    other = next(p for p in reversed(PINS) if p != robot_pin)
    advice = advisor.observe({"kind": "started", "operation": other, "agent": "H"})
    running = {r["operation"]: r["agent"] for r in advice.running}
    assert running == {robot_pin: "R", other: "H"}
    with pytest.raises(ObservationError, match="already running"):
        advisor.observe({"kind": "started", "operation": other, "agent": "H"})


# --------------------------------------------------------------------------- property


@pytest.mark.parametrize("turn_model", TURN_MODELS)
@pytest.mark.parametrize("name", sorted(SPECS))
@settings(max_examples=25, deadline=None)
@given(data=st.data())
def test_any_permutation_of_a_class_is_followed(turn_model, name, data):
    """The person places the alike parts of a class in a random order (the robots follow
    the advice): the advisor follows, the person's order is hers, and the cost is the
    canonical line's."""
    doc = PLANS[name, turn_model]
    blocks = doc["interchangeable"][0]
    perm = data.draw(st.permutations(range(len(blocks))))
    order = [block[p] for p in range(len(blocks[0])) for block in (blocks[k] for k in perm)]
    split = data.draw(st.booleans()) and turn_model == "alternate"
    follow = data.draw(st.booleans())
    advisor = play(doc, order, follow=follow, split=split)
    first = [op for op in order if op in {b[0] for b in blocks}]
    person = _person_order(advisor, first)
    assert person == [op for op in first if op in person]
    if follow:
        assert advisor.advice().elapsed == pytest.approx(play(doc, []).advice().elapsed)


# --------------------------------------------------------------------------- the service


@pytest.mark.parametrize("turn_model", TURN_MODELS)
def test_the_service_follows_alike_parts_over_http(tmp_path, turn_model):
    """Over real HTTP: alike parts out of order are taken (advice in physical ids, the
    same as a local advisor's), a roller without its pin is refused (409, nothing changes),
    and a restarted service replays the physical events to the same state."""
    import httpx

    from tests.asmplan.server import running

    doc = PLANS["ring", turn_model]
    order = ["pin2", "roller2", "pin1", "roller1", "pin0", "roller0"]
    local = play(doc, order)
    events = [{"kind": e.kind, "operation": e.operation, "agent": e.agent} for e in local.history]
    assert next(e["operation"] for e in events if e["agent"] == "H") == "pin2"
    plan = "ring" if turn_model == "alternate" else "ring-concurrent"
    with running([doc], tmp_path) as url, httpx.Client(base_url=url) as client:
        sid = client.post("/api/sessions", json={"plan": plan}).json()["id"]
        replay = Advisor(doc)
        for k, event in enumerate(events):
            if k == 1:  # a roller whose pin is not in: refused, nothing changes
                before = client.get(f"/api/sessions/{sid}").json()
                bad = {"kind": event["kind"], "operation": "roller1", "agent": "H"}
                r = client.post(f"/api/sessions/{sid}/events", json=bad)
                assert r.status_code == 409 and "roller1" in r.json()["detail"]
                assert client.get(f"/api/sessions/{sid}").json() == before
            r = client.post(f"/api/sessions/{sid}/events", json=event)
            assert r.status_code == 200, r.text
            assert r.json() == replay.observe(event).to_dict()
        advice = r.json()
        assert advice["finished"] and advice["elapsed"] <= doc["minimax"] + 1e-9
        record = client.get(f"/api/sessions/{sid}").json()
        assert [e["operation"] for e in record["events"]] == [e["operation"] for e in events]
    with running([doc], tmp_path) as url, httpx.Client(base_url=url) as client:
        assert client.get(f"/api/sessions/{sid}").json()["advice"] == advice
