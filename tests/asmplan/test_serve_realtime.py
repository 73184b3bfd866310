"""Real time over real HTTP: the clock runs, operations finish on it in wall-clock time
(scaled), the clock holds while the person chooses, and a restart goes on from there."""

from __future__ import annotations

import httpx
import pytest

from tests.asmplan.plans import CHOICES, cell_plan, concurrent_plan, with_ranges
from tests.asmplan.server import running

SPEED = 2.0  # game seconds per wall-clock second


def _start(advice: dict) -> dict:
    """The person's start of the instruction's operation (else the first option)."""
    options = advice["options"]
    pick = next((o for o in options if not o.get("deviation")), options[0])
    ev = {"kind": "started", "operation": pick["operation"], "agent": pick["agent"]}
    if pick.get("durations"):
        ev["duration"] = pick["durations"][-1]
    return ev


@pytest.mark.parametrize("plan", [concurrent_plan(with_ranges(CHOICES)), cell_plan()], ids=str)
def test_the_clock_finishes_operations_in_wall_time(tmp_path, plan):
    now = [1000.0]
    pid = "choices-concurrent" if plan["turn_model"] == "concurrent" else "cell"
    service = running([plan], tmp_path, realtime=SPEED, clock=lambda: now[0])
    with service as url, httpx.Client(base_url=url) as c:
        start = c.get(f"/api/plans/{pid}/advice").json()
        if not start["options"]:  # the robots move first: the session starts with a wait
            s = c.post("/api/sessions", json={"plan": pid}).json()
        else:
            s = c.post("/api/sessions", json={"plan": pid, "event": _start(start)}).json()
        sid = s["id"]
        assert s["clock"]["speed"] == SPEED
        finish = {"kind": "finished", "operation": "x", "agent": "H"}
        r = c.post(f"/api/sessions/{sid}/events", json=finish)
        assert r.status_code == 409 and "finish on its clock" in r.json()["detail"]
        for _ in range(200):
            view = c.get(f"/api/sessions/{sid}/advice").json()
            if view["finished"]:
                break
            clock = view["clock"]
            if clock["holding"]:
                held = now[0]
                now[0] += 3  # she thinks for 3 s: the game clock holds
                again = c.get(f"/api/sessions/{sid}/advice").json()
                assert again["clock"]["game_time"] == clock["game_time"]
                assert now[0] > held
                r = c.post(f"/api/sessions/{sid}/events", json=_start(view["advice"]))
                assert r.status_code == 200, r.text
                continue
            nxt = clock["next"]
            assert nxt is not None
            now[0] = nxt["wall"] - 0.01  # not yet
            before = c.get(f"/api/sessions/{sid}/advice").json()["events"]
            assert before == view["events"]
            now[0] = nxt["wall"] + 0.01  # now due
        else:
            pytest.fail("the game did not end")
        record = c.get(f"/api/sessions/{sid}").json()
    clocked = [e for e in record["events"] if e.get("source") == "clock"]
    assert clocked and all(e["kind"] == "finished" or e["by"] == "robot" for e in clocked)
    assert record["outcome"]["cost"] == record["advice"]["elapsed"]
    mine = [e for e in record["events"] if e["by"] == "human" and e["kind"] == "started"]
    assert any(e["decision_s"] >= 3 for e in mine)
    # each completion was recorded when it fell due: game time advances at SPEED
    created = record["created"]
    for e in clocked:
        if e["kind"] == "finished" and "time" in e:
            held = sum(x["decision_s"] for x in mine if x["t"] <= e["t"])
            assert e["t"] == pytest.approx(created + held + e["time"] / SPEED, abs=0.05)


def test_a_restart_goes_on_with_the_clock(tmp_path):
    plan = concurrent_plan(with_ranges(CHOICES))
    now = [1000.0]
    first = running([plan], tmp_path, realtime=SPEED, clock=lambda: now[0])
    with first as url, httpx.Client(base_url=url) as c:
        start = c.get("/api/plans/choices-concurrent/advice").json()
        body = {"plan": "choices-concurrent", "event": _start(start)}
        s = c.post("/api/sessions", json=body).json()
        nxt = s["clock"]["next"]
    now[0] = nxt["wall"] + 0.01
    second = running([plan], tmp_path, realtime=SPEED, clock=lambda: now[0])
    with second as url, httpx.Client(base_url=url) as c:
        events = c.get(f"/api/sessions/{s['id']}").json()["events"]
    assert events[-1]["source"] == "clock" and events[-1]["operation"] == nxt["operation"]
    assert events[-1]["t"] == pytest.approx(nxt["wall"])
