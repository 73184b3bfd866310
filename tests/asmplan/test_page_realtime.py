"""The page in real time (``asmplan serve --realtime SPEED``), in headless Chromium, and the
completions that explain themselves.

In real time the service's clock finishes operations: the page polls
``/api/sessions/{id}/advice``, shows the clock running (and holding while the person must
choose), offers no completion buttons (it says what the cell does next if she starts
nothing, with its reason) and the person only starts operations. A game is played to the
end in both turn models with every request outside 127.0.0.1 aborted; the record has the
clock's completions at their wall-clock times and the person's decision times. Without
real time each completion button says the robots' reply and the worst line behind it.
"""

from __future__ import annotations

import time

import httpx
import pytest

from tests.asmplan.browser import offline_page, wait_ready
from tests.asmplan.plans import CHOICES, cell_plan, concurrent_plan, with_ranges
from tests.asmplan.server import running
from tests.asmplan.test_page_browser import browser  # noqa: F401 (the fixture)

pytestmark = pytest.mark.slow
SPEED = 6.0
PLANS = {
    "concurrent": (lambda: concurrent_plan(with_ranges(CHOICES)), "choices-concurrent"),
    "alternate": (cell_plan, "cell"),
}


def _clock(page) -> tuple[float, bool]:
    node = page.locator("#realtime")
    return float(node.get_attribute("data-time") or 0), node.get_attribute("data-holding") == "1"


@pytest.mark.parametrize("turn_model", sorted(PLANS))
def test_a_game_in_real_time(browser, tmp_path, turn_model):  # noqa: F811
    make, pid = PLANS[turn_model]
    plan = make()
    with running([plan], tmp_path / "state", realtime=SPEED) as url:
        page, outside, errors = offline_page(browser, url, 1200)
        page.goto(f"{url}/?plan={pid}")
        wait_ready(page)
        assert page.locator("#realtime").is_visible()
        assert f"running at {SPEED:g} s of cell time per second" in page.inner_text("#realtime")
        ran, upcoming, started, shot = [], 0, 0, False
        deadline = time.monotonic() + 120
        while not page.locator("#final").is_visible():
            assert time.monotonic() < deadline, "the game did not end in real time"
            assert page.locator("#finishes button").count() == 0  # the clock finishes them
            for item in page.locator("#finishes .upcoming .why").all_inner_texts():
                assert "start nothing more" in item and "the worst that can still happen" in item
                upcoming += 1
            moves = page.locator("#options button.move")
            if moves.count() and page.evaluate("document.body.dataset.ready") == "1":
                try:
                    moves.first.click(timeout=2_000)
                    started += 1
                except Exception:  # the clock re-drew the options under the click: again
                    pass
                continue
            t0, holding = _clock(page)
            page.wait_for_timeout(400)
            t1, _ = _clock(page)
            if not holding:
                ran.append(t1 - t0)
            if not shot and ran:
                page.screenshot(path=str(tmp_path / f"realtime-{turn_model}-mid.png"))
                shot = True
        page.wait_for_selector("#submit-answers", timeout=30_000)
        page.screenshot(path=str(tmp_path / f"realtime-{turn_model}-end.png"), full_page=True)
        sid = page.evaluate("document.body.dataset.session")
        final = float(page.locator("#final-cost").get_attribute("data-value"))
        record = httpx.get(f"{url}/api/sessions/{sid}").json()
        assert outside == [] and errors == []
    assert started >= 2 and any(d > 0 for d in ran), ran  # the clock ran by itself
    if turn_model == "concurrent":
        assert upcoming, "no completion said what the cell does next"
    events = record["events"]
    clocked = [e for e in events if e.get("source") == "clock"]
    assert clocked and all(e["kind"] == "finished" or e["by"] == "robot" for e in clocked)
    mine = [e for e in events if e["by"] == "human" and e["kind"] == "started"]
    assert mine and all("decision_s" in e for e in mine)
    assert all(e.get("source") == "clock" for e in events if e["kind"] == "finished")
    assert final == record["outcome"]["cost"] == record["advice"]["elapsed"]
    # each completion fell due when the game clock reached it (never before)
    for e in clocked:
        if e["kind"] == "finished" and "time" in e:
            assert e["t"] - record["created"] >= e["time"] / SPEED - 0.05


def test_each_completion_explains_itself(browser, tmp_path):  # noqa: F811
    """Without real time: each "R1 finishes s at 8 s" button says the robots' reply and the
    worst case in words, and opens the worst line behind it."""
    plan = concurrent_plan(CHOICES)
    with running([plan], tmp_path / "state") as url:
        page, outside, errors = offline_page(browser, url, 1200)
        page.goto(f"{url}/?plan=choices-concurrent")
        wait_ready(page)
        page.locator("#options button.move").first.click()
        wait_ready(page)
        # no meshes: no 3D view, and the moves take the whole width
        assert not page.locator("#view-panel").is_visible()
        assert page.locator("#play-panel").bounding_box()["width"] > 0.9 * 1200
        # what runs is drawn once: not again in the plan ahead
        traces = page.evaluate(
            "() => Object.fromEntries(document.getElementById('gantt').data.map("
            "(t) => [t.name, (t.hovertext || []).map((h) => h.split(':')[0])]))"
        )
        now = set(traces["running (to its planned end)"])
        assert now and not now & set(traces["the plan ahead (if you follow it)"])
        finishes = page.locator("#finishes .finish")
        assert finishes.count() >= 1
        first = finishes.first
        why = first.locator("button .why").inner_text()
        worst = float(first.locator("button").get_attribute("data-worst"))
        assert why.startswith("If you") and why.endswith(f"is {worst:g} s.")
        assert "start nothing more" in why
        first.locator("details summary").click()
        steps = first.locator("details li").all_inner_texts()
        assert steps[-1] == f"the assembly is complete at {worst:g} s"
        assert all(" s: " in s for s in steps[:-1])
        page.screenshot(path=str(tmp_path / "completion-explained.png"), full_page=True)
        assert outside == [] and errors == []
