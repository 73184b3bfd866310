"""The study's part of the service API (``asmplan serve --study study.yaml``).

- ``GET /api/study``: title, consent, design, conditions (``id``, ``label``), plans,
  questionnaire, real-time speed.
- ``POST /api/participants`` ``{"participant"?: "P07"}``: enrols a participant (an id is
  made when none is given) and answers its assignment; the same id again answers the same
  (a participant who comes back resumes): ``{"id", "number", "blocks": [{"block", "plan",
  "condition", "label", "session", "finished", "answered"}], "next"}`` (``next``: the first
  block not both finished and answered, None when all are).
- ``GET /api/participants``, ``GET /api/participants/{id}``.

A block's session is made by ``POST /api/sessions {"participant", "block", "event"}`` (its
plan and condition come from the assignment; a block whose session is still open answers
409 naming it: resume that one).
"""

from __future__ import annotations

import secrets

from fastapi import FastAPI, HTTPException
from fastapi.responses import Response
from pydantic import BaseModel, ConfigDict, Field

from asmplan.study.assignment import blocks
from asmplan.study.config import Study


class ParticipantIn(BaseModel):
    """A participant to enrol (an id is made when none is given)."""

    model_config = ConfigDict(extra="forbid")
    participant: str | None = Field(None, min_length=1, max_length=64, pattern=r"^[A-Za-z0-9_.-]+$")


def add_study_routes(app: FastAPI, store, study: Study, json_response) -> None:
    """Register the study's routes on ``app`` (``store``: its SessionStore)."""
    plan_ids = list(dict.fromkeys(pid for pid, cond in store.plans if cond is not None))
    labels = {c.id: c.label for c in study.conditions}

    def assign(pid: str):
        def make(number: int) -> list[dict]:
            return blocks(
                plan_ids,
                [c.id for c in study.conditions],
                design=study.design,
                order=study.order,
                plan_order=study.plan_order,
                seed=study.seed,
                number=number,
                participant=pid,
            )

        return make

    def view(record: dict) -> dict:
        sessions = store.block_sessions(record["id"])
        out, nxt = [], None
        for b in record["blocks"]:
            sid = sessions.get(b["block"])
            session = store.get(sid) if sid else None
            finished = bool(session and session.finished_at)
            answered = bool(session and session.answered_at)
            out.append(
                {
                    **b,
                    "label": labels.get(b["condition"], b["condition"]),
                    "session": sid,
                    "finished": finished,
                    "answered": answered,
                }
            )
            if nxt is None and not (finished and answered):
                nxt = b["block"]
        return {"id": record["id"], "number": record["number"], "blocks": out, "next": nxt}

    @app.get("/api/study")
    async def get_study() -> Response:
        """The study: title, consent, design, conditions, plans, questionnaire."""
        return json_response({**study.summary(), "plans": plan_ids})

    @app.post("/api/participants")
    async def enrol(body: ParticipantIn) -> Response:
        """Enrol a participant (or resume one): its blocks, in order."""
        pid = body.participant or f"P{secrets.token_hex(4)}"
        known = store.participant(pid) is not None
        record = store.enrol(pid, assign(pid))
        return json_response(view(record), 200 if known else 201)

    @app.get("/api/participants")
    async def list_participants() -> Response:
        """Every participant with the blocks assigned."""
        return json_response([view(r) for r in store.participants()])

    @app.get("/api/participants/{pid}")
    async def get_participant(pid: str) -> Response:
        """One participant's blocks, sessions and what comes next."""
        record = store.participant(pid)
        if record is None:
            raise HTTPException(404, f"unknown participant {pid!r}")
        return json_response(view(record))


def block_of(store, participant: str, block: int) -> dict:
    """The plan and condition of a participant's block (HTTP errors: 404, 409)."""
    record = store.participant(participant)
    if record is None:
        raise HTTPException(404, f"unknown participant {participant!r}: enrol first")
    if not 0 <= block < len(record["blocks"]):
        raise HTTPException(404, f"participant {participant} has no block {block}")
    sid = store.block_sessions(participant).get(block)
    if sid is not None and store.get(sid).closed is None:
        raise HTTPException(
            409, f"block {block} of participant {participant} has session {sid}: resume it"
        )
    return record["blocks"][block]
