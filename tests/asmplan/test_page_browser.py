"""The page in a real headless Chromium (Debian's ``chromium``, driven by Playwright).

Loads the vacuum pump's page, plays a game to the end by clicking, checks that the robots'
replies and the final numbers are the policy's, and saves a screenshot in the test's tmp
folder. Skips, saying so, where no Chromium or no Playwright is found (never downloads a
browser).
"""

from __future__ import annotations

import shutil
from pathlib import Path

import httpx
import pytest

from asmplan.advisor import Advisor
from asmplan.pipeline import build_plan
from tests.asmplan.server import running

PUMP = Path(__file__).resolve().parents[2] / "examples" / "vacuum_pump"
CHROMIUM_FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
]


def chromium_path() -> str | None:
    for name in ("chromium", "chromium-browser"):
        found = shutil.which(name)
        if found:
            return found
    return None


@pytest.fixture(scope="module")
def browser():
    path = chromium_path()
    if path is None:
        pytest.skip("no Chromium found (apt-get install chromium): browser test skipped")
    sync_api = pytest.importorskip("playwright.sync_api", reason="Playwright not installed")
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=path, args=CHROMIUM_FLAGS, headless=True)
        yield b
        b.close()


@pytest.mark.slow
def test_play_the_pump_to_the_end(browser, tmp_path):
    plan = build_plan(PUMP)
    with running([plan], tmp_path / "state") as url:
        page = browser.new_page(viewport={"width": 1280, "height": 900})
        errors: list[str] = []
        page.on("pageerror", lambda exc: errors.append(str(exc)))
        page.goto(url + "/")
        page.wait_for_function(
            "() => ['1', 'done'].includes(document.body.dataset.ready)", timeout=30_000
        )
        assert page.locator("#wstar").inner_text() == f"{plan['minimax']:g} s"
        clicked = []
        for k in range(100):
            if page.locator("#final").is_visible():
                break
            buttons = page.locator("#options button")
            n = buttons.count()
            pick = buttons.nth(k % n)
            clicked.append((pick.get_attribute("data-op"), pick.get_attribute("data-agent")))
            if k == 3:
                page.screenshot(path=str(tmp_path / "page-mid-game.png"))
            pick.click()
            page.wait_for_function(
                "() => ['1', 'done'].includes(document.body.dataset.ready)", timeout=30_000
            )
        page.wait_for_selector("#final:not([hidden])", timeout=30_000)
        page.screenshot(path=str(tmp_path / "page-end.png"), full_page=True)
        robots = [
            (li.get_attribute("data-op"), li.get_attribute("data-agent"))
            for li in page.locator("#robot-log li:not(.person)").all()
        ]
        final = float(page.locator("#final-cost").get_attribute("data-value"))
        answers = _answer_the_questionnaire(page)
        sid = page.evaluate("() => document.body.dataset.session")
        stored = httpx.get(f"{url}/api/sessions/{sid}").json()
        assert errors == []
    assert stored["answers"] == answers and stored["outcome"]["cost"] == final
    # The same choices through the advisor: the same robots' replies, the same cost.
    advisor = Advisor(plan)
    want_robots, choices = [], list(clicked)
    advice = advisor.advice()
    while not advice.finished:
        if advice.turn == "robot":
            move = advice.robots[0]
            want_robots.append((move["operation"], move["agent"]))
        else:
            op, agent = choices.pop(0)
            move = {"operation": op, "agent": agent}
        advice = advisor.observe({"kind": "finished", **move})
    assert choices == []
    assert robots == want_robots
    assert final == advice.elapsed
    assert (tmp_path / "page-end.png").stat().st_size > 10_000
    assert plan["metrics"]["w0"] <= final <= plan["minimax"]


def _answer_the_questionnaire(page) -> dict:
    """Fill every item (a scale: its top value; a text: a sentence) and send the answers."""
    page.wait_for_selector("#submit-answers", timeout=30_000)
    answers = {}
    for scale in page.locator("#questionnaire fieldset[data-item]").all():
        top = scale.locator("input[type=radio]").last
        top.check()
        answers[top.get_attribute("name")] = int(top.get_attribute("value"))
    for item in page.locator("#questionnaire input[type=text]").all():
        item.fill("the robots waited for me")
        answers[item.get_attribute("name")] = "the robots waited for me"
    page.click("#submit-answers")
    page.wait_for_selector("#thanks:not([hidden])", timeout=30_000)
    return answers


@pytest.mark.slow
def test_play_the_concurrent_pump_to_the_end(browser, tmp_path):
    """The pump in the concurrent game: start operations and let the cell run to each next
    completion by clicking; the robots' replies, the clock and the final numbers are the
    policy's (replayed through the advisor), W*(0) = 215 s."""
    from asmplan import pipeline

    plan = pipeline.plan(PUMP, turn_model="concurrent", time_limit=20).to_dict()
    w0 = plan["robustness"][0]["bound"]
    with running([plan], tmp_path / "state") as url:
        page = browser.new_page(viewport={"width": 1280, "height": 1000})
        errors: list[str] = []
        page.on("pageerror", lambda exc: errors.append(str(exc)))
        page.goto(url + "/")
        ready = "() => ['1', 'done'].includes(document.body.dataset.ready)"
        page.wait_for_function(ready, timeout=30_000)
        assert page.locator("#w0").inner_text() == f"{w0:g} s"
        assert page.locator("#concurrent-panel").is_visible()
        events = []
        for k in range(400):
            if page.locator("#final").is_visible():
                break
            starts = page.locator('#options button[data-kind="start"]')
            finishes = page.locator("#finishes button")
            if starts.count():
                pick = starts.nth(k % starts.count())
                event = {"kind": "started", "duration": float(pick.get_attribute("data-duration"))}
            else:
                pick = finishes.nth(k % finishes.count())
                event = {"kind": "finished", "time": float(pick.get_attribute("data-time"))}
            event.update(
                operation=pick.get_attribute("data-op"), agent=pick.get_attribute("data-agent")
            )
            events.append(event)
            if k == 12:
                page.screenshot(path=str(tmp_path / "concurrent-mid-game.png"))
            pick.click()
            page.wait_for_function(ready, timeout=30_000)
        page.wait_for_selector("#final:not([hidden])", timeout=30_000)
        page.screenshot(path=str(tmp_path / "concurrent-end.png"), full_page=True)
        robots = [
            (
                li.get_attribute("data-op"),
                li.get_attribute("data-agent"),
                li.get_attribute("data-time"),
            )
            for li in page.locator("#robot-log li:not(.person)").all()
        ]
        final = float(page.locator("#final-cost").get_attribute("data-value"))
        shown_w0 = float(page.locator("#final-w0").get_attribute("data-value"))
        assert errors == []
    # The same events through the advisor: the same robots' replies at the same times.
    advisor = Advisor(plan)
    advice = advisor.advice()
    want = [(None, None, "0")] if not advice.robots else []
    want += [(r["operation"], r["agent"], "0") for r in advice.robots]
    for event in events:
        before = advice
        advice = advisor.observe(event)
        fresh = (advice.state, advice.elapsed) != (before.state, before.elapsed)
        if fresh and not advice.finished:
            t = f"{advice.elapsed:g}"
            want += [(r["operation"], r["agent"], t) for r in advice.robots] or [(None, None, t)]
    assert advice.finished and robots == want
    assert final == advice.elapsed == w0 == shown_w0  # the pump: no choice costs anything
    assert plan["minimax"] == w0
    assert (tmp_path / "concurrent-end.png").stat().st_size > 10_000
