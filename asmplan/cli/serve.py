"""``asmplan serve``: the advisor service and the page to play the plan (:mod:`asmplan.serve`).

``SOURCE`` is a plan folder written by ``asmplan plan`` (its ``plan.json``), a
``plan.json``, or an assembly (folder, ``assembly.yaml``, ``.IN2``), planned on start.
"""

from __future__ import annotations

import json
from pathlib import Path

import typer

from asmplan.cli.app import app
from asmplan.cli.graph import say
from asmplan.cli.options import TurnModel, turn_model_option

LOCAL_HOSTS = ("127.0.0.1", "localhost", "::1")


def load_source(source: Path, turn_model: str | None = None) -> dict:
    """The plan document of a plan folder, a ``plan.json`` or an assembly (planned in
    ``turn_model``, default the spec's)."""
    from asmplan.planfile import build_plan, read_plan

    if not source.exists():
        raise FileNotFoundError(f"{source}: no such file or folder")
    if (source.is_dir() and (source / "plan.json").is_file()) or source.suffix == ".json":
        return read_plan(source)
    say(f"planning {source} ...")
    return build_plan(source, turn_model=turn_model)


def read_questionnaire(path: Path | None) -> list[dict] | None:
    """Questionnaire items from a JSON file: ``[{"id", "text", "scale": [lo, hi] | null}]``."""
    if path is None:
        return None
    try:
        items = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path}: not JSON ({exc.msg} at line {exc.lineno})") from None
    if not isinstance(items, list) or not all(
        isinstance(i, dict) and isinstance(i.get("id"), str) and isinstance(i.get("text"), str)
        for i in items
    ):
        raise ValueError(f"{path}: expected a list of {{'id', 'text', 'scale'}} items")
    return items


@app.command("serve")
def serve_command(
    sources: list[Path] = typer.Argument(
        ..., help="Plan folder (plan.json) or assembly (folder, assembly.yaml, .IN2); several."
    ),
    host: str = typer.Option("127.0.0.1", "--host", help="Address to bind (default: local)."),
    port: int = typer.Option(8000, "--port", min=0, max=65535, help="TCP port."),
    sessions: Path = typer.Option(
        Path("asmplan-sessions"), "--sessions", help="Folder for the sessions and log.jsonl."
    ),
    questionnaire: Path | None = typer.Option(
        None, "--questionnaire", help="JSON list of questionnaire items (default: built in)."
    ),
    turn_model: TurnModel | None = turn_model_option(
        "An assembly's turn model when planned here (default: spec's)."
    ),
) -> None:
    """Serve the advisor's JSON API and the page to play the plan (FastAPI + uvicorn)."""
    import uvicorn

    from asmplan.serve import create_app

    turn = None if turn_model is None else turn_model.value
    plans = [load_source(s, turn) for s in sources]
    items = read_questionnaire(questionnaire)
    application = create_app(plans, sessions, questionnaire=items)
    if host not in LOCAL_HOSTS:
        say(
            f"asmplan: warning: serving on {host}, reachable from other machines; the "
            "service has no authentication"
        )
    say(f"serving {len(plans)} plan(s) on http://{host}:{port}/ (sessions in {sessions})")
    uvicorn.run(application, host=host, port=port, log_level="warning")
