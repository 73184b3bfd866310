"""Sessions of the advisor service: one cell (or one person playing) each, with its own state.

A session is a plan id, the events observed (each with its timestamp) and, at the end, the
outcome and the questionnaire's answers. It is written to ``DIR/sessions/<id>.json``
atomically after every change, and every change is appended to ``DIR/log.jsonl`` (one JSON
object a line: the trust-study log). On start the store reads every session file back and
replays its events through an :class:`~asmplan.advisor.Advisor`, so nothing is lost when the
service restarts. Session ids are made here (random hex); a request's id is only ever looked
up in memory, never turned into a path.
"""

from __future__ import annotations

import csv
import io
import json
import secrets
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

from asmplan.advisor import Advisor, Event, ObservationError
from asp.atomic import write_text

SESSION_FORMAT = "asmplan-session/1"
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


class UnknownSession(KeyError):
    """No session has this id."""


@dataclass
class Session:
    """One session: its plan, advisor and record.

    Attributes
    ----------
    id, plan_id : str
    advisor : Advisor
    events : list of dict
        ``{"kind", "operation", "agent", "t", "by", "deviation", "instruction", "elapsed",
        "bound_after"}`` per event (and its ``time`` and ``duration`` when given).
    created : float
        Unix time.
    answers : dict
        The questionnaire's answers (empty until given).
    """

    id: str
    plan_id: str
    advisor: Advisor
    events: list = field(default_factory=list)
    created: float = field(default_factory=time.time)
    answers: dict = field(default_factory=dict)
    finished_at: float | None = None

    @property
    def deviations(self) -> int:
        return sum(1 for e in self.events if e.get("deviation"))

    def record(self) -> dict:
        """The JSON object written to the session file."""
        return {
            "format": SESSION_FORMAT,
            "id": self.id,
            "plan": self.plan_id,
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


class SessionStore:
    """Every session of the service, persisted in ``folder``.

    Parameters
    ----------
    folder : Path
        Holds ``sessions/`` (one JSON file per session) and ``log.jsonl``.
    plans : dict
        Plan id -> plan document.
    """

    def __init__(self, folder: Path, plans: dict[str, dict]):
        self.folder = Path(folder)
        self.plans = plans
        self._sessions: dict[str, Session] = {}
        self._lock = threading.Lock()
        (self.folder / "sessions").mkdir(parents=True, exist_ok=True)
        self._load()

    # ------------------------------------------------------------------ persistence
    def _load(self) -> None:
        for path in sorted((self.folder / "sessions").glob("*.json")):
            data = json.loads(path.read_text(encoding="utf-8"))
            plan = self.plans.get(data.get("plan"))
            if plan is None:
                continue  # a plan this service was not given: kept on disk, not served
            advisor = Advisor.replay(plan, [_event(e) for e in data["events"]])
            self._sessions[data["id"]] = Session(
                id=data["id"],
                plan_id=data["plan"],
                advisor=advisor,
                events=data["events"],
                created=data["created"],
                answers=data.get("answers", {}),
                finished_at=data.get("finished"),
            )

    def _save(self, session: Session, change: dict) -> None:
        write_text(
            self.folder / "sessions" / f"{session.id}.json",
            json.dumps(session.record(), separators=(",", ":")) + "\n",
        )
        line = json.dumps({"session": session.id, "plan": session.plan_id, **change})
        with open(self.folder / "log.jsonl", "a", encoding="utf-8") as log:
            log.write(line + "\n")
            log.flush()

    # ------------------------------------------------------------------ operations
    def create(self, plan_id: str) -> Session:
        if plan_id not in self.plans:
            raise KeyError(plan_id)
        with self._lock:
            session = Session(secrets.token_hex(16), plan_id, Advisor(self.plans[plan_id]))
            self._sessions[session.id] = session
            self._save(session, {"t": session.created, "change": "created"})
        return session

    def get(self, session_id: str) -> Session:
        session = self._sessions.get(session_id)
        if session is None:
            raise UnknownSession(session_id)
        return session

    def all(self) -> list[Session]:
        return sorted(self._sessions.values(), key=lambda s: s.created)

    def observe(self, session_id: str, event: dict):
        """Apply an event; return the advice. Raises ``ObservationError`` (state unchanged)."""
        with self._lock:
            session = self.get(session_id)
            advisor = session.advisor
            before = advisor.advice()
            ev = Event.parse(event)
            advice = advisor.observe(ev)
            instruction = before.instruction if before.turn == "human" else None
            record = {
                "kind": ev.kind,
                "operation": ev.operation,
                "agent": ev.agent,
                "t": time.time(),
                "by": _side(self.plans[session.plan_id], ev.agent),
                "deviation": advice.deviations > before.deviations,
                "instruction": instruction,
                "elapsed": advice.elapsed,
                "bound_after": advice.total_bound,
            }
            for key in ("time", "duration"):
                if getattr(ev, key) is not None:
                    record[key] = getattr(ev, key)
            session.events.append(record)
            if advice.finished and session.finished_at is None:
                session.finished_at = record["t"]
            self._save(session, {"change": "event", **record, "outcome": session.outcome()})
            return advice

    def answer(self, session_id: str, answers: dict) -> Session:
        with self._lock:
            session = self.get(session_id)
            session.answers = dict(answers)
            self._save(session, {"t": time.time(), "change": "answers", "answers": answers})
            return session

    def csv(self) -> str:
        """Every session as one CSV row (:data:`CSV_COLUMNS`)."""
        buffer = io.StringIO()
        writer = csv.writer(buffer)
        writer.writerow(CSV_COLUMNS)
        for s in self.all():
            outcome = s.outcome() or {}
            plan = self.plans[s.plan_id]
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


def _event(record: dict) -> Event:
    return Event(
        record["kind"],
        record["operation"],
        record["agent"],
        record.get("time"),
        record.get("duration"),
    )


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


def _iso(t: float) -> str:
    return time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(t))


__all__ = ["ObservationError", "Session", "SessionStore", "UnknownSession"]
