"""``asmplan serve``: the advisor service and the page to play the plan (:mod:`asmplan.serve`).

``SOURCE`` is a plan folder written by ``asmplan plan`` (its ``plan.json``), a
``plan.json``, or an assembly (folder, ``assembly.yaml``, ``.IN2``), planned on start.
"""

from __future__ import annotations

import errno
import json
import socket
from pathlib import Path

import typer

from asmplan.cli.app import app
from asmplan.cli.graph import say
from asmplan.cli.options import TurnModel, turn_model_option
from asmplan.serve.limits import DEFAULT_MAX_DB_MB, DEFAULT_MAX_SESSIONS, DEFAULT_TTL

LOCAL_HOSTS = ("127.0.0.1", "localhost", "::1")


def load_source(source: Path, turn_model: str | None = None) -> dict:
    """The plan document of a plan folder, a ``plan.json`` or an assembly (planned in
    ``turn_model``, default the spec's)."""
    from asmplan.pipeline import build_plan
    from asmplan.planfile import read_plan

    if not source.exists():
        raise FileNotFoundError(f"{source}: no such file or folder")
    if (source.is_dir() and (source / "plan.json").is_file()) or source.suffix == ".json":
        return read_plan(source)
    say(f"planning {source} ...")
    return build_plan(source, turn_model=turn_model)


def read_questionnaire(path: Path | None) -> list[dict] | None:
    """Questionnaire items from a JSON file: ``[{"id", "text", "scale": [lo, hi] | null}]``
    (checked as :func:`asmplan.study.questionnaire.items_from_data` does)."""
    if path is None:
        return None
    from asmplan.study.questionnaire import items_from_data

    try:
        items = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path}: not JSON ({exc.msg} at line {exc.lineno})") from None
    if not isinstance(items, list):
        raise ValueError(f"{path}: expected a list of {{'id', 'text', 'scale'}} items")
    items_from_data(items, str(path))
    return items


def default_sessions_folder() -> Path:
    """The per-user data folder for sessions (``~/.local/share/asmplan/sessions`` on Linux,
    ``$XDG_DATA_HOME`` if set; the platform's own elsewhere), never the working folder."""
    import platformdirs

    return Path(platformdirs.user_data_dir("asmplan", appauthor=False)) / "sessions"


def bind(host: str, port: int) -> socket.socket:
    """A listening socket on ``host:port``; ``OSError`` naming the port when it is taken."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((host, port))
        sock.listen(2048)
    except OSError as exc:
        sock.close()
        why = "in use (another service?)" if exc.errno == errno.EADDRINUSE else exc.strerror
        raise OSError(
            exc.errno, f"cannot listen on {host}:{port}: {why}; choose another --port"
        ) from None
    sock.set_inheritable(True)
    return sock


@app.command("serve")
def serve_command(
    sources: list[Path] = typer.Argument(
        None,
        help="Plan folder (plan.json) or assembly (folder, assembly.yaml, .IN2); several "
        "(none with --study: the study's plans).",
    ),
    host: str = typer.Option("127.0.0.1", "--host", help="Address to bind (default: local)."),
    port: int = typer.Option(8000, "--port", min=0, max=65535, help="TCP port."),
    sessions: Path | None = typer.Option(
        None,
        "--sessions",
        help="Folder for the sessions database and log.jsonl (default: the per-user data "
        "folder, ~/.local/share/asmplan/sessions).",
    ),
    questionnaire: Path | None = typer.Option(
        None, "--questionnaire", help="JSON list of questionnaire items (default: built in)."
    ),
    turn_model: TurnModel | None = turn_model_option(
        "An assembly's turn model when planned here (default: spec's)."
    ),
    max_sessions: int = typer.Option(
        DEFAULT_MAX_SESSIONS,
        "--max-sessions",
        min=1,
        help="Most sessions open at once (429 past it).",
    ),
    session_ttl: float = typer.Option(
        DEFAULT_TTL,
        "--session-ttl",
        min=1,
        help="Seconds without an event after which an open session ages out (closed, kept).",
    ),
    fsync: bool = typer.Option(
        False, "--fsync", help="Wait for the disk at every event (survives a power cut)."
    ),
    max_db_mb: float = typer.Option(
        DEFAULT_MAX_DB_MB,
        "--max-db-mb",
        min=1,
        max=1e7,
        help="Largest size of the sessions database, MB (503 past it, nothing changed).",
    ),
    study: Path | None = typer.Option(
        None, "--study", help="A study file (study.yaml): conditions, participants, questionnaire."
    ),
    realtime: float | None = typer.Option(
        None,
        "--realtime",
        min=0.001,
        max=1000,
        help="The clock runs: game seconds per wall-clock second (operations finish on it).",
    ),
) -> None:
    """Serve the advisor's JSON API and the page to play the plan (FastAPI + uvicorn)."""
    import uvicorn

    from asmplan.serve import create_app

    folder = sessions if sessions is not None else default_sessions_folder()
    turn = None if turn_model is None else turn_model.value
    if not sources and study is None:
        raise ValueError("serve: expected a plan folder or assembly, or --study study.yaml")
    the_study = variants = None
    if study is not None:
        from asmplan.study.config import load_study
        from asmplan.study.plans import study_plans

        if questionnaire is not None:
            raise ValueError("--questionnaire: the study file holds the questionnaire")
        the_study = load_study(study)
        variants = study_plans(the_study, say=say)
    plans = [load_source(s, turn) for s in sources or ()]
    items = read_questionnaire(questionnaire)
    sock = bind(host, port)
    application = create_app(
        plans,
        folder,
        questionnaire=items,
        study=the_study,
        variants=variants,
        realtime=realtime,
        max_sessions=max_sessions,
        session_ttl=session_ttl,
        fsync=fsync,
        max_db_mb=max_db_mb,
    )
    store = application.state.store
    for note in store.notes:
        say(f"asmplan: {note}")
    for item in store.set_aside:
        what = f"session {item['session']}" if "session" in item else item["file"]
        say(f"asmplan: warning: {what} set aside ({item['moved_to']}): {item['reason']}")
    if host not in LOCAL_HOSTS:
        say(
            f"asmplan: warning: serving on {host}, reachable from other machines; the "
            "service has no authentication"
        )
    port = sock.getsockname()[1]
    count = len(plans) + len({pid for pid, _ in variants or {}})
    what = f"study {the_study.title!r}: " if the_study else ""
    say(
        f"serving {what}{count} plan(s) on http://{host}:{port}/ (sessions in {folder}, "
        f"{store.open_count} open)"
    )
    config = uvicorn.Config(application, log_level="warning", **fast_server())
    uvicorn.Server(config).run(sockets=[sock])


def fast_server() -> dict:
    """uvicorn's C HTTP parser and libuv event loop where installed (else its defaults)."""
    import importlib.util

    out = {}
    if importlib.util.find_spec("httptools"):
        out["http"] = "httptools"
    if importlib.util.find_spec("uvloop"):
        out["loop"] = "uvloop"
    return out
