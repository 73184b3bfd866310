"""The service's storage over real HTTP: a killed service loses nothing it acknowledged, a
full disk changes nothing (503), bad sessions are set aside and named, the bounds (body,
sessions, idle time), a busy port, the per-user default folder, HEAD."""

from __future__ import annotations

import json
import os
import random
import shutil
import signal
import socket
import subprocess
import threading
import time
from pathlib import Path

import httpx
import pytest

from asmplan.planfile import write_plan
from asmplan.serve.sessions import SessionStore
from tests.asmplan.plans import CELL, cell_plan
from tests.asmplan.serve_proc import serve_args, serving
from tests.asmplan.server import running

PLAN = cell_plan()


def _move(advice: dict, choose: int = 0) -> dict:
    """The robots' planned move, or the person's option ``choose`` (alternating game)."""
    move = advice["robots"][0] if advice["turn"] == "robot" else advice["options"][choose]
    return {"kind": "finished", "operation": move["operation"], "agent": move["agent"]}


def _plan_dir(tmp_path: Path, plan: dict = PLAN) -> Path:
    folder = tmp_path / "plan"
    write_plan(folder / "plan.json", plan)
    return folder


def _play(client, sid: str, advice: dict, n: int) -> dict:
    for _ in range(n):
        r = client.post(f"/api/sessions/{sid}/events", json=_move(advice))
        assert r.status_code == 200, r.text
        advice = r.json()
    return advice


# --------------------------------------------------------------------------- kills


def test_sigkill_loses_no_acknowledged_event(tmp_path):
    """Eight clients post events as fast as they can; the service is killed (SIGKILL) in
    the middle; after a restart every acknowledged event is there, in order."""
    plan_dir, state = _plan_dir(tmp_path), tmp_path / "state"
    acked: dict[str, list[dict]] = {}
    args = serve_args(plan_dir, "--sessions", state)
    with serving(args) as (url, proc, _):
        stop = threading.Event()

        def client(seed: int):
            rng = random.Random(seed)
            with httpx.Client(base_url=url, timeout=5) as c:
                while not stop.is_set():
                    try:
                        start = c.get("/api/plans/cell/advice").json()
                        event = _move(start, rng.randrange(len(start["options"]) or 1))
                        r = c.post("/api/sessions", json={"plan": "cell", "event": event})
                        if r.status_code != 201:
                            return
                        sid, advice = r.json()["id"], r.json()["advice"]
                        acked[sid] = [event]
                        while not advice["finished"] and not stop.is_set():
                            ev = _move(advice, rng.randrange(max(len(advice["options"]), 1)))
                            r = c.post(f"/api/sessions/{sid}/events", json=ev)
                            if r.status_code != 200:
                                return
                            acked[sid].append(ev)
                            advice = r.json()
                    except httpx.HTTPError:
                        return

        threads = [threading.Thread(target=client, args=(k,)) for k in range(8)]
        for t in threads:
            t.start()
        deadline = time.monotonic() + 30
        while sum(map(len, acked.values())) < 300 and time.monotonic() < deadline:
            time.sleep(0.01)  # kill in full flight, after some hundred events
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        stop.set()
        for t in threads:
            t.join(timeout=10)
    assert sum(map(len, acked.values())) > 20
    restarted = serving(serve_args(plan_dir, "--sessions", state))
    with restarted as (url, _, _), httpx.Client(base_url=url) as c:
        for sid, events in acked.items():
            got = c.get(f"/api/sessions/{sid}").json()["events"]
            assert len(got) >= len(events), sid
            for want, have in zip(events, got, strict=False):
                assert (have["operation"], have["agent"]) == (want["operation"], want["agent"])


# --------------------------------------------------------------------------- a full disk


def _can_mount() -> bool:
    if shutil.which("unshare") is None or os.geteuid() != 0:
        return False
    probe = subprocess.run(
        ["unshare", "-m", "sh", "-c", "mount -t tmpfs -o size=64k tmpfs /mnt"],
        capture_output=True,
    )
    return probe.returncode == 0


