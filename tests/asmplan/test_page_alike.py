"""The page in a real headless Chromium with alike parts: the person picks which alike part.

A ring of pins, each with its roller, planned with the symmetry reduction: an option naming
one of several alike pins has a choice of which (``select.alike``). The person always picks
the last one offered, so she places the pins in the reverse of the plan's order; the game
ends within the plan's bound and the service stored her physical choices. Skips like
``test_page_browser.py`` where no Chromium or Playwright is found.
"""

from __future__ import annotations

import httpx
import pytest

from tests.asmplan.plans import alike_plan
from tests.asmplan.server import running
from tests.asmplan.test_page_browser import browser  # noqa: F401 (the fixture)
from tests.asp.helpers_assembly import pin_roller_ring

READY = "() => ['1', 'done'].includes(document.body.dataset.ready)"


@pytest.mark.slow
@pytest.mark.parametrize("turn_model", ["alternate", "concurrent"])
def test_the_person_picks_which_alike_part(browser, tmp_path, turn_model):  # noqa: F811
    plan = alike_plan(*pin_roller_ring(3), turn_model)
    picked = []
    with running([plan], tmp_path / "state") as url:
        page = browser.new_page(viewport={"width": 1280, "height": 900})
        errors: list[str] = []
        page.on("pageerror", lambda exc: errors.append(str(exc)))
        page.goto(url + "/")
        page.wait_for_function(READY, timeout=30_000)
        for k in range(200):
            if page.locator("#final").is_visible():
                break
            alike = page.locator("#options select.alike")
            starts = page.locator("#options button")
            if alike.count():
                pick = alike.nth(0)
                values = pick.locator("option").evaluate_all("(os) => os.map((o) => o.value)")
                pick.select_option(values[-1])
                picked.append(values[-1])
                op = pick.get_attribute("data-alike-for")
                button = page.locator(f'#options button[data-op="{op}"]').first
            elif starts.count():
                button = starts.nth(k % starts.count())
            else:
                button = page.locator("#finishes button").first
            button.click()
            page.wait_for_function(READY, timeout=30_000)
        page.wait_for_selector("#final:not([hidden])", timeout=30_000)
        sid = page.evaluate("() => document.body.dataset.session")
        stored = httpx.get(f"{url}/api/sessions/{sid}").json()
        assert errors == []
    assert picked and picked[0] == "pin2"  # the last pin offered, not the plan's pin0
    person = [e["operation"] for e in stored["events"] if e["by"] == "human"]
    assert "pin2" in person
    assert stored["outcome"]["cost"] <= plan["minimax"] + 1e-9
