"""The advisor service: a FastAPI application over plans and sessions.

Routes (the OpenAPI document is at ``/openapi.json``, its browsable form at ``/docs``, from
installed files: :mod:`asmplan.serve.docs`):

- ``GET /``: the page (play the person's side against the robots' policy).
- ``GET /static/{name}``: the page's own files and plotly's JavaScript from the installed
  plotly package (a fixed table of names; no path from a request reaches the file system).
- ``GET /api/plans``, ``GET /api/plans/{plan}``, ``GET /api/plans/{plan}/meshes``.
- ``POST /api/sessions`` ``{"plan": id}`` -> 201 and the session with its advice.
- ``GET /api/sessions``, ``GET /api/sessions/{session}``.
- ``POST /api/sessions/{session}/events`` ``{"kind": "started"|"finished", "operation",
  "agent", "time"?, "duration"?}`` -> the advice; 409 naming the problem when the plan
  cannot explain it (the session is unchanged), 404 for an unknown session, 422 for a
  malformed body.
- ``GET /api/questionnaire``; ``POST /api/sessions/{session}/answers`` ``{"answers": {...}}``.
- ``GET /api/export.csv``: every session, one row each.
- ``GET /api/sessions/{session}/explain``, ``GET /api/plans/{plan}/explain``: the advice
  that explains itself (:mod:`asmplan.serve.explain`).

Request bodies are validated (pydantic, unknown keys refused) and limited to
:data:`MAX_BODY` bytes (413 above).
"""

from __future__ import annotations

import contextlib
import gc
import json
import re
import time
from importlib import resources
from pathlib import Path
from typing import Literal

from fastapi import FastAPI, HTTPException
from fastapi.responses import FileResponse, HTMLResponse, JSONResponse, Response
from pydantic import BaseModel, ConfigDict, Field

from asmplan.advisor import Advisor, ObservationError
from asmplan.serve.clock import clock_view
from asmplan.serve.docs import add_docs
from asmplan.serve.explain import add_explain_routes
from asmplan.serve.limits import DEFAULT_MAX_DB_MB
from asmplan.serve.meshes import base_parts, plan_meshes
from asmplan.serve.sessions import (
    DEFAULT_MAX_SESSIONS,
    DEFAULT_TTL,
    AlreadyAnswered,
    NotFinished,
    SessionClosed,
    SessionLimit,
    SessionStore,
    StorageError,
    UnknownSession,
)
from asmplan.study.questionnaire import AnswerError, check_answers, items_from_data
from asp.game.turns import turn_of

MAX_BODY = 16 * 1024
"""Largest request body accepted, bytes."""
DEFAULT_QUESTIONNAIRE = (
    {"id": "trust", "text": "I trusted the robots to adapt to what I did.", "scale": [1, 5]},
    {"id": "predictable", "text": "The robots' replies were predictable.", "scale": [1, 5]},
    {"id": "comment", "text": "Anything else?", "scale": None},
)
"""Items of the optional end-of-game questionnaire (``--questionnaire`` replaces them)."""
STATIC = {
    "app.js": "application/javascript",
    "style.css": "text/css",
}


class EventIn(BaseModel):
    """An observation: an operation started or finished by an agent."""

    model_config = ConfigDict(extra="forbid")
    kind: Literal["started", "finished"]
    operation: str = Field(min_length=1, max_length=64)
    agent: str = Field(min_length=1, max_length=64)
    time: float | None = Field(
        None, ge=0, le=1e9, description="seconds since the start (a completion's time)"
    )
    duration: float | None = Field(
        None, ge=0, le=1e9, description="a start: the duration the agent will take"
    )


class SessionIn(BaseModel):
    """A new session on one of the service's plans, with its first event when given."""

    model_config = ConfigDict(extra="forbid")
    plan: str | None = Field(None, min_length=1, max_length=64)
    condition: str | None = Field(None, min_length=1, max_length=64)
    participant: str | None = Field(None, min_length=1, max_length=64, pattern=r"^[A-Za-z0-9_.-]+$")
    block: int | None = Field(None, ge=0, le=1000)
    event: EventIn | None = None


class AnswersIn(BaseModel):
    """The questionnaire's answers: item id -> a number or a short text."""

    model_config = ConfigDict(extra="forbid")
    answers: dict[str, int | float | str | None] = Field(max_length=200)


