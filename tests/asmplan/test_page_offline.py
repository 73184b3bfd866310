"""Nothing leaves the machine: the page and the API docs in headless Chromium with every
request not to 127.0.0.1 aborted and recorded (``tests/asmplan/browser.py``).

The pump's page is played a few moves (the 3D view and the Gantt chart drawn, their
toolbars shown) at a desktop and a phone width; then ``/docs`` (Swagger UI) renders and
opens an operation. The plotly toolbars have no cloud button and stay out of the Tab order.
Skips like ``test_page_browser.py`` where no Chromium or Playwright is found.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from asmplan.pipeline import build_plan
from tests.asmplan.browser import offline_page, wait_ready
from tests.asmplan.server import running
from tests.asmplan.test_page_browser import browser  # noqa: F401 (the fixture)

PUMP = Path(__file__).resolve().parents[2] / "examples" / "vacuum_pump"
CLOUD_WORDS = ("share", "cloud", "studio", "edit", "plotly")


@pytest.fixture(scope="module")
def pump_plan():
    return build_plan(PUMP)


def test_the_record_sees_a_request_to_the_outside(browser, tmp_path, pump_plan):  # noqa: F811
    """The record is not empty by construction: a page that asks the outside is caught."""
    with running([pump_plan], tmp_path / "state") as url:
        page, outside, _ = offline_page(browser, url, 800)
        page.goto(url + "/")
        page.evaluate("() => fetch('https://cdn.example.invalid/x.js').catch(() => 0)")
        page.evaluate(
            "() => new Promise((ok) => { const i = new Image(); i.onerror = ok;"
            " i.src = 'http://192.0.2.1/x.png'; })"
        )
    assert outside == ["https://cdn.example.invalid/x.js", "http://192.0.2.1/x.png"]


@pytest.mark.slow
@pytest.mark.parametrize("width", [1400, 400])
def test_nothing_leaves_the_machine(browser, tmp_path, pump_plan, width):  # noqa: F811
    with running([pump_plan], tmp_path / "state") as url:
        page, outside, errors = offline_page(browser, url, width)
        page.goto(url + "/")
        wait_ready(page)
        for _ in range(3):
            page.locator("#options button").first.click()
            wait_ready(page)
        page.hover("#view")
        page.hover("#gantt")
        titles = page.evaluate(
            "() => [...document.querySelectorAll('.modebar-btn')]"
            ".map((b) => [b.getAttribute('data-title') || '', b.tabIndex])"
        )
        links = page.evaluate("() => [...document.querySelectorAll('[href]')].map((a) => a.href)")
        page.screenshot(path=str(tmp_path / f"offline-{width}.png"), full_page=True)
        page.goto(url + "/docs")
        page.wait_for_selector(".swagger-ui .info .title", timeout=30_000)
        assert "asmplan advisor" in page.locator(".swagger-ui .info .title").inner_text()
        page.locator(".opblock-summary").first.click()  # open one operation
        page.wait_for_selector(".opblock-body", timeout=10_000)
        links += page.evaluate("() => [...document.querySelectorAll('[href]')].map((a) => a.href)")
        assert errors == []
    assert outside == []
    assert titles and all(tab == -1 for _, tab in titles), titles
    assert not [t for t, _ in titles if any(w in t.lower() for w in CLOUD_WORDS)], titles
    assert all(link.startswith(url) for link in links), links
