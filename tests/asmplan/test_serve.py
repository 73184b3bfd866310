"""``asmplan serve`` over real HTTP: the API contract, bad events, two sessions, a restart."""

from __future__ import annotations

import csv
import io
import json

import httpx
import pytest

from asmplan.advisor import Advisor
from asmplan.serve.app import MAX_BODY
from tests.asmplan.plans import cell_plan
from tests.asmplan.server import running

PLAN = cell_plan()


def _post(client, path, body):
    return client.post(path, json=body)


def _play_one(client, sid, advice, *, choose=-1):
    """One move: the robots' planned move, or the person's option ``choose``."""
    move = advice["robots"][0] if advice["turn"] == "robot" else advice["options"][choose]
    event = {"kind": "finished", "operation": move["operation"], "agent": move["agent"]}
    r = _post(client, f"/api/sessions/{sid}/events", event)
    assert r.status_code == 200, r.text
    return r.json()


def test_api_contract(tmp_path):
    with running([PLAN], tmp_path) as url, httpx.Client(base_url=url) as client:
        plans = client.get("/api/plans").json()
        assert plans == [
            {
                "id": "cell",
                "assembly": "cell",
                "turn_model": "alternate",
                "cost": "time",
                "tct": PLAN["tct"],
                "minimax": PLAN["minimax"],
                "w0": PLAN["metrics"]["w0"],
            }
        ]
        info = client.get("/api/plans/cell").json()
        assert info["robust_plan"] == PLAN["robust_plan"]
        assert set(info["operations"]) == set("abcdef")
        openapi = client.get("/openapi.json").json()
        assert "/api/sessions/{sid}/events" in openapi["paths"]
        assert "<title>" in client.get("/").text
        assert client.get("/static/plotly.min.js").status_code == 200
        r = _post(client, "/api/sessions", {"plan": "cell"})
        assert r.status_code == 201
        session = r.json()
        sid, advice = session["id"], session["advice"]
        local = Advisor(PLAN)
        assert advice == local.advice().to_dict()
        while not advice["finished"]:
            move = advice["robots"][0] if advice["turn"] == "robot" else advice["options"][0]
            advice = _play_one(client, sid, advice, choose=0)
            want = local.observe(
                {"kind": "finished", "operation": move["operation"], "agent": move["agent"]}
            )
            assert advice == want.to_dict()
        record = client.get(f"/api/sessions/{sid}").json()
        assert record["outcome"]["cost"] == advice["elapsed"]
        assert record["outcome"]["minimax"] == PLAN["minimax"]
        items = client.get("/api/questionnaire").json()
        answers = {items[0]["id"]: 4}
        r = _post(client, f"/api/sessions/{sid}/answers", {"answers": answers})
        assert r.status_code == 200 and r.json()["answers"] == answers
        rows = list(csv.DictReader(io.StringIO(client.get("/api/export.csv").text)))
        assert len(rows) == 1 and rows[0]["session"] == sid
        assert float(rows[0]["cost"]) == advice["elapsed"]
        assert json.loads(rows[0]["answers"]) == answers
    log = [json.loads(x) for x in (tmp_path / "log.jsonl").read_text().splitlines()]
    assert {x["change"] for x in log} == {"created", "event", "answers"}
    assert all("t" in x for x in log)
    assert log[-2]["outcome"]["cost"] == advice["elapsed"]


BAD = [
    ({"kind": "finished", "operation": "zz", "agent": "H"}, 409, "unknown operation 'zz'"),
    ({"kind": "finished", "operation": "c", "agent": "R1"}, 409, "may not do operation c"),
    ({"kind": "finished", "operation": "e", "agent": "R1"}, 409, "not the plan's move"),
    ({"kind": "finished", "operation": "c", "agent": "H"}, 409, "robots' turn"),
    ({"kind": "ended", "operation": "a", "agent": "H"}, 422, "kind"),
    ({"kind": "finished", "operation": "a"}, 422, "agent"),
    ({"kind": "finished", "operation": "a", "agent": "H", "extra": 1}, 422, "extra"),
]


@pytest.mark.parametrize(("event", "status", "message"), BAD)
def test_bad_events_are_refused_and_change_nothing(tmp_path, event, status, message):
    with running([PLAN], tmp_path) as url, httpx.Client(base_url=url) as client:
        sid = _post(client, "/api/sessions", {"plan": "cell"}).json()["id"]
        before = client.get(f"/api/sessions/{sid}").json()
        r = _post(client, f"/api/sessions/{sid}/events", event)
        assert r.status_code == status
        assert message in json.dumps(r.json()["detail"])
        assert client.get(f"/api/sessions/{sid}").json() == before


def test_unknown_ids_big_bodies_and_paths(tmp_path):
    with running([PLAN], tmp_path) as url, httpx.Client(base_url=url) as client:
        r = _post(
            client,
            "/api/sessions/nope/events",
            {"kind": "finished", "operation": "a", "agent": "H"},
        )
        assert r.status_code == 404 and "unknown session 'nope'" in r.json()["detail"]
        assert _post(client, "/api/sessions", {"plan": "other"}).status_code == 404
        big = {"kind": "finished", "operation": "a" * (MAX_BODY + 10), "agent": "H"}
        assert _post(client, "/api/sessions", big).status_code == 413
        for path in ("/static/../app.py", "/static/..%2F..%2Fplanfile.py", "/static/index.html"):
            assert client.get(path).status_code == 404, path


def test_two_sessions_at_once_keep_their_own_state(tmp_path):
    with running([PLAN], tmp_path) as url, httpx.Client(base_url=url) as client:
        a = _post(client, "/api/sessions", {"plan": "cell"}).json()
        b = _post(client, "/api/sessions", {"plan": "cell"}).json()
        assert a["id"] != b["id"]
        adv_a = _play_one(client, a["id"], a["advice"])
        adv_a = _play_one(client, a["id"], adv_a)
        now_b = client.get(f"/api/sessions/{b['id']}").json()
        assert now_b["advice"] == b["advice"] and now_b["events"] == []
        adv_b = _play_one(client, b["id"], b["advice"])
        assert client.get(f"/api/sessions/{a['id']}").json()["advice"] == adv_a
        assert adv_b != adv_a
        assert len(client.get("/api/sessions").json()) == 2


def test_restart_mid_game_loses_nothing(tmp_path):
    with running([PLAN], tmp_path) as url, httpx.Client(base_url=url) as client:
        s = _post(client, "/api/sessions", {"plan": "cell"}).json()
        advice = s["advice"]
        for _ in range(3):
            advice = _play_one(client, s["id"], advice)
        events = client.get(f"/api/sessions/{s['id']}").json()["events"]
    with running([PLAN], tmp_path) as url, httpx.Client(base_url=url) as client:
        again = client.get(f"/api/sessions/{s['id']}").json()
        assert again["advice"] == advice
        assert again["events"] == events
        while not advice["finished"]:
            advice = _play_one(client, s["id"], advice)
        assert client.get(f"/api/sessions/{s['id']}").json()["outcome"]["cost"] == advice["elapsed"]
