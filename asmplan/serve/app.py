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

import re
from importlib import resources
from pathlib import Path
from typing import Literal

from fastapi import FastAPI, HTTPException
from fastapi.responses import FileResponse, HTMLResponse, JSONResponse, Response
from pydantic import BaseModel, ConfigDict, Field

from asmplan.advisor import ObservationError
from asmplan.serve.docs import add_docs
from asmplan.serve.explain import add_explain_routes
from asmplan.serve.meshes import base_parts, plan_meshes
from asmplan.serve.sessions import SessionStore, UnknownSession

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
    """A new session on one of the service's plans."""

    model_config = ConfigDict(extra="forbid")
    plan: str = Field(min_length=1, max_length=64)


class AnswersIn(BaseModel):
    """The questionnaire's answers: item id -> a number or a short text."""

    model_config = ConfigDict(extra="forbid")
    answers: dict[str, int | float | str] = Field(max_length=50)


def plan_id(plan: dict) -> str:
    """A URL-safe id from the assembly's name (``vacuum pump`` -> ``vacuum-pump``; a plan of
    the concurrent game: ``vacuum-pump-concurrent``)."""
    name = re.sub(r"[^a-z0-9]+", "-", str(plan.get("assembly", "plan")).lower()).strip("-")
    return f"{name}-concurrent" if plan.get("turn_model") == "concurrent" else name


def _plotly_js() -> Path:
    return Path(str(resources.files("plotly").joinpath("package_data", "plotly.min.js")))


class BodyLimit:
    """ASGI middleware: refuse request bodies over ``limit`` bytes with 413."""

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
        seen = 0

        async def limited():
            nonlocal seen
            message = await receive()
            if message["type"] == "http.request":
                seen += len(message.get("body", b""))
                if seen > self.limit:
                    raise _TooLarge
            return message

        try:
            return await self.app(scope, limited, send)
        except _TooLarge:
            return await _too_large(send, self.limit)


class _TooLarge(Exception):
    pass


async def _too_large(send, limit: int) -> None:
    body = f'{{"detail":"request body over {limit} bytes"}}'.encode()
    await send(
        {
            "type": "http.response.start",
            "status": 413,
            "headers": [(b"content-type", b"application/json")],
        }
    )
    await send({"type": "http.response.body", "body": body})


def create_app(
    plans: list[dict], state_dir: str | Path, *, questionnaire: list[dict] | None = None
) -> FastAPI:
    """The service for ``plans`` (plan documents), keeping its sessions in ``state_dir``."""
    by_id: dict[str, dict] = {}
    for plan in plans:
        pid = plan_id(plan)
        if pid in by_id:
            raise ValueError(f"two plans named {pid!r}: give each assembly its own name")
        by_id[pid] = plan
    store = SessionStore(Path(state_dir), by_id)
    meshes: dict[str, dict] = {}
    items = list(questionnaire if questionnaire is not None else DEFAULT_QUESTIONNAIRE)
    static_dir = resources.files("asmplan.serve").joinpath("static")

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
    add_explain_routes(app, store, by_id)
    app.state.store = store

    def _plan(pid: str) -> dict:
        plan = by_id.get(pid)
        if plan is None:
            raise HTTPException(404, f"unknown plan {pid!r}")
        return plan

    def _session(sid: str):
        try:
            return store.get(sid)
        except UnknownSession:
            raise HTTPException(404, f"unknown session {sid!r}") from None

    def _session_view(session) -> dict:
        return {
            "id": session.id,
            "plan": session.plan_id,
            "created": session.created,
            "finished": session.finished_at,
            "events": session.events,
            "answers": session.answers,
            "outcome": session.outcome(),
            "advice": session.advisor.advice().to_dict(),
        }

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
    def get_plan(pid: str) -> dict:
        """One plan: metrics, operations, parts, agents, the principal and worst lines."""
        plan = _plan(pid)
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
        )
        return out

    @app.get("/api/plans/{pid}/meshes")
    def get_meshes(pid: str) -> dict:
        """Part id -> mesh arrays (``x, y, z, i, j, k``) for a plotly Mesh3d."""
        plan = _plan(pid)
        if pid not in meshes:
            meshes[pid] = plan_meshes(plan)
        return meshes[pid]

    @app.post("/api/sessions", status_code=201)
    def new_session(body: SessionIn) -> dict:
        """Start a session (a cell, or a person playing) on a plan."""
        _plan(body.plan)
        return _session_view(store.create(body.plan))

    @app.get("/api/sessions")
    def list_sessions() -> list[dict]:
        """Every session: id, plan, number of events, outcome."""
        return [
            {
                "id": s.id,
                "plan": s.plan_id,
                "created": s.created,
                "events": len(s.events),
                "outcome": s.outcome(),
            }
            for s in store.all()
        ]

    @app.get("/api/sessions/{sid}")
    def get_session(sid: str) -> dict:
        """A session's record and its current advice."""
        return _session_view(_session(sid))

    @app.post("/api/sessions/{sid}/events")
    def post_event(sid: str, body: EventIn) -> dict:
        """Observe an event; 409 naming the problem if the plan cannot explain it."""
        _session(sid)
        try:
            advice = store.observe(sid, body.model_dump(exclude_none=True))
        except ObservationError as exc:
            raise HTTPException(409, str(exc)) from None
        return advice.to_dict()

    @app.get("/api/questionnaire")
    def get_questionnaire() -> list[dict]:
        """The end-of-game questionnaire's items (``scale``: ``[min, max]`` or null: text)."""
        return items

    @app.post("/api/sessions/{sid}/answers")
    def post_answers(sid: str, body: AnswersIn) -> dict:
        """Store the questionnaire's answers with the session."""
        _session(sid)
        known = {item["id"] for item in items}
        unknown = sorted(set(body.answers) - known)
        if unknown:
            raise HTTPException(422, f"unknown questionnaire item {unknown[0]!r}")
        return _session_view(store.answer(sid, body.answers))

    @app.get("/api/export.csv")
    def export_csv() -> Response:
        """Every session as one CSV row."""
        return Response(store.csv(), media_type="text/csv")

    @app.exception_handler(ValueError)
    def value_error(_request, exc: ValueError) -> JSONResponse:
        return JSONResponse({"detail": str(exc).splitlines()[0]}, status_code=400)

    app.add_middleware(BodyLimit, limit=MAX_BODY)
    return app


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