@pytest.mark.skipif(not _can_mount(), reason="needs root and unshare to mount a small tmpfs")
def test_full_disk_changes_nothing_and_answers_503(tmp_path):
    """The sessions folder on a 1 MB tmpfs, filled: every refused event leaves the session
    as it was (503 with the reason, again on a retry: never 409 'already done'); once
    space is freed the same event is taken."""
    plan_dir, mnt = _plan_dir(tmp_path), tmp_path / "mnt"
    mnt.mkdir()
    args = serve_args(plan_dir, "--sessions", mnt / "state")
    script = f'mount -t tmpfs -o size=1m tmpfs {mnt} && mkdir {mnt}/state && exec "$@"'
    with serving(args, prefix=["unshare", "-m", "sh", "-c", script, "sh"]) as (url, proc, _):
        inside = Path(f"/proc/{proc.pid}/root") / str(mnt).lstrip("/")
        with httpx.Client(base_url=url, timeout=10) as c:
            s = c.post("/api/sessions", json={"plan": "cell"}).json()
            sid, advice = s["id"], s["advice"]
            advice = _play(c, sid, advice, 1)
            before = c.get(f"/api/sessions/{sid}").json()
            filler = inside / "filler"
            with open(filler, "wb") as f, pytest.raises(OSError):  # fill the disk
                while True:
                    f.write(b"\0" * 65536)
                    f.flush()
            event = _move(advice)
            refused = None
            for _ in range(200):  # the WAL may still have room for a few pages
                r = c.post(f"/api/sessions/{sid}/events", json=event)
                if r.status_code == 503:
                    refused = r
                    break
                assert r.status_code == 200, r.text
                advice = r.json()
                before = c.get(f"/api/sessions/{sid}").json()
                if advice["finished"]:
                    s = c.post("/api/sessions", json={"plan": "cell"})
                    if s.status_code == 503:
                        refused = s
                        break
                    sid, advice = s.json()["id"], s.json()["advice"]
                    before = c.get(f"/api/sessions/{sid}").json()
                event = _move(advice)
            assert refused is not None, "the disk never filled"
            assert "full" in refused.json()["detail"] and "nothing was changed" in refused.text
            if refused.request.url.path.endswith("/events"):
                assert c.get(f"/api/sessions/{sid}").json() == before
                again = c.post(f"/api/sessions/{sid}/events", json=event)
                assert again.status_code == 503, again.text
                assert c.get(f"/api/sessions/{sid}").json() == before
                filler.unlink()
                taken = c.post(f"/api/sessions/{sid}/events", json=event)
                assert taken.status_code == 200, taken.text
                after = c.get(f"/api/sessions/{sid}").json()
                assert after["events"] == before["events"] + [after["events"][-1]]


def test_a_refused_commit_keeps_memory_and_disk_alike(tmp_path):
    """The database refusing to grow (SQLite's page limit: the same error as a full disk):
    the event is refused, memory unchanged, and a restart shows what memory showed."""
    store = SessionStore(tmp_path, {"cell": PLAN})
    session = store.create("cell")
    store.observe(session.id, _move(session.advisor.advice().to_dict()))
    (pages,) = store._db.execute("PRAGMA page_count").fetchone()
    store._db.execute(f"PRAGMA max_page_count={pages}")
    advice = session.advisor.advice().to_dict()
    events = list(session.events)
    from asmplan.serve.sessions import StorageError

    for _ in range(200):
        if session.advisor.finished:
            session = store.create("cell")
        try:
            store.observe(session.id, _move(session.advisor.advice().to_dict()))
        except StorageError as exc:
            assert "full" in str(exc)
            break
        advice, events = session.advisor.advice().to_dict(), list(session.events)
    else:
        pytest.fail("the page limit never refused a commit")
    assert session.advisor.advice().to_dict() == advice and session.events == events
    store.close()
    again = SessionStore(tmp_path, {"cell": PLAN})
    assert again.get(session.id).advisor.advice().to_dict() == advice
    assert again.get(session.id).events == events


