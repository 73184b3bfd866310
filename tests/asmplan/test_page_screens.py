"""The page on any screen and by keyboard, in headless Chromium (requests outside 127.0.0.1
aborted and recorded, ``tests/asmplan/browser.py``).

- At 360, 400 and 1400 px nothing is wider than the screen (no sideways scrolling), every
  move's button is on screen, and the numbers of the robots' list (10 and up) have room.
- A whole game and the questionnaire by keyboard alone: after each move the focus is on the
  next one, so Enter plays the plan; Tab reaches the questionnaire.
- A plan picker; an unknown ``?plan=`` is an error naming the plans there are (no session).

Screenshots go into the test's tmp folder. Skips like ``test_page_browser.py``.
"""

from __future__ import annotations

from pathlib import Path

import httpx
import pytest

from asmplan import pipeline
from asmplan.pipeline import build_plan
from tests.asmplan.browser import offline_page, wait_ready
from tests.asmplan.plans import cell_plan
from tests.asmplan.server import running
from tests.asmplan.test_page_browser import browser  # noqa: F401 (the fixture)

PUMP = Path(__file__).resolve().parents[2] / "examples" / "vacuum_pump"
FOCUSED = (
    "() => { const e = document.activeElement;"
    " return e ? [e.tagName, e.className, e.dataset.op || '', e.dataset.kind || ''] : null; }"
)


@pytest.fixture(scope="module")
def pump_plans():
    alternate = build_plan(PUMP)
    concurrent = pipeline.plan(PUMP, turn_model="concurrent", time_limit=20).to_dict()
    return alternate, concurrent


def _fits(page, width: int) -> None:
    wide = page.evaluate("() => document.documentElement.scrollWidth")
    assert wide <= width, f"the page is {wide} px wide on a {width} px screen"
    boxes = page.evaluate(
        "() => [...document.querySelectorAll('#options button.move, #finishes button,"
        " #view, #gantt')].map((e) => { const r = e.getBoundingClientRect();"
        " return [e.id || e.dataset.op, r.left, r.right]; })"
    )
    off = [b for b in boxes if b[1] < 0 or b[2] > width + 0.5]
    assert not off, off


@pytest.mark.slow
@pytest.mark.parametrize("width", [360, 400, 1400])
def test_the_page_fits_the_screen(browser, tmp_path, pump_plans, width):  # noqa: F811
    _, concurrent = pump_plans
    with running([concurrent], tmp_path / "state") as url:
        page, outside, errors = offline_page(browser, url, width)
        page.goto(url + "/")
        wait_ready(page)
        _fits(page, width)
        for k in range(14):
            buttons = page.locator("#options button.move, #finishes button")
            buttons.nth(k % buttons.count()).click()
            wait_ready(page)
            _fits(page, width)
        page.locator("#options details summary").first.click()  # the line behind an option
        _fits(page, width)
        page.screenshot(path=str(tmp_path / f"screen-{width}.png"), full_page=True)
        room = page.evaluate(
            "() => { const ol = document.getElementById('robot-log');"
            " const probe = document.createElement('span'); probe.textContent = '00.';"
            " ol.lastElementChild.append(probe); const w = probe.getBoundingClientRect().width;"
            " probe.remove(); return [ol.children.length, parseFloat(getComputedStyle(ol)"
            ".paddingLeft), w]; }"
        )
        assert errors == []
    assert outside == []
    n, padding, marker = room
    assert n >= 10 and padding >= marker + 4, room


@pytest.mark.slow
@pytest.mark.parametrize("which", ["alternate", "concurrent"])
def test_a_game_by_keyboard_only(browser, tmp_path, pump_plans, which):  # noqa: F811
    plan = pump_plans[which == "concurrent"]
    with running([plan], tmp_path / "state") as url:
        page, outside, errors = offline_page(browser, url, 400)
        page.goto(url + "/")
        wait_ready(page)
        moves = 0
        while not page.locator("#final").is_visible():
            tag, cls, op, kind = page.evaluate(FOCUSED)
            assert tag == "BUTTON" and (kind == "finish" or "move" in cls), (tag, cls)
            page.keyboard.press("Enter")
            page.wait_for_function(
                "() => ['1', 'done'].includes(document.body.dataset.ready)", timeout=30_000
            )
            moves += 1
            assert moves < 200
        page.wait_for_function("() => document.body.dataset.ready === 'done'", timeout=30_000)
        assert page.evaluate(FOCUSED)[0] == "H2"  # the end: "Done"
        answers = {}
        page.keyboard.press("Tab")  # the first scale item: its first value
        for _ in range(20):
            tag, _, _, _ = page.evaluate(FOCUSED)
            info = page.evaluate(
                "() => { const e = document.activeElement;"
                " return [e.type || '', e.name || '', e.id]; }"
            )
            if info[0] == "radio":
                page.keyboard.press("ArrowRight")  # checks the second value
                page.keyboard.press("ArrowRight")  # and the third
                answers[info[1]] = int(
                    page.evaluate(
                        f"() => document.querySelector('input[name={info[1]}]:checked').value"
                    )
                )
            elif info[0] == "text":
                page.keyboard.type("fine")
                answers[info[1]] = "fine"
            elif info[2] == "submit-answers":
                page.keyboard.press("Enter")
                break
            page.keyboard.press("Tab")
        page.wait_for_selector("#thanks:not([hidden])", timeout=30_000)
        page.screenshot(path=str(tmp_path / f"keyboard-{which}.png"), full_page=True)
        sid = page.evaluate("() => document.body.dataset.session")
        stored = httpx.get(f"{url}/api/sessions/{sid}").json()
        assert errors == []
    assert outside == []
    assert stored["outcome"]["deviations"] == 0  # Enter always plays the plan's move
    assert stored["outcome"]["cost"] == pytest.approx(stored["outcome"]["w0"])
    assert answers and stored["answers"] == answers
    assert all(v == 3 for k, v in answers.items() if isinstance(v, int))


@pytest.mark.slow
def test_a_plan_picker_and_an_unknown_plan(browser, tmp_path):  # noqa: F811
    plans = [cell_plan(), cell_plan("steps") | {"assembly": "cell in steps"}]
    with running(plans, tmp_path / "state") as url:
        page, outside, errors = offline_page(browser, url, 400)
        page.goto(url + "/?plan=no-such-plan")
        page.wait_for_function("() => document.body.dataset.ready === 'error'", timeout=30_000)
        error = page.locator("#error").inner_text()
        assert "unknown plan" in error and "no-such-plan" in error
        assert "cell" in error and "cell-in-steps" in error
        assert page.evaluate(FOCUSED)[0] == "SELECT"
        assert httpx.get(f"{url}/api/sessions").json() == []  # no session for a typo
        page.locator("#plan-pick").select_option("cell-in-steps")
        page.keyboard.press("Tab")
        page.keyboard.press("Enter")  # "open"
        page.wait_for_url("**/?plan=cell-in-steps", timeout=30_000)
        wait_ready(page)
        assert page.locator("#title").inner_text().startswith("cell in steps")
        assert page.locator("#wstar").inner_text().endswith("steps")
        first_tabs = []
        page.mouse.click(3, 3)  # the header's corner: Tab goes on from the top
        for _ in range(3):
            page.keyboard.press("Tab")
            first_tabs.append(
                page.evaluate("() => document.activeElement.id || document.activeElement.className")
            )
        assert errors == []
    assert outside == []
    assert first_tabs[:2] == ["plan-pick", "plan-open"] and "move" in first_tabs[2], first_tabs