def plan_id(plan: dict) -> str:
    """A URL-safe id from the assembly's name (``vacuum pump`` -> ``vacuum-pump``; a plan of
    the concurrent game: ``vacuum-pump-concurrent``)."""
    name = re.sub(r"[^a-z0-9]+", "-", str(plan.get("assembly", "plan")).lower()).strip("-")
    return name + turn_of(plan.get("turn_model")).plan_id_suffix


def _plotly_js() -> Path:
    return Path(str(resources.files("plotly").joinpath("package_data", "plotly.min.js")))


def _replaying(message: dict, receive):
    """An ASGI ``receive`` that hands on ``message`` (the request a middleware has already
    read) first, then what ``receive`` gives."""
    sent = False

    async def replay():
        nonlocal sent
        if not sent:
            sent = True
            return message
        return await receive()

    return replay


class BodyLimit:
    """ASGI middleware: refuse request bodies over ``limit`` bytes with 413.

    The body is read here, whole, before the application sees it (a declared length over
    the limit is refused before reading; a chunked body as soon as it passes the limit),
    and handed on as one message."""

    def __init__(self, app, limit: int = MAX_BODY):
        self.app = app
        self.limit = limit

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        headers = dict(scope.get("headers") or [])
        length = headers.get(b"content-length")
        if length is not None and (not length.isdigit() or int(length) > self.limit):
            return await _too_large(send, self.limit)
        chunks, seen = [], 0
        while True:
            message = await receive()
            if message["type"] != "http.request":
                return  # the client went away
            body = message.get("body", b"")
            seen += len(body)
            if seen > self.limit:
                return await _too_large(send, self.limit)
            chunks.append(body)
            if not message.get("more_body", False):
                break
        whole = {"type": "http.request", "body": b"".join(chunks), "more_body": False}
        return await self.app(scope, _replaying(whole, receive), send)


async def _too_large(send, limit: int) -> None:
    body = f'{{"detail":"request body over {limit} bytes"}}'.encode()
    await send(
        {
            "type": "http.response.start",
            "status": 413,
            "headers": [
                (b"content-type", b"application/json"),
                (b"content-length", str(len(body)).encode()),
                (b"connection", b"close"),
            ],
        }
    )
    await send({"type": "http.response.body", "body": body})


class HeadAsGet:
    """ASGI middleware: a HEAD request is answered as its GET, headers only."""

    def __init__(self, app):
        self.app = app

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http" or scope["method"] != "HEAD":
            return await self.app(scope, receive, send)

        async def headers_only(message):
            if message["type"] == "http.response.body":
                if message.get("more_body", False):
                    return
                message = {"type": "http.response.body", "body": b""}
            await send(message)

        return await self.app({**scope, "method": "GET"}, receive, headers_only)


def create_app(
    plans: list[dict],
    state_dir: str | Path,
    *,
    questionnaire: list[dict] | None = None,
    study=None,
    variants: dict | None = None,
    realtime: float | None = None,
    max_sessions: int = DEFAULT_MAX_SESSIONS,
    session_ttl: float = DEFAULT_TTL,
    fsync: bool = False,
    max_db_mb: float = DEFAULT_MAX_DB_MB,
    clock=time.time,
) -> FastAPI:
    """The service for ``plans`` (plan documents), keeping its sessions in ``state_dir``
    (:class:`~asmplan.serve.sessions.SessionStore`: ``max_sessions`` open at once, aged out
    after ``session_ttl`` seconds without an event, ``fsync`` at every commit, the database
    at most ``max_db_mb`` MB).

    ``study``: a :class:`~asmplan.study.config.Study` (``asmplan serve --study``), served
    with ``variants``, ``(plan id, condition id) -> plan document``
    (:func:`asmplan.study.plans.study_plans`). ``realtime``: game seconds per wall-clock
    second of every new session (:mod:`asmplan.serve.clock`; a study's own ``realtime``
    otherwise)."""
    by_id: dict[str, dict] = {}
    for plan in plans:
        pid = plan_id(plan)
        if pid in by_id:
            raise ValueError(f"two plans named {pid!r}: give each assembly its own name")
        by_id[pid] = plan
    served: dict = dict(by_id)
    for (pid, cond), doc in (variants or {}).items():
        served[(pid, cond)] = doc
        by_id.setdefault(pid, doc)
    store = SessionStore(
        Path(state_dir),
        served,
        max_sessions=max_sessions,
        ttl=session_ttl,
        fsync=fsync,
        max_db_mb=max_db_mb,
        clock=clock,
    )
    if study is not None:
        items = list(study.questionnaire)
    else:
        given = questionnaire if questionnaire is not None else DEFAULT_QUESTIONNAIRE
        items = items_from_data(list(given), "questionnaire")
    with contextlib.suppress(StorageError):  # the export's columns; a full disk can wait
        store.set_meta("questionnaire", [item.id for item in items])

    app = FastAPI(
        title="asmplan advisor",
        version="1",
        description="The robust plan's policy for a cell: observe operations started and "
        "finished, get the robots' next operations, the person's instruction and the "
        "guaranteed bound. See README.md, 'The advisor service'.",
        docs_url=None,
        redoc_url=None,
    )
    add_docs(app, "asmplan advisor")
    add_explain_routes(app, store, store.plans)
    app.state.store = store
    speed = study.speed if study is not None and realtime is None else realtime
    _page_routes(app, by_id, store.plans, speed)
    _session_routes(app, store, items, study, speed)
    if study is not None:
        from asmplan.study.routes import add_study_routes

        add_study_routes(app, store, study, json_response)
    app.add_exception_handler(ValueError, _value_error)
    app.add_middleware(EventFastPath, store=store)
    app.add_middleware(BodyLimit, limit=MAX_BODY)
    app.add_middleware(HeadAsGet)
    gc.freeze()  # the plans and the service: no collection walks them again (p99 latency)
    return app


