"""The page's explanation routes over real HTTP: the explained advice of a session and of a
plan's start, the plain event answer unchanged."""

from __future__ import annotations

import httpx

from asmplan.advisor import Advisor
from tests.asmplan.plans import CHOICES, cell_plan, concurrent_plan
from tests.asmplan.server import running

PLANS = [cell_plan(), concurrent_plan(CHOICES)]


def test_a_session_and_a_plan_start_explain_themselves(tmp_path):
    with running(PLANS, tmp_path) as url, httpx.Client(base_url=url) as client:
        for plan in client.get("/api/plans").json():
            doc = next(d for d in PLANS if d["assembly"] == plan["assembly"])
            start = client.get(f"/api/plans/{plan['id']}/explain")
            assert start.status_code == 200
            assert start.json() == Advisor(doc).explain().to_dict()
            session = client.post("/api/sessions", json={"plan": plan["id"]}).json()
            assert "line" not in str(session["advice"]["options"])  # the plain advice
            sid = session["id"]
            advisor = Advisor(doc)
            advice = advisor.advice()
            while advice.turn == "robot" and not advice.finished:
                event = {
                    "kind": "finished",
                    **{k: advice.robots[0][k] for k in ("operation", "agent")},
                }
                assert client.post(f"/api/sessions/{sid}/events", json=event).status_code == 200
                advice = advisor.observe(event)
            got = client.get(f"/api/sessions/{sid}/explain").json()
            assert got == advisor.explain().to_dict()
            assert got["options"] and all(o["why"] and o["line"] for o in got["options"])
            assert got["ahead"]
        assert client.get("/api/sessions/nope/explain").status_code == 404
        missing = client.get("/api/plans/nope/explain")
        assert missing.status_code == 404 and "nope" in missing.json()["detail"]
