"""``asmplan serve`` with a concurrent plan, over real HTTP (uvicorn on 127.0.0.1, a free port):
the API contract, a game with deviations played to the end, bad events, two sessions, a
restart mid-game with the events' times and durations."""

from __future__ import annotations

import csv
import io
import json

import httpx
import pytest

from asmplan.advisor import Advisor
from tests.asmplan.plans import CHOICES, concurrent_plan, with_ranges
from tests.asmplan.server import running

PLAN = concurrent_plan(with_ranges(CHOICES))
EVENTS = "/api/sessions/{}/events"


def _next_event(advice: dict, k: int) -> dict:
    """A person who deviates at even ``k`` when she may, at her slowest; else the cell's
    next completion (the ``k``-th)."""
    if advice["options"]:
        deviations = [o for o in advice["options"] if o["deviation"]]
        pool = deviations if deviations and k % 2 == 0 else advice["options"]
        opt = pool[k % len(pool)]
        return {"kind": "started", **_pick(opt), "duration": opt["durations"][-1]}
    f = advice["finishes"][k % len(advice["finishes"])]
    return {"kind": "finished", **_pick(f), "time": f["time"]}


def _pick(move: dict) -> dict:
    return {"operation": move["operation"], "agent": move["agent"]}


def _step(client, sid, advice, k=0):
    r = client.post(EVENTS.format(sid), json=_next_event(advice, k))
    assert r.status_code == 200, r.text
    return r.json()


def test_concurrent_api_contract(tmp_path):
    with running([PLAN], tmp_path) as url, httpx.Client(base_url=url) as client:
        (summary,) = client.get("/api/plans").json()
        assert summary["id"] == "choices-concurrent" and summary["turn_model"] == "concurrent"
        info = client.get("/api/plans/choices-concurrent").json()
        assert info["robustness"] == PLAN["robustness"]
        assert info["robust_plan"] == PLAN["robust_plan"]
        s = client.post("/api/sessions", json={"plan": "choices-concurrent"}).json()
        sid, advice = s["id"], s["advice"]
        local = Advisor(PLAN)
        assert advice == local.advice().to_dict()
        assert advice["turn_model"] == "concurrent" and advice["budget"] == 2
        k = 0
        while not advice["finished"]:
            event = _next_event(advice, k)
            advice = _step(client, sid, advice, k)
            assert advice == local.observe(event).to_dict()
            k += 1
        record = client.get(f"/api/sessions/{sid}").json()
        out = record["outcome"]
        assert out["cost"] == advice["elapsed"] <= PLAN["minimax"]
        assert out["robustness"] == PLAN["robustness"] and out["deviations"] >= 1
        assert out["deviations"] == sum(e["deviation"] for e in record["events"])
        assert all("time" in e for e in record["events"] if e["kind"] == "finished")
        assert all("duration" in e for e in record["events"] if e["kind"] == "started")
        r = client.post(f"/api/sessions/{sid}/answers", json={"answers": {"trust": 2}})
        assert r.status_code == 200
        (row,) = csv.DictReader(io.StringIO(client.get("/api/export.csv").text))
        assert float(row["cost"]) == advice["elapsed"]
        assert int(row["deviations"]) == out["deviations"]
        assert int(row["choices"]) == sum(
            e["kind"] == "started" and e["by"] == "human" for e in record["events"]
        )


BAD = [
    ({"kind": "started", "operation": "zz", "agent": "H"}, 409, "unknown operation 'zz'"),
    ({"kind": "started", "operation": "s", "agent": "H"}, 409, "may not do operation s"),
    ({"kind": "started", "operation": "s", "agent": "R1"}, 409, "not the plan's move"),
    ({"kind": "started", "operation": "t", "agent": "R1"}, 409, "not the plan's move"),
    ({"kind": "finished", "operation": "p", "agent": "H"}, 409, "not running"),
    ({"kind": "started", "operation": "p", "agent": "H", "duration": 99}, 409, "duration 99"),
    ({"kind": "finished", "operation": "p", "agent": "H", "time": -1}, 422, "time"),
    ({"kind": "started", "operation": "p", "agent": "H", "when": 1}, 422, "when"),
]


@pytest.mark.parametrize(("event", "status", "message"), BAD)
def test_bad_events_are_refused_and_change_nothing(tmp_path, event, status, message):
    with running([PLAN], tmp_path) as url, httpx.Client(base_url=url) as client:
        sid = client.post("/api/sessions", json={"plan": "choices-concurrent"}).json()["id"]
        before = client.get(f"/api/sessions/{sid}").json()
        r = client.post(EVENTS.format(sid), json=event)
        assert r.status_code == status, r.text
        assert message in json.dumps(r.json()["detail"])
        assert client.get(f"/api/sessions/{sid}").json() == before


def test_two_sessions_and_a_restart_mid_game(tmp_path):
    with running([PLAN], tmp_path) as url, httpx.Client(base_url=url) as client:
        a = client.post("/api/sessions", json={"plan": "choices-concurrent"}).json()
        b = client.post("/api/sessions", json={"plan": "choices-concurrent"}).json()
        adv_a = a["advice"]
        for k in range(4):
            adv_a = _step(client, a["id"], adv_a, k)
        adv_b = _step(client, b["id"], b["advice"], 1)
        assert client.get(f"/api/sessions/{a['id']}").json()["advice"] == adv_a
        assert adv_a["elapsed"] > 0 and adv_b != adv_a
        events = client.get(f"/api/sessions/{a['id']}").json()["events"]
    with running([PLAN], tmp_path) as url, httpx.Client(base_url=url) as client:
        again = client.get(f"/api/sessions/{a['id']}").json()
        assert again["advice"] == adv_a and again["events"] == events
        assert client.get(f"/api/sessions/{b['id']}").json()["advice"] == adv_b
        advice, k = adv_a, 4
        while not advice["finished"]:
            advice = _step(client, a["id"], advice, k)
            k += 1
        assert client.get(f"/api/sessions/{a['id']}").json()["outcome"]["cost"] == advice["elapsed"]
