"""The routes of the advice that explains itself (the page asks for them beside the events).

:meth:`asmplan.advisor.Advisor.explain` gives each option the robots' reply, the worst line
it leads to and a sentence saying both, and the plan ahead (the Gantt chart's). It costs
more than the plain advice (the options times the operations left), so the event route
answers the plain advice at once and the page asks for the explanation beside it:

- ``GET /api/sessions/{session}/explain``: the session's current advice, explained;
- ``GET /api/plans/{plan}/explain``: the advice at the plan's start, explained (no session
  is made: a page shows the first move before anyone has played).
"""

from __future__ import annotations

from fastapi import FastAPI, HTTPException

from asmplan.advisor import Advisor
from asmplan.serve.sessions import SessionStore, UnknownSession


def add_explain_routes(app: FastAPI, store: SessionStore, plans: dict[str, dict]) -> None:
    """Add the explanation routes for the sessions of ``store`` and ``plans`` (id -> plan)."""
    starts: dict[str, dict] = {}

    @app.get("/api/sessions/{sid}/explain")
    def explain_session(sid: str) -> dict:
        """The session's current advice with each option explained and the plan ahead."""
        try:
            session = store.get(sid)
        except UnknownSession:
            raise HTTPException(404, f"unknown session {sid!r}") from None
        return session.advisor.explain().to_dict()

    @app.get("/api/plans/{pid}/explain")
    def explain_start(pid: str) -> dict:
        """The advice at the plan's start, explained (the same for every new session)."""
        plan = plans.get(pid)
        if plan is None:
            raise HTTPException(404, f"unknown plan {pid!r}")
        if pid not in starts:
            starts[pid] = Advisor(plan).explain().to_dict()
        return starts[pid]
