"""The page in a real headless Chromium (Debian's ``chromium``, driven by Playwright).

Loads the vacuum pump's page, plays a game to the end by clicking, checks that the robots'
replies and the final numbers are the policy's, and saves a screenshot in the test's tmp
folder. Skips, saying so, where no Chromium or no Playwright is found (never downloads a
browser).
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from asmplan.advisor import Advisor
from asmplan.planfile import build_plan
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
            for li in page.locator("#robot-log li").all()
        ]
        final = float(page.locator("#final-cost").inner_text())
        assert errors == []
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