# --------------------------------------------------------------------------- bad sessions


def _legacy(folder: Path, name: str, text: str) -> None:
    (folder / "sessions").mkdir(parents=True, exist_ok=True)
    (folder / "sessions" / name).write_text(text)


def test_bad_session_files_are_set_aside_and_named(tmp_path):
    """Session files of the earlier format: good ones imported, a truncated one, one of
    the wrong shape and one that no longer replays each moved aside and named; a stale
    temporary file removed; the service starts."""
    state = tmp_path / "state"
    good = {
        "format": "asmplan-session/1",
        "id": "a" * 32,
        "plan": "cell",
        "created": 1.0,
        "events": [{"kind": "finished", "operation": "a", "agent": "R2", "by": "robot"}],
        "answers": {},
    }
    first = _move(json.loads(json.dumps(cell_advice())))
    good["events"] = [{**first, "by": "robot"}]
    _legacy(state, "good.json", json.dumps(good))
    _legacy(state, "truncated.json", json.dumps(good)[:40])
    _legacy(state, "list.json", "[1, 2]")
    stale = {
        **good,
        "id": "b" * 32,
        "events": [{"kind": "finished", "operation": "zz", "agent": "H"}],
    }
    _legacy(state, "stale.json", json.dumps(stale))
    _legacy(state, ".x.json.999999.abc.tmp", "half")
    started = serving(serve_args(_plan_dir(tmp_path), "--sessions", state))
    with started as (url, _, lines), httpx.Client(base_url=url) as c:
        assert (
            c.get(f"/api/sessions/{'a' * 32}").json()["events"][0]["operation"]
            == (first["operation"])
        )
        aside = c.get("/api/set-aside").json()
    named = {x.get("file") for x in aside}
    assert {"truncated.json", "list.json", "stale.json"} <= named
    text = "\n".join(lines)
    for name in ("truncated.json", "list.json", "stale.json"):
        assert name in text
    assert "no longer replays" in text and "event 1 (finished zz by H)" in text
    moved = sorted(p.name.split("-")[0] for p in (state / "set-aside").iterdir())
    assert moved == ["list", "stale", "truncated"]
    assert not list((state / "sessions").glob("*.tmp"))
    assert (state / "imported" / "good.json").exists()


def cell_advice() -> dict:
    from asmplan.advisor import Advisor

    return Advisor(PLAN).advice().to_dict()


def test_sessions_that_no_longer_replay_are_set_aside(tmp_path):
    """A plan made again (another plan under the same id): its old sessions no longer
    replay; the service starts, serves the rest, and names each set-aside session."""
    state = tmp_path / "state"
    with running([PLAN], state) as url, httpx.Client(base_url=url) as c:
        s = c.post("/api/sessions", json={"plan": "cell"}).json()
        _play(c, s["id"], s["advice"], 2)
        kept = c.post("/api/sessions", json={"plan": "cell"}).json()["id"]
    store = SessionStore(state, {"cell": _replanned()})
    reasons = {x["session"]: x["reason"] for x in store.set_aside}
    assert s["id"] in reasons and "no longer replays on plan 'cell'" in reasons[s["id"]]
    assert kept not in reasons and store.get(kept).events == []
    assert [x["session"] for x in store.set_aside_all()] == [s["id"]]
    store.close()


def _replanned() -> dict:
    """The cell planned again after an edit: operation a is now the person's only."""
    from asmplan.pipeline import plan_document
    from asp.game.solve import solve
    from asp.graph.game_dag import game_dag
    from asp.graph.game_states import alternate_states
    from asp.graph.state_graph import build_state_graph
    from asp.spec import spec_from_dict

    ops = [dict(op) for op in CELL["operations"]]
    ops[0]["agents"] = {"H": 2}
    spec = spec_from_dict({**CELL, "operations": ops}, source="cell.yaml")
    graph = build_state_graph(spec)
    dag = game_dag(graph)
    describe = alternate_states(graph, dag)
    return plan_document(spec=spec, dag=dag, solution=solve(dag), describe=describe)