def _page_routes(app: FastAPI, by_id: dict[str, dict], served: dict, speed) -> None:
    """The page, its files and the plans (read only; ``served``: ``(plan id, condition)``
    -> plan document, a study's conditions included; ``speed``: the real-time clock's
    speed of new sessions, None: the game waits for events)."""
    meshes: dict[str, dict] = {}
    static_dir = resources.files("asmplan.serve").joinpath("static")

    def _plan(pid: str) -> dict:
        plan = by_id.get(pid)
        if plan is None:
            raise HTTPException(404, f"unknown plan {pid!r}")
        return plan

    @app.get("/", response_class=HTMLResponse, include_in_schema=False)
    def page() -> HTMLResponse:
        return HTMLResponse(static_dir.joinpath("index.html").read_text(encoding="utf-8"))

    @app.get("/static/{name}", include_in_schema=False)
    def static(name: str) -> Response:
        if name == "plotly.min.js":
            return FileResponse(_plotly_js(), media_type="application/javascript")
        if name not in STATIC:
            raise HTTPException(404, f"no static file {name!r}")
        text = static_dir.joinpath(name).read_text(encoding="utf-8")
        return Response(text, media_type=STATIC[name])

    @app.get("/api/plans")
    def list_plans() -> list[dict]:
        """The plans this service runs."""
        return [_plan_summary(pid, plan) for pid, plan in by_id.items()]

    @app.get("/api/plans/{pid}")
    def get_plan(pid: str, condition: str | None = None) -> dict:
        """One plan: metrics, operations, parts, agents, the principal and worst lines (of a
        study's ``condition``: that robot's), and ``realtime``: the speed of its sessions'
        clock (game seconds per wall-clock second; null: the game waits for events)."""
        plan = _plan(pid) if condition is None else served.get((pid, condition))
        if plan is None:
            raise HTTPException(404, f"unknown plan {pid!r} or condition {condition!r}")
        keys = ("assembly", "turn_model", "cost", "tct", "minimax", "metrics", "agents")
        keys += ("robustness",)
        out = {k: plan.get(k) for k in keys}
        out.update(
            id=pid,
            parts=plan.get("parts", []),
            base_parts=base_parts(plan),
            operations=plan.get("operations", {}),
            robust_plan=plan.get("robust_plan", []),
            worst_line=plan.get("worst_line", []),
            realtime=speed,
        )
        return out

    @app.get("/api/plans/{pid}/meshes")
    def get_meshes(pid: str) -> dict:
        """Part id -> mesh arrays (``x, y, z, i, j, k``) for a plotly Mesh3d."""
        plan = _plan(pid)
        if pid not in meshes:
            meshes[pid] = plan_meshes(plan)
        return meshes[pid]


