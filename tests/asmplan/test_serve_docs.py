"""``/docs`` over real HTTP: every file it names is served from this machine; ``/redoc``
(whose ReDoc loads its logo from a CDN) is off."""

from __future__ import annotations

import re

import httpx

from asmplan.serve.docs import DOCS_FILES
from tests.asmplan.plans import cell_plan
from tests.asmplan.server import running

PLAN = cell_plan()


def test_the_docs_page_names_only_local_files(tmp_path):
    with running([PLAN], tmp_path) as url, httpx.Client(base_url=url) as client:
        assert client.get("/redoc").status_code == 404
        page = client.get("/docs")
        assert page.status_code == 200
        named = re.findall(r"""(?:src|href|url)\s*[=:]\s*['"]([^'"]+)['"]""", page.text)
        assert named, page.text
        assert not [u for u in named if "//" in u], named  # no other host
        for ref in named:
            r = client.get(ref)
            assert r.status_code == 200, ref
            assert len(r.content) > 100, ref


def test_swagger_validates_nothing_online(tmp_path):
    with running([PLAN], tmp_path) as url:
        text = httpx.get(url + "/docs").text
    assert re.search(r'"validatorUrl"\s*:\s*null', text), text


def test_the_docs_files_are_a_fixed_table(tmp_path):
    with running([PLAN], tmp_path) as url, httpx.Client(base_url=url) as client:
        for name, media in DOCS_FILES.items():
            r = client.get(f"/docs-static/{name}")
            assert r.status_code == 200 and r.headers["content-type"].startswith(media)
        for bad in ("index.html", "..%2Fcore.py", "%2e%2e%2f%2e%2e%2fapp.py", "swagger-ui.css.map"):
            assert client.get(f"/docs-static/{bad}").status_code == 404, bad
