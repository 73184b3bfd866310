"""Sessions of the advisor service, kept in an embedded database (SQLite in WAL mode).

A session is one cell, or one person playing one plan (in a study: one participant's block,
under one robot condition): its events, each with its wall-clock time, the state, the
instruction in force, whether it deviated and the worst case before and after; at the end
the outcome; and the questionnaire's answers, given once.

Storage (``DIR/sessions.db``, format :data:`STORE_FORMAT`)
----------------------------------------------------------
One SQLite database in write-ahead-log mode. Every change is one transaction, committed
before the service answers: a change the disk refuses (a full disk) is rolled back, the
session in memory is left as it was and the request is answered 503 with the reason, so a
retry does the same thing again. A committed transaction is in the operating system's hands
when the answer is sent, so a killed service (SIGKILL) loses nothing it acknowledged; with
``fsync=True`` (``asmplan serve --fsync``) every commit also waits for the disk, so a power
cut loses nothing either. Every change is also appended to ``DIR/log.jsonl`` (one JSON
object a line, after the commit; the database is the record).

Tables: ``sessions`` (id, plan, condition, participant, block, created, finished, outcome,
closed), ``events`` (session, seq, record), ``answers`` (session, t, answers),
``participants`` (id, number, created, blocks: a study's assignment), ``set_aside``
(sessions not served, with the reason), ``meta``.

Starting
--------
The service starts whatever it finds. Each session of a served plan is replayed through its
:class:`~asmplan.advisor.Advisor`; one that no longer replays (the plan was made again since)
or whose record cannot be read is moved to ``set_aside`` with the reason and named in
:attr:`SessionStore.set_aside` (printed at start, ``GET /api/set-aside``). A database file
that is not one, or is damaged, is moved to ``DIR/set-aside/`` (the sessions it still
gives up copied into a new one). Session files of the earlier format
(``DIR/sessions/<id>.json``, ``asmplan-session/1``) are imported and moved to
``DIR/imported/``; a file that does not read or replay is moved to ``DIR/set-aside/``;
temporary files left by a killed writer are removed.

Bounds
------
At most ``max_sessions`` sessions are open (not finished, not aged out) at once; one more is
refused (:class:`SessionLimit`, 429). A session with no event for ``ttl`` seconds ages out:
it is closed (kept, exported, no more events: :class:`SessionClosed`, 410). Only open
sessions are held in memory; a closed one is read back from the database when asked for.
The database grows to at most ``max_db_mb`` MB (SQLite's page limit): past it every change
is refused like one on a full disk (503 naming ``--max-db-mb``, nothing changed) while
reads and the export go on.
Session ids are made here (random hex); a request's id is only ever looked up, never turned
into a path.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import os
import secrets
import shutil
import sqlite3
import sys
import threading
import time
from collections import OrderedDict
from dataclasses import dataclass, field
from pathlib import Path

from asmplan.advisor import Advisor, Event, ObservationError
from asmplan.serve.limits import DEFAULT_MAX_DB_MB, DEFAULT_MAX_SESSIONS, DEFAULT_TTL
from asp.atomic import remove_stale_temps

SESSION_FORMAT = "asmplan-session/1"
"""The earlier one-file-per-session format, imported on start."""
STORE_FORMAT = 2
"""The database's format (``PRAGMA user_version``)."""
DB_NAME = "sessions.db"
CHECKPOINT_S = 1.0
"""Seconds between the background checkpoints of the write-ahead log."""
CLOSED_CACHE = 64
"""Closed sessions kept in memory once read back (the most recently used)."""
CSV_COLUMNS = (
    "session",
    "plan",
    "created",
    "finished",
    "events",
    "choices",
    "deviations",
    "cost",
    "w0",
    "minimax",
    "answers",
)

SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS sessions (
    id TEXT PRIMARY KEY,
    plan TEXT NOT NULL,
    condition TEXT,
    participant TEXT,
    block INTEGER,
    created REAL NOT NULL,
    finished REAL,
    outcome TEXT,
    closed TEXT,
    speed REAL
);
CREATE INDEX IF NOT EXISTS sessions_participant ON sessions (participant, block);
CREATE TABLE IF NOT EXISTS events (
    session TEXT NOT NULL,
    seq INTEGER NOT NULL,
    record TEXT NOT NULL,
    PRIMARY KEY (session, seq)
) WITHOUT ROWID;
CREATE TABLE IF NOT EXISTS answers (
    session TEXT PRIMARY KEY,
    t REAL NOT NULL,
    answers TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS participants (
    id TEXT PRIMARY KEY,
    number INTEGER NOT NULL UNIQUE,
    created REAL NOT NULL,
    blocks TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS set_aside (
    session TEXT PRIMARY KEY,
    t REAL NOT NULL,
    reason TEXT NOT NULL,
    record TEXT NOT NULL
);
"""


class UnknownSession(KeyError):
    """No session has this id."""


class StorageError(RuntimeError):
    """The disk refused a change (full, read-only, gone): nothing was changed (HTTP 503)."""


class SessionLimit(RuntimeError):
    """As many sessions are open as the service allows (HTTP 429)."""


class SessionClosed(RuntimeError):
    """The session aged out: it is kept but takes no more events (HTTP 410)."""


class NotFinished(RuntimeError):
    """The questionnaire comes after the end of the game (HTTP 409)."""


class AlreadyAnswered(RuntimeError):
    """The session's questionnaire was answered before (HTTP 409; the first answers stay)."""


@dataclass
class Session:
    """One session: its plan, advisor and record.

    Attributes
    ----------
    id, plan_id : str
    advisor : Advisor
    events : list of dict
        Per event: ``kind, operation, agent, t`` (wall clock, Unix time), ``by`` (side),
        ``state`` (policy state before it), ``done`` (operations done before it),
        ``instruction`` (in force before it), ``deviation``, ``bound_before`` and
        ``bound_after`` (the guaranteed total before and after it), ``elapsed`` (game time
        after it), and ``time`` / ``duration`` when given.
    created : float
        Unix time.
    answers : dict
        The questionnaire's answers (empty until given; an item not answered is absent).
    condition, participant : str or None
        The study's robot condition and participant (None outside a study).
    block : int or None
        The participant's block (the position in the assigned order).
    closed : str or None
        Why the session takes no more events (``"aged out"``), else None.
    """

    id: str
    plan_id: str
    advisor: Advisor
    events: list = field(default_factory=list)
    created: float = field(default_factory=time.time)
    answers: dict = field(default_factory=dict)
    finished_at: float | None = None
    condition: str | None = None
    participant: str | None = None
    block: int | None = None
    answered_at: float | None = None
    closed: str | None = None
    last_active: float = 0.0
    advice: object = None
    """The advisor's current :class:`~asmplan.advisor.Advice` (kept: an event's record
    needs the advice before it, and its answer the advice after)."""
    speed: float | None = None
    """Real time: game seconds per wall-clock second (None: the game waits for events)."""

    def current(self):
        """The current advice (made once per change)."""
        if self.advice is None:
            self.advice = self.advisor.advice()
        return self.advice

    @property
    def deviations(self) -> int:
        return sum(1 for e in self.events if e.get("deviation"))

    @property
    def is_open(self) -> bool:
        return self.finished_at is None and self.closed is None

    def record(self) -> dict:
        """The session as one JSON object (the earlier file format's keys, and more)."""
        return {
            "format": SESSION_FORMAT,
            "id": self.id,
            "plan": self.plan_id,
            "condition": self.condition,
            "participant": self.participant,
            "block": self.block,
            "created": self.created,
            "finished": self.finished_at,
            "events": self.events,
            "answers": self.answers,
            "outcome": self.outcome(),
        }

    def outcome(self) -> dict | None:
        """Cost against W*(0) and W* once the assembly is complete."""
        if not self.advisor.finished:
            return None
        plan = self.advisor.plan
        out = {
            "cost": self.advisor.advice().elapsed,
            "w0": plan["metrics"]["w0"],
            "minimax": plan["minimax"],
            "deviations": self.deviations,
        }
        if plan.get("robustness"):  # the concurrent game: W*(k) for each budget k
            out["robustness"] = plan["robustness"]
        return out


PlanKey = tuple[str, "str | None"]
"""A served plan: ``(plan id, condition)`` (condition None: the plan as planned)."""


class SessionStore:
    """Every session of the service, persisted in ``folder`` (module docstring).

    Parameters
    ----------
    folder : Path
        Holds ``sessions.db`` and ``log.jsonl``.
    plans : dict
        Plan id -> plan document, or ``(plan id, condition)`` -> plan document.
    max_sessions : int
        Most sessions open at once.
    ttl : float
        Seconds without an event after which an open session ages out.
    fsync : bool
        Wait for the disk at every commit (durable across a power cut), not only for the
        operating system (durable across a killed service).
    max_db_mb : float
        Largest size of ``sessions.db``, MB.
    clock : callable
        Wall-clock time (Unix seconds); tests give their own.
    """

    def __init__(
        self,
        folder: Path,
        plans: dict,
        *,
        max_sessions: int = DEFAULT_MAX_SESSIONS,
        ttl: float = DEFAULT_TTL,
        fsync: bool = False,
        max_db_mb: float = DEFAULT_MAX_DB_MB,
        clock=time.time,
    ):
        if max_sessions < 1:
            raise ValueError(f"max_sessions: expected at least 1, got {max_sessions}")
        if not ttl > 0:
            raise ValueError(f"session ttl: expected seconds > 0, got {ttl}")
        if not max_db_mb > 0:
            raise ValueError(f"max_db_mb: expected MB > 0, got {max_db_mb}")
        self.max_db_mb = float(max_db_mb)
        self.folder = Path(folder)
        self.plans: dict[PlanKey, dict] = {
            (k if isinstance(k, tuple) else (k, None)): doc for k, doc in plans.items()
        }
        self.max_sessions = max_sessions
        self.ttl = float(ttl)
        self.clock = clock
        self.set_aside: list[dict] = []
        """Sessions and files set aside at this start: ``{"session"|"file", "reason",
        "moved_to"}``."""
        self.notes: list[str] = []
        """What the start did besides (imports, temporary files removed)."""
        self._open: dict[str, Session] = {}
        self._closed: OrderedDict[str, Session] = OrderedDict()
        self._lock = threading.RLock()
        self.folder.mkdir(parents=True, exist_ok=True)
        self._db = self._open_db(fsync)
        self._log = os.open(self.folder / "log.jsonl", os.O_WRONLY | os.O_APPEND | os.O_CREAT)
        self._import_files()
        self._load()
        self._stop = threading.Event()
        self._checkpointer = threading.Thread(
            target=self._checkpoints, name="sessions-checkpoint", daemon=True
        )
        self._checkpointer.start()

    # ------------------------------------------------------------------ the database
    def _connect(self, path: Path, fsync: bool) -> sqlite3.Connection:
        db = sqlite3.connect(path, isolation_level=None, check_same_thread=False, timeout=10)
        db.execute("PRAGMA journal_mode=WAL")
        db.execute(f"PRAGMA synchronous={'FULL' if fsync else 'NORMAL'}")
        db.execute("PRAGMA wal_autocheckpoint=0")  # checkpoints run beside, not in a request
        (page,) = db.execute("PRAGMA page_size").fetchone()
        db.execute(f"PRAGMA max_page_count={max(1, int(self.max_db_mb * 1e6 // page))}")
        db.executescript(SCHEMA)
        version = db.execute("PRAGMA user_version").fetchone()[0]
        if version not in (0, STORE_FORMAT):
            db.close()
            raise ValueError(
                f"{path}: sessions database of format {version}, this asmplan reads "
                f"{STORE_FORMAT}: serve it with the asmplan that wrote it, or use another "
                "--sessions folder"
            )
        db.execute(f"PRAGMA user_version={STORE_FORMAT}")
        return db

    def _open_db(self, fsync: bool) -> sqlite3.Connection:
        path = self.folder / DB_NAME
        try:
            db = self._connect(path, fsync)
            check = db.execute("PRAGMA quick_check").fetchone()[0]
            if check == "ok":
                return db
            db.close()
            problem = f"damaged ({check})"
        except sqlite3.DatabaseError as exc:
            problem = f"not a readable database ({exc})"
        moved = self._move_aside(path, suffix=".db")
        for extra in ("-wal", "-shm"):
            side = Path(str(path) + extra)
            if side.exists():
                shutil.move(side, Path(str(moved) + extra))
        db = self._connect(path, fsync)
        saved = _salvage(moved, db)
        self.set_aside.append(
            {
                "file": DB_NAME,
                "reason": f"{DB_NAME} is {problem}; {saved} session(s) copied from it",
                "moved_to": str(moved),
            }
        )
        return db

    def _move_aside(self, path: Path, suffix: str = "") -> Path:
        aside = self.folder / "set-aside"
        aside.mkdir(exist_ok=True)
        stamp = time.strftime("%Y%m%dT%H%M%S", time.gmtime(self.clock()))
        target = aside / f"{path.stem}-{stamp}{suffix or path.suffix}"
        n = 1
        while target.exists():
            n += 1
            target = aside / f"{path.stem}-{stamp}-{n}{suffix or path.suffix}"
        shutil.move(path, target)
        return target

    @contextlib.contextmanager
    def _transaction(self):
        """One transaction; a refusal of the disk is rolled back and raised as
        :class:`StorageError`."""
        try:
            self._db.execute("BEGIN IMMEDIATE")
            yield self._db
            self._db.execute("COMMIT")
        except sqlite3.Error as exc:
            with contextlib.suppress(sqlite3.Error):
                self._db.execute("ROLLBACK")
            raise self._refused(exc) from exc

    def _refused(self, exc: sqlite3.Error) -> StorageError:
        """The :class:`StorageError` of a refused change, saying whether the database is at
        its size cap (``--max-db-mb``) or the disk refused."""
        with contextlib.suppress(sqlite3.Error):
            (pages,) = self._db.execute("PRAGMA page_count").fetchone()
            (cap,) = self._db.execute("PRAGMA max_page_count").fetchone()
            if pages >= cap:
                return StorageError(
                    f"the sessions database is full: it reached its cap of "
                    f"{self.max_db_mb:g} MB (--max-db-mb); export the sessions and serve "
                    "another --sessions folder, or raise the cap"
                )
        return StorageError(f"the sessions database refused the change: {exc}")

    def _append_log(self, session: Session, change: dict) -> None:
        line = json.dumps({"session": session.id, "plan": session.plan_id, **change})
        try:
            os.write(self._log, (line + "\n").encode("utf-8"))
        except OSError as exc:  # the database holds the record; the log is a copy
            print(f"asmplan: warning: log.jsonl: {exc.strerror or exc}", file=sys.stderr)

    def _checkpoints(self) -> None:
        """Copy the log into the database every :data:`CHECKPOINT_S` seconds on a
        connection of its own (a passive checkpoint never waits for the requests, so an
        event never pays for one; the log stays small)."""
        try:
            db = sqlite3.connect(self.folder / DB_NAME, isolation_level=None, timeout=1)
        except sqlite3.Error:
            return
        with contextlib.closing(db):
            while not self._stop.wait(CHECKPOINT_S):
                with contextlib.suppress(sqlite3.Error):
                    db.execute("PRAGMA wal_checkpoint(PASSIVE)")

    def close(self) -> None:
        self._stop.set()
        self._checkpointer.join(timeout=5)
        with self._lock:
            with contextlib.suppress(sqlite3.Error):
                self._db.close()
            with contextlib.suppress(OSError):
                os.close(self._log)

    # ------------------------------------------------------------------ starting
    def _import_files(self) -> None:
        """Import session files of the earlier format (module docstring)."""
        folder = self.folder / "sessions"
        if not folder.is_dir():
            return
        removed = remove_stale_temps(folder)
        if removed:
            self.notes.append(f"removed {len(removed)} temporary file(s) left in {folder}")
        imported = 0
        for path in sorted(folder.glob("*.json")):
            try:
                data = _read_session_file(path)
                self._check_replays(data)
                with self._transaction() as db:
                    _insert_record(db, data)
            except (ValueError, ObservationError, StorageError) as exc:
                if isinstance(exc, StorageError):
                    raise
                moved = self._move_aside(path)
                self.set_aside.append(
                    {"file": path.name, "reason": _one_line(exc), "moved_to": str(moved)}
                )
                continue
            target = self.folder / "imported"
            target.mkdir(exist_ok=True)
            shutil.move(path, target / path.name)
            imported += 1
        if imported:
            self.notes.append(f"imported {imported} session file(s) from {folder}")

    def _check_replays(self, data: dict) -> None:
        """Raise ``ValueError`` naming the event if ``data`` no longer replays on its plan
        (a plan this service was not given is not checked)."""
        plan = self.plans.get((data["plan"], data.get("condition")))
        if plan is not None:
            _replay(plan, data)

    def _load(self) -> None:
        """Replay every open session of a served plan; set aside those that fail."""
        rows = self._db.execute(
            "SELECT id, plan, condition FROM sessions ORDER BY created"
        ).fetchall()
        now = self.clock()
        for sid, plan_id, condition in rows:
            if (plan_id, condition) not in self.plans:
                continue  # a plan this service was not given: kept, not served
            try:
                session = self._read(sid)
            except (ValueError, ObservationError) as exc:
                self._set_aside(sid, _one_line(exc))
                continue
            if session.is_open and now - session.last_active > self.ttl:
                self._age_out(session)
            if session.is_open:
                self._open[sid] = session

    def _set_aside(self, sid: str, reason: str) -> None:
        """Move a session that cannot be served to ``set_aside`` (its record kept as is)."""
        row = self._db.execute("SELECT * FROM sessions WHERE id = ?", (sid,)).fetchone()
        events = [r for (r,) in self._db.execute(_EVENTS_SQL, (sid,))]
        answers = self._db.execute(
            "SELECT answers FROM answers WHERE session = ?", (sid,)
        ).fetchone()
        record = json.dumps(
            {
                "session": list(row),
                "events": events,
                "answers": answers[0] if answers else None,
            }
        )
        with self._transaction() as db:
            db.execute(
                "INSERT OR REPLACE INTO set_aside VALUES (?, ?, ?, ?)",
                (sid, self.clock(), reason, record),
            )
            for table, key in (("events", "session"), ("answers", "session"), ("sessions", "id")):
                db.execute(f"DELETE FROM {table} WHERE {key} = ?", (sid,))
        self.set_aside.append(
            {"session": sid, "plan": row[1], "reason": reason, "moved_to": "set_aside"}
        )

    def set_aside_all(self) -> list[dict]:
        """Every session ever set aside: ``{"session", "t", "reason"}``, and the files of
        this start."""
        out = [
            {"session": sid, "t": t, "reason": reason}
            for sid, t, reason in self._db.execute(
                "SELECT session, t, reason FROM set_aside ORDER BY t"
            )
        ]
        return out + [x for x in self.set_aside if "file" in x]

    # ------------------------------------------------------------------ reading
    def _read(self, sid: str) -> Session:
        """A session from the database, replayed (raises ``ValueError`` naming the event it
        cannot replay, ``UnknownSession``)."""
        row = self._db.execute(
            "SELECT plan, condition, participant, block, created, finished, closed, speed "
            "FROM sessions WHERE id = ?",
            (sid,),
        ).fetchone()
        if row is None:
            raise UnknownSession(sid)
        plan_id, condition, participant, block, created, finished, closed, speed = row
        plan = self.plans.get((plan_id, condition))
        if plan is None:
            raise UnknownSession(sid)
        try:
            events = [json.loads(r) for (r,) in self._db.execute(_EVENTS_SQL, (sid,))]
        except json.JSONDecodeError as exc:
            raise ValueError(f"session {sid}: an event record is not JSON ({exc.msg})") from None
        answers_row = self._db.execute(
            "SELECT t, answers FROM answers WHERE session = ?", (sid,)
        ).fetchone()
        data = {"id": sid, "plan": plan_id, "condition": condition, "events": events}
        advisor = _replay(plan, data)
        last = max([created] + [e.get("t", 0) for e in events])
        return Session(
            id=sid,
            plan_id=plan_id,
            advisor=advisor,
            events=events,
            created=created,
            answers=json.loads(answers_row[1]) if answers_row else {},
            answered_at=answers_row[0] if answers_row else None,
            finished_at=finished,
            condition=condition,
            participant=participant,
            block=block,
            closed=closed,
            last_active=last,
            speed=speed,
        )

    def get(self, session_id: str) -> Session:
        """An open or closed session (raises :class:`UnknownSession`)."""
        session = self._open.get(session_id)
        if session is not None:
            return session
        with self._lock:
            session = self._closed.get(session_id)
            if session is None:
                if not isinstance(session_id, str) or len(session_id) > 64:
                    raise UnknownSession(session_id)
                try:
                    session = self._read(session_id)
                except (ValueError, ObservationError):
                    raise UnknownSession(session_id) from None
                self._closed[session_id] = session
                while len(self._closed) > CLOSED_CACHE:
                    self._closed.popitem(last=False)
            self._closed.move_to_end(session_id)
            return session

    def all(self) -> list[dict]:
        """Every session of a served plan: ``id, plan, condition, participant, block,
        created, finished, events, outcome, closed`` (read from the database)."""
        rows = self._db.execute(
            "SELECT s.id, s.plan, s.condition, s.participant, s.block, s.created, s.finished, "
            "s.outcome, s.closed, (SELECT COUNT(*) FROM events e WHERE e.session = s.id) "
            "FROM sessions s ORDER BY s.created"
        ).fetchall()
        out = []
        for sid, plan, cond, part, block, created, finished, outcome, closed, n in rows:
            if (plan, cond) not in self.plans:
                continue
            out.append(
                {
                    "id": sid,
                    "plan": plan,
                    "condition": cond,
                    "participant": part,
                    "block": block,
                    "created": created,
                    "finished": finished,
                    "events": n,
                    "outcome": json.loads(outcome) if outcome else None,
                    "closed": closed,
                }
            )
        return out

    @property
    def open_count(self) -> int:
        return len(self._open)

    # ------------------------------------------------------------------ changes
    def create(
        self,
        plan_id: str,
        *,
        condition: str | None = None,
        participant: str | None = None,
        block: int | None = None,
        event: dict | None = None,
        speed: float | None = None,
    ) -> Session:
        """A new session (in real time at ``speed``, :mod:`asmplan.serve.clock`), with its
        first event when given (one transaction: a session
        refused its first event is not made). Raises ``KeyError`` (unknown plan),
        :class:`SessionLimit`, ``ObservationError``, :class:`StorageError`."""
        plan = self.plans.get((plan_id, condition))
        if plan is None:
            raise KeyError(plan_id)
        with self._lock:
            now = self.clock()
            self._age_out_idle(now)
            if len(self._open) >= self.max_sessions:
                raise SessionLimit(
                    f"{len(self._open)} sessions are open, the most this service takes "
                    f"(--max-sessions {self.max_sessions}); a session closes when it finishes "
                    f"or after {_duration(self.ttl)} without an event (--session-ttl)"
                )
            session = Session(
                secrets.token_hex(16),
                plan_id,
                Advisor(plan),
                created=now,
                condition=condition,
                participant=participant,
                block=block,
                last_active=now,
                speed=speed,
            )
            record, advice = (None, None)
            if event is not None:
                record, advice = self._apply(session, event, now)
            with self._transaction() as db:
                db.execute(
                    "INSERT INTO sessions (id, plan, condition, participant, block, created, "
                    "speed) VALUES (?, ?, ?, ?, ?, ?, ?)",
                    (session.id, plan_id, condition, participant, block, now, speed),
                )
                if record is not None:
                    self._write_event(session, record, db)
            if record is not None:
                self._commit_event(session, record, advice)
            if session.is_open:
                self._open[session.id] = session
            self._append_log(session, {"t": now, "change": "created", **_study_keys(session)})
            if record is not None:
                self._append_log(
                    session, {"change": "event", **record, "outcome": session.outcome()}
                )
            return session

    def observe(self, session_id: str, event: dict, *, at: float | None = None):
        """Apply an event; return the advice. Raises ``ObservationError`` (the plan cannot
        explain it), :class:`SessionClosed`, :class:`StorageError`: the session unchanged.

        A real-time session first takes the completions its clock has made due
        (:meth:`tick`) and refuses a ``finished`` event from outside: the clock finishes
        operations. ``at``: the wall-clock time to record (the clock's own events)."""
        with self._lock:
            session = self._open.get(session_id)
            if session is None:
                session = self.get(session_id)  # raises UnknownSession
                if session.closed:
                    raise SessionClosed(
                        f"session {session_id} is closed ({session.closed}): it takes no "
                        "more events"
                    )
            if session.speed is not None and at is None:
                self.tick(session_id)
                if isinstance(event, dict) and event.get("kind") == "finished":
                    raise ObservationError(
                        f"finished {event.get('operation')} by {event.get('agent')}: a real-time "
                        "session's operations finish on its clock"
                    )
            now = self.clock() if at is None else at
            record, advice = self._apply(session, event, now)
            try:
                self._write_event(session, record)
            except StorageError:
                session.advisor = Advisor.replay(session.advisor.plan, session.events)
                session.advice = None
                raise
            self._commit_event(session, record, advice)
            self._append_log(session, {"change": "event", **record, "outcome": session.outcome()})
            return advice

    def tick(self, session_id: str) -> list[dict]:
        """Take the completions a real-time session's clock has made due
        (:func:`asmplan.serve.clock.due`); return their records (none for other sessions)."""
        from asmplan.serve.clock import due

        with self._lock:
            session = self._open.get(session_id)
            taken = []
            while session is not None and session.speed is not None and session.is_open:
                event, at = due(session, self.clock())
                if event is None:
                    break
                self.observe(session_id, event, at=at)
                taken.append(session.events[-1])
            return taken

    def _apply(self, session: Session, event: dict, now: float):
        """Take ``event`` in the session's advisor; return its record and the advice after
        it (the session's record is not changed yet: :meth:`_commit_event` does, once
        written)."""
        advisor = session.advisor
        before = session.current()
        ev = Event.parse(event)
        advice = advisor.observe(ev)
        record = {
            "kind": ev.kind,
            "operation": ev.operation,
            "agent": ev.agent,
            "t": now,
            "by": _side(advisor.plan, ev.agent),
            "state": before.state,
            "done": before.done,
            "deviation": advice.deviations > before.deviations,
            "instruction": before.instruction if before.turn == "human" else None,
            "bound_before": before.total_bound,
            "elapsed": advice.elapsed,
            "bound_after": advice.total_bound,
        }
        for key in ("time", "duration"):
            if getattr(ev, key) is not None:
                record[key] = getattr(ev, key)
        if isinstance(event, dict) and event.get("source"):
            record["source"] = event["source"]
        elif session.speed is not None:  # real time: how long the person took to choose
            last = session.events[-1]["t"] if session.events else session.created
            record["decision_s"] = round(max(0.0, now - last), 3)
        return record, advice

    def _write_event(self, session: Session, record: dict, db=None) -> None:
        """Insert the event (in the transaction ``db``, else in one of its own: a single
        statement commits by itself)."""
        insert = "INSERT INTO events (session, seq, record) VALUES (?, ?, ?)"
        row = (session.id, len(session.events), json.dumps(record, separators=(",", ":")))
        if not session.advisor.finished:
            if db is not None:
                db.execute(insert, row)
                return
            try:
                self._db.execute(insert, row)
            except sqlite3.Error as exc:
                raise self._refused(exc) from exc
            return
        outcome = dict(session.outcome() or {})
        outcome["deviations"] = session.deviations + bool(record["deviation"])
        update = "UPDATE sessions SET finished = ?, outcome = ? WHERE id = ?"
        with contextlib.nullcontext(db) if db is not None else self._transaction() as tx:
            tx.execute(insert, row)
            tx.execute(update, (record["t"], json.dumps(outcome), session.id))

    def _commit_event(self, session: Session, record: dict, advice) -> None:
        session.events.append(record)
        session.advice = advice
        session.last_active = record["t"]
        if session.advisor.finished and session.finished_at is None:
            session.finished_at = record["t"]
            self._open.pop(session.id, None)
            self._closed[session.id] = session

    def answer(self, session_id: str, answers: dict) -> Session:
        """Store the questionnaire's answers, once (raises :class:`AlreadyAnswered`,
        :class:`StorageError`)."""
        with self._lock:
            session = self.get(session_id)
            if not session.advisor.finished:
                raise NotFinished(
                    f"session {session_id} is not finished: the questionnaire comes after "
                    "the assembly is complete"
                )
            if session.answered_at is not None:
                raise AlreadyAnswered(
                    f"session {session_id} was answered at {_iso(session.answered_at)}: the "
                    "answers are kept as given"
                )
            now = self.clock()
            with self._transaction() as db:
                db.execute(
                    "INSERT INTO answers (session, t, answers) VALUES (?, ?, ?)",
                    (session_id, now, json.dumps(answers, sort_keys=True)),
                )
            session.answers = dict(answers)
            session.answered_at = now
            self._append_log(session, {"t": now, "change": "answers", "answers": answers})
            return session

    def _age_out_idle(self, now: float) -> None:
        idle = [s for s in self._open.values() if now - s.last_active > self.ttl]
        for session in idle:
            self._age_out(session)

    def _age_out(self, session: Session) -> None:
        reason = "aged out"
        with self._transaction() as db:
            db.execute("UPDATE sessions SET closed = ? WHERE id = ?", (reason, session.id))
        session.closed = reason
        self._open.pop(session.id, None)
        self._append_log(session, {"t": self.clock(), "change": "closed", "reason": reason})

    def set_meta(self, key: str, value) -> None:
        """Keep ``value`` (JSON) under ``key`` in the database's ``meta`` table (the study's
        questionnaire item ids, for the export's columns)."""
        with self._transaction() as db:
            db.execute("INSERT OR REPLACE INTO meta VALUES (?, ?)", (key, json.dumps(value)))

    # ------------------------------------------------------------------ participants
    def participant(self, pid: str) -> dict | None:
        """A study participant: ``{"id", "number", "created", "blocks"}``, or None."""
        row = self._db.execute(
            "SELECT id, number, created, blocks FROM participants WHERE id = ?", (pid,)
        ).fetchone()
        if row is None:
            return None
        return {"id": row[0], "number": row[1], "created": row[2], "blocks": json.loads(row[3])}

    def enrol(self, pid: str, assign) -> dict:
        """Enrol participant ``pid`` (or return the one enrolled): ``assign(number)`` gives
        the blocks of the ``number``-th participant (0, 1, ...)."""
        with self._lock:
            known = self.participant(pid)
            if known is not None:
                return known
            (count,) = self._db.execute("SELECT COUNT(*) FROM participants").fetchone()
            blocks = assign(count)
            now = self.clock()
            with self._transaction() as db:
                db.execute(
                    "INSERT INTO participants VALUES (?, ?, ?, ?)",
                    (pid, count, now, json.dumps(blocks)),
                )
            return {"id": pid, "number": count, "created": now, "blocks": blocks}

    def participants(self) -> list[dict]:
        return [
            {"id": r[0], "number": r[1], "created": r[2], "blocks": json.loads(r[3])}
            for r in self._db.execute(
                "SELECT id, number, created, blocks FROM participants ORDER BY number"
            )
        ]

    def block_sessions(self, pid: str) -> dict[int, str]:
        """Block -> the id of the participant's (latest) session of that block."""
        return {
            block: sid
            for sid, block in self._db.execute(
                "SELECT id, block FROM sessions WHERE participant = ? ORDER BY created", (pid,)
            )
        }

    # ------------------------------------------------------------------ export
    def csv(self) -> str:
        """Every session as one CSV row (:data:`CSV_COLUMNS`)."""
        buffer = io.StringIO()
        writer = csv.writer(buffer)
        writer.writerow(CSV_COLUMNS)
        for row in self.all():
            s = self.get(row["id"])
            outcome = s.outcome() or {}
            plan = s.advisor.plan
            writer.writerow(
                [
                    s.id,
                    s.plan_id,
                    _iso(s.created),
                    _iso(s.finished_at) if s.finished_at else "",
                    len(s.events),
                    _choices(s.events),
                    s.deviations,
                    outcome.get("cost", ""),
                    plan["metrics"]["w0"],
                    plan["minimax"],
                    json.dumps(s.answers, sort_keys=True) if s.answers else "",
                ]
            )
        return buffer.getvalue()


_EVENTS_SQL = "SELECT record FROM events WHERE session = ? ORDER BY seq"


def _replay(plan: dict, data: dict) -> Advisor:
    """The advisor of a session record; ``ValueError`` naming the event that fails."""
    advisor = Advisor(plan)
    for n, e in enumerate(data["events"]):
        try:
            advisor.observe(_event(e))
        except (ObservationError, KeyError, TypeError) as exc:
            what = (
                f"{e.get('kind')} {e.get('operation')} by {e.get('agent')}"
                if isinstance(e, dict)
                else repr(e)[:40]
            )
            raise ValueError(
                f"session {data['id']} no longer replays on plan {data['plan']!r}: event "
                f"{n + 1} ({what}): {_one_line(exc)}"
            ) from None
    return advisor


def _read_session_file(path: Path) -> dict:
    """A session file of the earlier format, checked (``ValueError`` naming what is wrong)."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path.name}: not a readable JSON session file ({exc})") from None
    if not isinstance(data, dict):
        raise ValueError(f"{path.name}: expected a JSON object, got {type(data).__name__}")
    for key, kind in (("id", str), ("plan", str), ("events", list), ("created", (int, float))):
        if not isinstance(data.get(key), kind):
            raise ValueError(f"{path.name}: missing or bad {key!r}")
    if not all(isinstance(e, dict) for e in data["events"]):
        raise ValueError(f"{path.name}: an event is not an object")
    if not (len(data["id"]) <= 64 and data["id"].isalnum()):
        raise ValueError(f"{path.name}: bad session id {data['id'][:40]!r}")
    return data


def _insert_record(db, data: dict) -> None:
    """Insert a session record of the earlier format (a session already there is kept)."""
    if db.execute("SELECT 1 FROM sessions WHERE id = ?", (data["id"],)).fetchone():
        return
    outcome = data.get("outcome")
    db.execute(
        "INSERT INTO sessions (id, plan, condition, participant, block, created, finished, "
        "outcome) VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
        (
            data["id"],
            data["plan"],
            data.get("condition"),
            data.get("participant"),
            data.get("block"),
            float(data["created"]),
            data.get("finished"),
            json.dumps(outcome) if outcome else None,
        ),
    )
    for seq, e in enumerate(data["events"]):
        db.execute(
            "INSERT INTO events (session, seq, record) VALUES (?, ?, ?)",
            (data["id"], seq, json.dumps(e, separators=(",", ":"))),
        )
    if data.get("answers"):
        db.execute(
            "INSERT INTO answers (session, t, answers) VALUES (?, ?, ?)",
            (data["id"], data.get("finished") or data["created"], json.dumps(data["answers"])),
        )


def _salvage(path: Path, db: sqlite3.Connection) -> int:
    """Copy the sessions a damaged database still gives up into ``db``; return how many."""
    saved = 0
    try:
        old = sqlite3.connect(f"file:{path}?mode=ro", uri=True)
        ids = [r[0] for r in old.execute("SELECT id FROM sessions")]
    except sqlite3.Error:
        return 0
    tables = (
        ("sessions", "id"),
        ("events", "session"),
        ("answers", "session"),
    )
    for sid in ids:
        try:
            rows = {
                t: old.execute(f"SELECT * FROM {t} WHERE {k} = ?", (sid,)).fetchall()
                for t, k in tables
            }
            db.execute("BEGIN")
            for table, found in rows.items():
                for row in found:
                    marks = ", ".join("?" * len(row))
                    db.execute(f"INSERT OR IGNORE INTO {table} VALUES ({marks})", row)
            db.execute("COMMIT")
            saved += 1
        except sqlite3.Error:
            with contextlib.suppress(sqlite3.Error):
                db.execute("ROLLBACK")
    with contextlib.suppress(sqlite3.Error):
        for row in old.execute("SELECT * FROM participants"):
            db.execute("INSERT OR IGNORE INTO participants VALUES (?, ?, ?, ?)", row)
    old.close()
    return saved


def _event(record: dict) -> Event:
    return Event(
        record["kind"],
        record["operation"],
        record["agent"],
        record.get("time"),
        record.get("duration"),
    )


def _study_keys(session: Session) -> dict:
    keys = {"condition": session.condition, "participant": session.participant}
    keys["block"] = session.block
    return {k: v for k, v in keys.items() if v is not None}


def _choices(events: list) -> int:
    """The person's choices: her starts, and her completions not seen to start (the
    alternating game's sensor may see completions only)."""
    seen, n = set(), 0
    for e in events:
        if e["by"] != "human":
            continue
        key = (e["operation"], e["agent"])
        if e["kind"] == "started" or key not in seen:
            n += 1
        seen.add(key)
    return n


def _side(plan: dict, agent: str) -> str:
    """``human`` or ``robot``: the side of an agent (a worker ``A:human`` of the concurrent
    game's agent ``A`` of side ``any`` says its side)."""
    if ":" in agent:
        return agent.rsplit(":", 1)[1]
    return plan.get("agents", {}).get(agent, "")


def _one_line(exc: BaseException) -> str:
    text = str(exc.args[0]) if isinstance(exc, KeyError) and exc.args else str(exc)
    lines = text.strip().splitlines()
    return lines[0] if lines else type(exc).__name__


def _duration(seconds: float) -> str:
    if seconds >= 3600 and seconds % 3600 == 0:
        return f"{seconds / 3600:g} h"
    if seconds >= 60 and seconds % 60 == 0:
        return f"{seconds / 60:g} min"
    return f"{seconds:g} s"


def _iso(t: float) -> str:
    return time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(t))


__all__ = [
    "AlreadyAnswered",
    "NotFinished",
    "ObservationError",
    "Session",
    "SessionClosed",
    "SessionLimit",
    "SessionStore",
    "StorageError",
    "UnknownSession",
]
