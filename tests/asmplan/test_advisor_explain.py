"""Advice that explains itself (:meth:`Advisor.explain`): each option's reply, worst line and
sentence, and the plan ahead, are the plan's own.

The line behind an option is replayed through a fresh advisor as events (the person's starts
with their durations, every completion at its time): the advisor accepts every event (the
robots' operations in it are the plan's replies) and the game ends exactly at the option's
worst case. Following ``ahead`` from the start ends at W*(0).
"""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from asmplan.advisor import Advisor, finish_why, option_why, quantity
from tests.asmplan.plans import CHOICES, alike_plan, cell_plan, concurrent_plan, with_ranges
from tests.asp.helpers_assembly import pin_roller_ring

PLANS = {
    "alternate-time": cell_plan("time"),
    "alternate-steps": cell_plan("steps"),
    "concurrent-cell": concurrent_plan(),
    "concurrent-choices": concurrent_plan(CHOICES),
    "concurrent-ranges": concurrent_plan(with_ranges(CHOICES)),
}
EXPLAINED = ("reply", "line", "why")


def _w0(doc) -> float:
    rows = doc.get("robustness") or []
    return rows[0]["bound"] if rows else doc["metrics"]["w0"]


def _replay(doc, history, advice, line):
    """The advisor after ``history`` and then the events of ``line`` (and the completions of
    what runs now); returns the final advice."""
    advisor = Advisor.replay(doc, history)
    if advice.turn_model != "concurrent":
        for e in line:
            advisor.observe({"kind": "finished", "operation": e["operation"], "agent": e["agent"]})
        return advisor.advice()
    events = [
        (advice.elapsed + r["remaining"], 0, {"kind": "finished", **_move(r)})
        for r in advice.running
    ]
    # completions at this very instant not reported yet come first
    events += [
        (f["time"], -1, {"kind": "finished", **_move(f)})
        for f in advice.finishes
        if f["time"] == advice.elapsed
    ]
    for e in line:
        if e["side"] == "human":
            start = {"kind": "started", **_move(e), "duration": e["end"] - e["start"]}
            events.append((e["start"], 1, start))
        events.append((e["end"], 0, {"kind": "finished", **_move(e)}))
    for t, _, event in sorted(events, key=lambda x: (x[0], x[1])):
        if event["kind"] == "finished":
            event["time"] = t
        advisor.observe(event)
    return advisor.advice()


def _move(item):
    return {"operation": item["operation"], "agent": item["agent"]}


def _check_options(doc, advisor):
    advice = advisor.explain()
    plain = advisor.advice()
    strip = [{k: v for k, v in o.items() if k not in EXPLAINED} for o in advice.options]
    assert strip == plain.options  # the explanation adds keys, changes none
    assert all(not set(EXPLAINED) & set(o) for o in plain.options) and plain.ahead == []
    for option in advice.options:
        line = option["line"]
        assert _move(line[0]) == _move(option) and line[0]["start"] == advice.elapsed
        end = _replay(doc, advisor.history, advice, line)
        assert end.finished
        assert end.elapsed == pytest.approx(option["worst"])
        robots = [e for e in line if e["side"] == "robot" and e["start"] > line[0]["start"]]
        reply = option["reply"]
        if reply is None:
            assert not robots and all(e["end"] <= option["worst"] for e in line)
        else:
            first = [_move(e) for e in robots if e["start"] == reply["time"]]
            assert [_move(r) for r in reply["robots"]] == first
        assert option["why"] == option_why(option, doc.get("cost"))
        assert quantity(option["worst"], doc.get("cost")) in option["why"]
    return advice


def _check_finishes(doc, advisor):
    """Each completion the person may let the cell run to: the robots' reply then, the
    worst line (ending at its worst case) and the sentence saying both."""
    advice = advisor.explain()
    plain = advisor.advice()
    strip = [{k: v for k, v in f.items() if k not in EXPLAINED} for f in advice.finishes]
    assert strip == plain.finishes
    for f in advice.finishes:
        assert f["why"] == finish_why(f, doc.get("cost"))
        assert quantity(f["worst"], doc.get("cost")) in f["why"] and f["agent"] in f["why"]
        if not f["line"]:  # a completion at this very instant, not reported yet
            continue
        running = [advice.elapsed + r["remaining"] for r in advice.running]
        assert max([e["end"] for e in f["line"]] + running) == pytest.approx(f["worst"])
        reply = f["reply"]
        robots = [_move(e) for e in f["line"] if e["side"] == "robot" and e["start"] == f["time"]]
        if reply is not None:
            assert reply["time"] == f["time"]
            assert [_move(r) for r in reply["robots"]] == robots
            said = " and ".join(f"{r['agent']} starts {r['operation']}" for r in reply["robots"])
            assert (said or "the robots wait") in f["why"]


