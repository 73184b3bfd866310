"""The Typer application and the error policy every command shares.

Bad input (a ``ValueError``, a missing or unreadable file) ends the command with a one-line
message on stderr and exit code 2; nothing is half-written because every output goes
through :func:`asp.atomic.write_text` / :func:`asp.atomic.write_bytes`.
"""

from __future__ import annotations

import sys
from enum import StrEnum

import typer

app = typer.Typer(
    name="asmplan",
    help="Robust human-robot collaborative assembly planning.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


class OutputFormat(StrEnum):
    """Output format of a command that prints a result."""

    text = "text"
    json = "json"


class TableFormat(StrEnum):
    """Output format of a command that prints tables."""

    text = "text"
    json = "json"
    csv = "csv"
    markdown = "markdown"


def fail(message: str) -> None:
    """Print ``asmplan: error: message`` on stderr and exit with code 2."""
    typer.echo(f"asmplan: error: {message}", err=True)
    raise typer.Exit(code=2)


def main(argv: list[str] | None = None) -> None:
    """Console entry point: run the app, turning bad input into exit code 2."""
    try:
        app(args=argv, standalone_mode=True)
    except (ValueError, FileNotFoundError, IsADirectoryError, PermissionError) as exc:
        message = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        print(f"asmplan: error: {message}", file=sys.stderr)
        sys.exit(2)