def test_a_damaged_database_is_moved_aside(tmp_path):
    state = tmp_path / "state"
    state.mkdir()
    (state / "sessions.db").write_bytes(b"this is not a database" * 100)
    store = SessionStore(state, {"cell": PLAN})
    (item,) = store.set_aside
    assert item["file"] == "sessions.db" and "not a readable database" in item["reason"]
    assert Path(item["moved_to"]).exists()
    assert store.create("cell").id
    store.close()


# --------------------------------------------------------------------------- bounds


def test_chunked_big_body_gets_413(tmp_path):
    with running([PLAN], tmp_path) as url:
        port = int(url.rsplit(":", 1)[1])
        with socket.create_connection(("127.0.0.1", port)) as sock:
            sock.sendall(
                b"POST /api/sessions HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                b"Transfer-Encoding: chunked\r\n\r\n"
            )
            chunk = b"x" * 65536
            try:
                for _ in range(160):  # 10 MB
                    sock.sendall(b"%x\r\n%s\r\n" % (len(chunk), chunk))
            except OSError:
                pass  # the service answered and closed
            answer = sock.recv(4096)
        assert answer.startswith(b"HTTP/1.1 413"), answer[:80]


def test_session_cap_and_age_out(tmp_path):
    now = [1000.0]
    service = running([PLAN], tmp_path, max_sessions=2, session_ttl=60, clock=lambda: now[0])
    with service as url, httpx.Client(base_url=url) as c:
        a = c.post("/api/sessions", json={"plan": "cell"}).json()
        c.post("/api/sessions", json={"plan": "cell"})
        r = c.post("/api/sessions", json={"plan": "cell"})
        assert r.status_code == 429 and r.headers["retry-after"]
        assert "--max-sessions 2" in r.json()["detail"] and "1 min" in r.json()["detail"]
        now[0] += 61
        assert c.post("/api/sessions", json={"plan": "cell"}).status_code == 201
        r = c.post(f"/api/sessions/{a['id']}/events", json=_move(a["advice"]))
        assert r.status_code == 410 and "aged out" in r.json()["detail"]
        assert c.get(f"/api/sessions/{a['id']}").json()["closed"] == "aged out"


def test_the_database_stops_at_its_size_cap(tmp_path):
    """``--max-db-mb``: past the cap every change is refused (503 naming the flag, the
    session unchanged), reads and the export go on, and a restart serves what was taken."""
    with running([PLAN], tmp_path, max_db_mb=0.08) as url, httpx.Client(base_url=url) as c:
        refused, sid, before = None, None, None
        for _ in range(500):
            if sid is None:
                r = c.post("/api/sessions", json={"plan": "cell"})
                if r.status_code != 201:
                    refused = r
                    break
                sid, advice = r.json()["id"], r.json()["advice"]
            before = c.get(f"/api/sessions/{sid}").json()
            r = c.post(f"/api/sessions/{sid}/events", json=_move(advice))
            if r.status_code != 200:
                refused = r
                break
            advice = r.json()
            if advice["finished"]:
                sid = None
        assert refused is not None, "the cap never refused a change"
        assert refused.status_code == 503, refused.text
        assert "--max-db-mb" in refused.json()["detail"] and "0.08 MB" in refused.text
        if sid is not None:
            assert c.get(f"/api/sessions/{sid}").json() == before
        assert c.get("/api/export.csv").status_code == 200
        listed = c.get("/api/sessions").json()
    assert (tmp_path / "sessions.db").stat().st_size <= 0.08e6
    again = SessionStore(tmp_path, {"cell": PLAN})
    assert [s["events"] for s in again.all()] == [s["events"] for s in listed]
    again.close()


