"""``asmplan study export DIR``: a study's record as one row per event, or per session.

Reads the sessions database of ``asmplan serve`` (``DIR/sessions.db``, read only: a running
service may go on writing). Event rows (:data:`EVENT_COLUMNS`):

- ``session, participant, condition, plan, block, seq``: whose event, in which order;
- ``wall_time`` (ISO 8601 UTC, milliseconds) and ``t`` (Unix seconds): when the service
  took it;
- ``kind, operation, agent, by``: the move (``by``: human or robot);
- ``state`` (the plan's policy state before it), ``done`` (operations done before it,
  ``;``-separated), ``instruction`` (what the person was asked to do, ``op by agent``);
- ``deviation`` (1: the person did something else), ``bound_before`` and ``bound_after``
  (the guaranteed total, cost so far included, before and after it), ``elapsed`` (game
  time after it), ``time`` and ``duration`` when the event gave them, ``source`` (``clock``:
  a completion the real-time clock made), ``decision_s`` (real time: the wall-clock
  seconds the person took to choose, since the event before).

Session rows (:data:`SESSION_COLUMNS` and one column per questionnaire item, ``answer.<item>``:
the items the service last served, and any other answered; an unanswered item is empty,
never a default).
``--format json`` writes ``{"format", "events": [...], "sessions": [...]}`` with the same
keys (answers as an object).
"""

from __future__ import annotations

import csv
import io
import json
import sqlite3
import time
from pathlib import Path

from asmplan.serve.sessions import DB_NAME

FORMAT = "asmplan-study-export/1"
EVENT_COLUMNS = (
    "session",
    "participant",
    "condition",
    "plan",
    "block",
    "seq",
    "wall_time",
    "t",
    "kind",
    "operation",
    "agent",
    "by",
    "state",
    "done",
    "instruction",
    "deviation",
    "bound_before",
    "bound_after",
    "elapsed",
    "time",
    "duration",
    "source",
    "decision_s",
)
SESSION_COLUMNS = (
    "session",
    "participant",
    "condition",
    "plan",
    "block",
    "created",
    "finished",
    "closed",
    "events",
    "deviations",
    "cost",
    "w0",
    "minimax",
    "answered",
)


def open_sessions(folder: str | Path) -> sqlite3.Connection:
    """The sessions database of ``folder``, read only (``ValueError`` if there is none)."""
    path = Path(folder) / DB_NAME
    if not path.is_file():
        raise ValueError(f"{folder}: no {DB_NAME} here (the --sessions folder of asmplan serve)")
    try:
        db = sqlite3.connect(f"file:{path}?mode=ro", uri=True)
        db.execute("SELECT COUNT(*) FROM sessions").fetchone()
    except sqlite3.Error as exc:
        raise ValueError(f"{path}: not a sessions database ({exc})") from None
    return db


def event_rows(db: sqlite3.Connection) -> list[dict]:
    """One row per event, sessions in the order made, events in their order."""
    rows = []
    query = (
        "SELECT s.id, s.participant, s.condition, s.plan, s.block, e.seq, e.record "
        "FROM events e JOIN sessions s ON s.id = e.session ORDER BY s.created, s.id, e.seq"
    )
    for sid, participant, condition, plan, block, seq, record in db.execute(query):
        r = json.loads(record)
        instruction = r.get("instruction")
        rows.append(
            {
                "session": sid,
                "participant": participant,
                "condition": condition,
                "plan": plan,
                "block": block,
                "seq": seq,
                "wall_time": iso_ms(r.get("t")),
                "t": r.get("t"),
                "kind": r.get("kind"),
                "operation": r.get("operation"),
                "agent": r.get("agent"),
                "by": r.get("by"),
                "state": r.get("state"),
                "done": r.get("done"),
                "instruction": _instruction(instruction),
                "deviation": bool(r.get("deviation")),
                "bound_before": r.get("bound_before"),
                "bound_after": r.get("bound_after"),
                "elapsed": r.get("elapsed"),
                "time": r.get("time"),
                "duration": r.get("duration"),
                "source": r.get("source"),
                "decision_s": r.get("decision_s"),
            }
        )
    return rows


def session_rows(db: sqlite3.Connection) -> list[dict]:
    """One row per session with its outcome and answers."""
    answers = {sid: (t, json.loads(a)) for sid, t, a in db.execute("SELECT * FROM answers")}
    counts = dict(db.execute("SELECT session, COUNT(*) FROM events GROUP BY session"))
    deviations: dict[str, int] = {}
    for sid, record in db.execute("SELECT session, record FROM events"):
        deviations[sid] = deviations.get(sid, 0) + bool(json.loads(record).get("deviation"))
    rows = []
    query = (
        "SELECT id, participant, condition, plan, block, created, finished, outcome, closed "
        "FROM sessions ORDER BY created, id"
    )
    for sid, part, cond, plan, block, created, finished, outcome, closed in db.execute(query):
        out = json.loads(outcome) if outcome else {}
        t, given = answers.get(sid, (None, {}))
        rows.append(
            {
                "session": sid,
                "participant": part,
                "condition": cond,
                "plan": plan,
                "block": block,
                "created": iso_ms(created),
                "finished": iso_ms(finished),
                "closed": closed,
                "events": counts.get(sid, 0),
                "deviations": deviations.get(sid, 0),
                "cost": out.get("cost"),
                "w0": out.get("w0"),
                "minimax": out.get("minimax"),
                "answered": iso_ms(t),
                "answers": given,
            }
        )
    return rows


def export(folder: str | Path, fmt: str = "csv", table: str = "events") -> str:
    """The export as text: CSV of ``table`` (``events`` or ``sessions``), or JSON of both."""
    db = open_sessions(folder)
    try:
        if fmt == "json":
            doc = {"format": FORMAT, "events": event_rows(db), "sessions": session_rows(db)}
            return json.dumps(doc, indent=1) + "\n"
        if fmt != "csv":
            raise ValueError(f"--format: expected csv or json, got {fmt!r}")
        if table == "events":
            return _csv(EVENT_COLUMNS, event_rows(db))
        if table == "sessions":
            rows = session_rows(db)
            known = db.execute("SELECT value FROM meta WHERE key = 'questionnaire'").fetchone()
            items = json.loads(known[0]) if known else []
            items += sorted({k for r in rows for k in r["answers"]} - set(items))
            for r in rows:
                given = r.pop("answers")
                for k in items:
                    r[f"answer.{k}"] = given.get(k)
            return _csv(SESSION_COLUMNS + tuple(f"answer.{k}" for k in items), rows)
        raise ValueError(f"--table: expected events or sessions, got {table!r}")
    finally:
        db.close()


def _csv(columns: tuple[str, ...], rows: list[dict]) -> str:
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(columns)
    for r in rows:
        writer.writerow([_cell(r.get(c)) for c in columns])
    return buffer.getvalue()


def _cell(value) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, list):
        return ";".join(str(v) for v in value)
    return str(value)


def _instruction(instruction) -> str | None:
    if not instruction:
        return None
    if isinstance(instruction, dict):
        op, agent = instruction.get("operation"), instruction.get("agent")
        return "wait" if op is None else f"{op} by {agent}"
    return str(instruction)


def iso_ms(t) -> str | None:
    """Unix seconds as ISO 8601 UTC with milliseconds (None stays None)."""
    if t is None:
        return None
    whole = time.strftime("%Y-%m-%dT%H:%M:%S", time.gmtime(t))
    return f"{whole}.{int(round((t % 1) * 1000)) % 1000:03d}Z"