def _session_routes(app: FastAPI, store: SessionStore, items: list, study, speed) -> None:
    """Sessions, their events and answers (the engine: :mod:`asmplan.serve.sessions`).

    The handlers are coroutines that answer with JSON text made here: an event is taken,
    committed and answered on the event loop, with no thread hop and no re-encoding."""

    def _session(sid: str):
        try:
            return store.get(sid)
        except UnknownSession:
            raise HTTPException(404, f"unknown session {sid!r}") from None

    @app.get("/api/plans/{pid}/advice")
    async def start_advice(pid: str, condition: str | None = None) -> Response:
        """The advice at the start of a plan, without making a session (a session is made
        with its first event: ``POST /api/sessions`` with ``event``)."""
        plan = store.plans.get((pid, condition))
        if plan is None:
            what = (
                f"unknown plan {pid!r}"
                if condition is None
                else (f"unknown plan {pid!r} or condition {condition!r}")
            )
            raise HTTPException(404, what)
        return json_response(advice_dict(Advisor(plan).advice()))

    @app.post("/api/sessions", status_code=201)
    async def new_session(body: SessionIn) -> Response:
        """Start a session (a cell, or a person playing) on a plan, with its first event
        when given (then a refused event makes no session)."""
        plan, condition = body.plan, body.condition
        if body.block is not None:
            if body.participant is None or study is None:
                raise HTTPException(422, "block: only with a participant of a study (--study)")
            from asmplan.study.routes import block_of

            assigned = block_of(store, body.participant, body.block)
            plan, condition = assigned["plan"], assigned["condition"]
            if body.plan not in (None, plan) or body.condition not in (None, condition):
                raise HTTPException(
                    409, f"block {body.block} of {body.participant} is {plan} / {condition}"
                )
        if plan is None:
            raise HTTPException(422, "plan: expected a plan id (or a participant's block)")
        if (plan, condition) not in store.plans:
            what = "" if condition is None else f" under condition {condition!r}"
            raise HTTPException(404, f"unknown plan {plan!r}{what}")
        event = body.event.model_dump(exclude_none=True) if body.event else None
        with _errors():
            session = store.create(
                plan,
                condition=condition,
                participant=body.participant,
                block=body.block,
                event=event,
                speed=speed,
            )
        return json_response(session_view(session, store.clock()), 201)

    @app.get("/api/sessions")
    async def list_sessions() -> Response:
        """Every session: id, plan, condition, participant, number of events, outcome."""
        return json_response(store.all())

    @app.get("/api/sessions/{sid}")
    async def get_session(sid: str) -> Response:
        """A session's record and its current advice (a real-time session's clock first
        takes the completions due)."""
        _session(sid)
        with _errors():
            store.tick(sid)
        return json_response(session_view(_session(sid), store.clock()))

    @app.get("/api/sessions/{sid}/advice")
    async def get_advice(sid: str) -> Response:
        """The current advice, the clock (real time) and the number of events: what a page
        polls while the clock runs."""
        _session(sid)
        with _errors():
            store.tick(sid)
        session = _session(sid)
        return json_response(
            {
                "advice": advice_dict(session.current()),
                "clock": clock_view(session, store.clock()),
                "events": len(session.events),
                "finished": session.finished_at,
            }
        )

    @app.post("/api/sessions/{sid}/events")
    async def post_event(sid: str, body: EventIn) -> Response:
        """Observe an event; 409 naming the problem if the plan cannot explain it."""
        _session(sid)
        with _errors():
            advice = store.observe(sid, body.model_dump(exclude_none=True))
        return json_response(advice_dict(advice))

    @app.get("/api/questionnaire")
    def get_questionnaire() -> list[dict]:
        """The end-of-game questionnaire's items: ``id, text, scale`` (``[min, max]``, or
        null: free text), ``labels`` (point -> text), ``required``."""
        return [item.to_dict() for item in items]

    @app.post("/api/sessions/{sid}/answers")
    async def post_answers(sid: str, body: AnswersIn) -> Response:
        """Store the questionnaire's answers with the session (once)."""
        _session(sid)
        try:
            answers = check_answers(items, body.answers)
        except AnswerError as exc:
            raise HTTPException(422, str(exc)) from None
        with _errors():
            session = store.answer(sid, answers)
        return json_response(session_view(session, store.clock()))

    @app.get("/api/set-aside")
    async def set_aside() -> Response:
        """Sessions and files not served: each with the reason (a plan made again since,
        a damaged record)."""
        return json_response(store.set_aside_all())

    @app.get("/api/export.csv")
    def export_csv() -> Response:
        """Every session as one CSV row."""
        return Response(store.csv(), media_type="text/csv")