def test_busy_port_fails_before_saying_it_serves(tmp_path):
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        r = subprocess.run(
            serve_args(_plan_dir(tmp_path), "--sessions", tmp_path / "s", port=port),
            capture_output=True,
            text=True,
            timeout=60,
        )
    assert r.returncode == 2
    assert "serving on" not in r.stderr
    assert f"cannot listen on 127.0.0.1:{port}: in use" in r.stderr


def test_default_sessions_folder_is_per_user(tmp_path, monkeypatch):
    from asmplan.cli.serve import default_sessions_folder

    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    assert default_sessions_folder() == tmp_path / "data" / "asmplan" / "sessions"
    work = tmp_path / "checkout"
    work.mkdir()
    args = serve_args(_plan_dir(tmp_path))
    env = {"XDG_DATA_HOME": str(tmp_path / "data")}
    with serving(args, env=env) as (_, _, lines):
        pass
    assert list(work.iterdir()) == []
    assert (tmp_path / "data" / "asmplan" / "sessions" / "sessions.db").exists()
    assert str(tmp_path / "data" / "asmplan" / "sessions") in "\n".join(lines)


# --------------------------------------------------------------------------- the API


def test_head_answers_where_get_does(tmp_path):
    with running([PLAN], tmp_path) as url, httpx.Client(base_url=url) as c:
        sid = c.post("/api/sessions", json={"plan": "cell"}).json()["id"]
        paths = ["/", "/static/app.js", "/openapi.json", f"/api/sessions/{sid}"]
        for path, ops in c.get("/openapi.json").json()["paths"].items():
            if "get" in ops and "{" not in path:
                paths.append(path)
        paths += ["/api/plans/cell", "/api/plans/cell/advice"]
        for path in paths:
            get, head = c.get(path), c.head(path)
            assert head.status_code == get.status_code == 200, path
            assert (
                head.content == b"" and head.headers["content-type"] == get.headers["content-type"]
            ), path


def test_no_session_until_the_first_move(tmp_path):
    with running([PLAN], tmp_path) as url, httpx.Client(base_url=url) as c:
        start = c.get("/api/plans/cell/advice").json()
        assert start == cell_advice()
        assert c.get("/api/sessions").json() == []
        bad = {"kind": "finished", "operation": "zz", "agent": "H"}
        r = c.post("/api/sessions", json={"plan": "cell", "event": bad})
        assert r.status_code == 409 and c.get("/api/sessions").json() == []
        r = c.post(
            "/api/sessions", json={"plan": "cell", "participant": "P01", "event": _move(start)}
        )
        assert r.status_code == 201
        s = r.json()
        assert len(s["events"]) == 1 and s["participant"] == "P01"
        assert s["events"][0]["bound_before"] == start["total_bound"]
        (row,) = c.get("/api/sessions").json()
        assert row["events"] == 1 and row["participant"] == "P01"


def test_answers_once_after_the_end(tmp_path):
    with running([PLAN], tmp_path) as url, httpx.Client(base_url=url) as c:
        s = c.post("/api/sessions", json={"plan": "cell"}).json()
        advice = s["advice"]
        r = c.post(f"/api/sessions/{s['id']}/answers", json={"answers": {"trust": 4}})
        assert r.status_code == 409 and "not finished" in r.json()["detail"]
        while not advice["finished"]:
            advice = _play(c, s["id"], advice, 1)
        r = c.post(f"/api/sessions/{s['id']}/answers", json={"answers": {"trust": 4}})
        assert r.status_code == 200
        r = c.post(f"/api/sessions/{s['id']}/answers", json={"answers": {"trust": 1}})
        assert r.status_code == 409 and "kept as given" in r.json()["detail"]
        assert c.get(f"/api/sessions/{s['id']}").json()["answers"] == {"trust": 4}
