"""Helpers of the page tests in headless Chromium: a page that cannot reach the outside.

:func:`offline_page` opens a page on which every request not to the test server is aborted
before it is sent and recorded, so a test asserts the record is empty: nothing the page
loads, links or posts leaves the machine.
"""

from __future__ import annotations

READY = "() => ['1', 'done'].includes(document.body.dataset.ready)"
"""The page has shown its advice (``1``) or the end of the game (``done``)."""


def offline_page(browser, url: str, width: int, height: int = 900):
    """A new page of ``width`` x ``height`` px whose requests outside ``url`` are aborted
    and listed; returns ``(page, outside, errors)`` (the lists fill as the page runs)."""
    page = browser.new_page(viewport={"width": width, "height": height})
    outside: list[str] = []
    errors: list[str] = []

    def route(r):
        if r.request.url == url or r.request.url.startswith(url + "/"):
            r.continue_()
        else:
            outside.append(r.request.url)
            r.abort()

    page.route("**/*", route)
    page.on("websocket", lambda ws: outside.append(ws.url))
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    return page, outside, errors


def wait_ready(page, timeout: float = 30_000) -> None:
    page.wait_for_function(READY, timeout=timeout)