@pytest.mark.parametrize("name", sorted(PLANS))
@settings(max_examples=25, deadline=None)
@given(data=st.data())
def test_every_option_explains_itself_in_random_games(name, data):
    doc = PLANS[name]
    advisor = Advisor(doc)
    advice = advisor.advice()
    while not advice.finished:
        if advice.turn == "robot":
            advice = advisor.observe({"kind": "finished", **_move(advice.robots[0])})
            continue
        if advice.options:
            _check_options(doc, advisor)
        if advice.finishes:
            _check_finishes(doc, advisor)
        if advice.options and (not advice.finishes or data.draw(st.booleans())):
            option = data.draw(st.sampled_from(advice.options))
            event = {"kind": "started", **_move(option)}
            if advice.turn_model == "concurrent":
                event["duration"] = data.draw(st.sampled_from(option["durations"]))
            else:
                event["kind"] = "finished"
            advice = advisor.observe(event)
        else:
            f = data.draw(st.sampled_from(advice.finishes))
            advice = advisor.observe({"kind": "finished", **_move(f), "time": f["time"]})


@pytest.mark.parametrize("name", sorted(PLANS))
def test_the_plan_ahead_from_the_start_ends_at_w0(name):
    doc = PLANS[name]
    advice = Advisor(doc).explain()
    assert max(e["end"] for e in advice.ahead) == pytest.approx(_w0(doc))
    assert not any(e["deviation"] for e in advice.ahead)
    running = [r["operation"] for r in advice.running]  # the robots' first commitment
    assert sorted(running + [e["operation"] for e in advice.ahead]) == sorted(doc["operations"])
    if advice.turn_model != "concurrent":
        principal = [s["operation"] for s in doc["robust_plan"] if s["operation"]]
        assert [e["operation"] for e in advice.ahead] == principal


def test_deviations_are_named_in_the_alternating_game():
    """An option other than the instruction is a deviation, in the advice and its lines."""
    doc = PLANS["alternate-time"]
    advisor = Advisor(doc)
    advice = advisor.advice()
    seen = set()
    while not advice.finished:
        if advice.turn == "robot":
            advice = advisor.observe({"kind": "finished", **_move(advice.robots[0])})
            continue
        told = advice.instruction
        for o in advisor.explain().options:
            asked = told is not None and _move(o) == _move(told)
            assert o["deviation"] is (not asked)
            assert o["line"][0]["deviation"] is o["deviation"]
            seen.add(o["deviation"])
        advice = advisor.observe({"kind": "finished", **_move(advice.options[-1])})
    assert seen == {True, False}


def test_the_sentence_names_the_reply_and_the_worst_case_with_units():
    doc = PLANS["concurrent-choices"]
    advice = Advisor(doc).explain()
    worst = max(advice.options, key=lambda o: o["worst"])
    reply = worst["reply"]
    robots = " and ".join(f"{r['agent']} starts {r['operation']}" for r in reply["robots"])
    assert worst["why"] == (
        f"If you start {worst['operation']} now, at {quantity(reply['time'], 'time')} "
        + (robots or "the robots wait")
        + f"; the worst that can still happen is {worst['worst']:g} s."
    )
    steps = Advisor(PLANS["alternate-steps"]).explain()
    assert all(o["why"].endswith(" steps.") for o in steps.options)
    assert quantity(1, "steps") == "1 step" and quantity(2.5, "time") == "2.5 s"


def test_a_choice_that_matters_has_a_longer_worst_line():
    """The choices job: the options' worst cases differ, and each line shows why."""
    doc = PLANS["concurrent-choices"]
    options = Advisor(doc).explain().options
    worsts = {o["operation"]: o["worst"] for o in options}
    assert len(set(worsts.values())) > 1, worsts
    for o in options:
        assert max(e["end"] for e in o["line"]) == pytest.approx(o["worst"])


@pytest.mark.parametrize("turn_model", ["alternate", "concurrent"])
def test_lines_name_physical_alike_operations(turn_model):
    """With alike parts, an option's line starts with the option's own (physical) operation
    and names only operations of the plan."""
    doc = alike_plan(*pin_roller_ring(3), turn_model)
    advisor = Advisor(doc)
    advice = advisor.advice()
    if advice.turn == "robot":
        advice = advisor.observe({"kind": "finished", **_move(advice.robots[0])})
    for o in advisor.explain().options:
        assert o["line"][0]["operation"] == o["operation"]
        assert {e["operation"] for e in o["line"]} <= set(doc["operations"])