_EVENTS_PATH = re.compile(r"^/api/sessions/([0-9a-f]{1,64})/events$")


class EventFastPath:
    """ASGI middleware: ``POST /api/sessions/{id}/events`` taken without the framework.

    An event is the service's hot path (issue 25: p50 under 1 ms over HTTP). A body that
    :class:`EventIn` accepts is observed here, committed and answered as the route
    ``post_event`` would answer it (200 with the advice; 404, 409, 410, 503 with
    ``detail``); anything else (a malformed body: the framework's 422) goes on to the
    application, which documents the route."""

    def __init__(self, app, store: SessionStore):
        self.app = app
        self.store = store

    async def __call__(self, scope, receive, send):
        match = None
        if scope["type"] == "http" and scope["method"] == "POST":
            match = _EVENTS_PATH.match(scope["path"])
        if match is None:
            return await self.app(scope, receive, send)
        message = await receive()
        try:
            event = EventIn.model_validate_json(message.get("body", b""))
        except ValueError:
            event = None
        if event is None:
            return await self.app(scope, _replaying(message, receive), send)
        status, data, headers = 200, None, {}
        sid = match.group(1)
        try:
            with _errors():
                try:
                    advice = self.store.observe(sid, event.model_dump(exclude_none=True))
                except UnknownSession:
                    raise HTTPException(404, f"unknown session {sid!r}") from None
            data = advice_dict(advice)
        except HTTPException as exc:
            status, data, headers = exc.status_code, {"detail": exc.detail}, exc.headers or {}
        body = json.dumps(data, separators=(",", ":"), ensure_ascii=False, allow_nan=False)
        raw = body.encode("utf-8")
        head = [
            (b"content-type", b"application/json"),
            (b"content-length", str(len(raw)).encode()),
            *((k.lower().encode(), v.encode()) for k, v in headers.items()),
        ]
        await send({"type": "http.response.start", "status": status, "headers": head})
        await send({"type": "http.response.body", "body": raw})


def session_view(session, now: float) -> dict:
    """A session as the API gives it: its record, current advice and (real time) clock."""
    return {
        "id": session.id,
        "plan": session.plan_id,
        "condition": session.condition,
        "participant": session.participant,
        "block": session.block,
        "created": session.created,
        "finished": session.finished_at,
        "closed": session.closed,
        "events": session.events,
        "answers": session.answers,
        "outcome": session.outcome(),
        "advice": advice_dict(session.current()),
        "clock": clock_view(session, now),
    }


def advice_dict(advice) -> dict:
    """:meth:`Advice.to_dict <asmplan.advisor.Advice.to_dict>` without its deep copy (the
    advice's lists are its own, made for it): the same JSON, a hundred times faster."""
    return dict(advice.__dict__, total_bound=advice.total_bound)


def json_response(data, status: int = 200, headers: dict | None = None) -> Response:
    """``data`` as compact JSON (no re-encoding by the framework)."""
    text = json.dumps(data, separators=(",", ":"), ensure_ascii=False, allow_nan=False)
    return Response(text, status_code=status, media_type="application/json", headers=headers)


@contextlib.contextmanager
def _errors():
    """The engine's refusals as HTTP answers (the session unchanged in each)."""
    try:
        yield
    except ObservationError as exc:
        raise HTTPException(409, str(exc)) from None
    except StorageError as exc:
        raise HTTPException(503, f"{exc}; nothing was changed, try again", headers=RETRY) from None
    except SessionLimit as exc:
        raise HTTPException(429, str(exc), headers=RETRY) from None
    except SessionClosed as exc:
        raise HTTPException(410, str(exc)) from None
    except (AlreadyAnswered, NotFinished) as exc:
        raise HTTPException(409, str(exc)) from None


RETRY = {"Retry-After": "5"}


def _value_error(_request, exc: ValueError) -> JSONResponse:
    return JSONResponse({"detail": str(exc).splitlines()[0]}, status_code=400)


def _plan_summary(pid: str, plan: dict) -> dict:
    return {
        "id": pid,
        "assembly": plan.get("assembly"),
        "turn_model": plan.get("turn_model"),
        "cost": plan.get("cost"),
        "tct": plan.get("tct"),
        "minimax": plan.get("minimax"),
        "w0": plan["metrics"]["w0"],
    }
