"""A two-condition trust study run end to end in the page, in headless Chromium.

``asmplan serve --study``'s service (two robots, Robot A the robust plan and Robot B the
CP-SAT schedule run as a fixed plan, within subjects, counterbalanced) with two
participants: P01 on a 1400 px screen by mouse, deviating wherever she can; P02 on a 400 px
screen by keyboard alone, following the plan. Every request not to 127.0.0.1 is aborted and
recorded (none may be made). Each gives consent and a code, plays both rounds, answers each
round's questionnaire (an item left alone stays missing) and reaches the end of the study;
then ``asmplan study export`` has every event of both, by condition, with P01's deviations,
and the fixed plan lost time to them. Skips like ``test_page_browser.py``.
"""

from __future__ import annotations

import csv
import io
import json

import pytest
from typer.testing import CliRunner

from asmplan.cli import app as cli
from asmplan.study.config import load_study
from asmplan.study.plans import study_plans
from tests.asmplan.browser import offline_page, wait_ready
from tests.asmplan.server import running
from tests.asmplan.test_page_browser import browser  # noqa: F401 (the fixture)
from tests.asmplan.test_study import write_study

READY = "(want) => want.includes(document.body.dataset.ready)"


def _wait(page, *states):
    page.wait_for_function(READY, arg=list(states), timeout=30_000)


def _play_by_mouse(page, tmp_path, k):
    """Click to the end: a deviation wherever one is offered, else the plan's move, else the
    cell's next completion."""
    while not page.locator("#final").is_visible():
        deviation = page.locator('#options button.move[data-deviation="1"]')
        moves = page.locator("#options button.move")
        pick = deviation.first if deviation.count() else moves.first
        if not moves.count():
            pick = page.locator("#finishes button").first
        pick.click()
        _wait(page, "1", "done")
    page.screenshot(path=str(tmp_path / f"study-mouse-{k}.png"), full_page=True)


def _answer_by_mouse(page) -> None:
    page.wait_for_selector("#submit-answers", timeout=30_000)
    page.locator("#q-trust-2").check()  # 'predictable' left alone: missing
    page.locator("#q-comment").fill("it waited")
    page.click("#submit-answers")


def _play_by_keyboard(page):
    """Enter plays the move that has the focus (the plan's) until the end."""
    for _ in range(200):
        if page.locator("#final").is_visible():
            return
        kind = page.evaluate(
            "() => document.activeElement.className + document.activeElement.dataset.kind"
        )
        assert "move" in kind or "finish" in kind, kind
        page.keyboard.press("Enter")
        _wait(page, "1", "done")
    raise AssertionError("the game did not end")


def _answer_by_keyboard(page) -> None:
    _wait(page, "done")
    page.keyboard.press("Tab")  # from "Done" to the first item's first value
    for _ in range(30):
        info = page.evaluate("() => [document.activeElement.type, document.activeElement.id]")
        if info[0] == "radio":
            page.keyboard.press("ArrowRight")  # its second value, checked
        elif info[1] == "submit-answers":
            page.keyboard.press("Enter")
            return
        page.keyboard.press("Tab")
    raise AssertionError("no way to the questionnaire's button by Tab")


@pytest.mark.slow
def test_a_two_condition_study_with_two_participants(browser, tmp_path):  # noqa: F811
    study = load_study(write_study(tmp_path))
    variants = study_plans(study, say=lambda _: None)
    state = tmp_path / "state"
    with running([], state, study=study, variants=variants) as url:
        # P01: 1400 px, by mouse, deviating
        page, outside, errors = offline_page(browser, url, 1400)
        page.goto(url + "/")
        _wait(page, "consent")
        assert "You agree" in page.locator("#consent").inner_text()
        page.locator("#participant").fill("P01")
        page.click("#agree")
        titles = []
        for k in range(2):
            wait_ready(page)
            titles.append(page.locator("#title").inner_text())
            _play_by_mouse(page, tmp_path, k)
            _answer_by_mouse(page)
            _wait(page, "answered")
            page.click("#next-round")
        _wait(page, "study-done")
        assert "the study is complete" in page.locator("#thanks").inner_text()
        # P02: 400 px, by keyboard alone, following the plan
        phone, outside2, errors2 = offline_page(browser, url, 400)
        phone.goto(url + "/")
        _wait(phone, "consent")
        phone.keyboard.press("Shift+Tab")  # from "I agree" back to the code
        phone.keyboard.type("P02")
        phone.keyboard.press("Tab")
        phone.keyboard.press("Enter")
        for k in range(2):
            wait_ready(phone)
            wide = phone.evaluate("() => document.documentElement.scrollWidth")
            assert wide <= 400, wide
            _play_by_keyboard(phone)
            _answer_by_keyboard(phone)
            _wait(phone, "answered")
            assert phone.evaluate("() => document.activeElement.id") == "next-round"
            phone.screenshot(path=str(tmp_path / f"study-keyboard-{k}.png"), full_page=True)
            phone.keyboard.press("Enter")
        _wait(phone, "study-done")
        assert errors == [] and errors2 == []
    assert outside == [] and outside2 == []
    assert [t.split(", ")[-1] for t in titles] == ["Robot A", "Robot B"]  # labels, not names
    runner = CliRunner()
    out = runner.invoke(cli, ["study", "export", str(state)])
    assert out.exit_code == 0, out.output
    rows = list(csv.DictReader(io.StringIO(out.stdout)))
    assert {r["participant"] for r in rows} == {"P01", "P02"}
    assert {(r["participant"], r["condition"]) for r in rows} == {
        (p, c) for p in ("P01", "P02") for c in ("robust", "schedule")
    }
    assert any(r["deviation"] == "1" for r in rows if r["participant"] == "P01")
    assert not any(r["deviation"] == "1" for r in rows if r["participant"] == "P02")
    doc = json.loads(runner.invoke(cli, ["study", "export", str(state), "--format", "json"]).stdout)
    sessions = {(s["participant"], s["condition"]): s for s in doc["sessions"]}
    assert len(sessions) == 4
    for (pid, _), s in sessions.items():
        if pid == "P01":
            assert s["answers"]["trust"] == 2 and s["answers"].get("predictable") is None
        else:
            assert s["answers"]["trust"] == 2  # the second value of the scale, by arrow key
    assert sessions[("P01", "schedule")]["cost"] > sessions[("P01", "robust")]["cost"]
