"""The Typer application and the error policy every command shares.

Bad input ends a command with one line on stderr, ``asmplan: error: <message>``, and exit
code 2, whatever raised it:

- the library's :class:`~asmplan.errors.AsmplanError` family (and any ``ValueError``);
- a missing, unreadable or unwritable file or folder, a full disk (the ``OSError`` family);
- input nested too deep to read (``RecursionError``) or numbers too large to convert
  (``OverflowError``);
- a bad command line (unknown option, value out of range, missing argument): Typer's
  multi-line error box becomes the same one line.

A library warning (a non-watertight part, a generated spec) is one line
``asmplan: warning: <message>``. The policy lives in :class:`AsmplanGroup`, the click group
behind ``app``, so ``main()``, ``python -m asmplan`` and
``typer.testing.CliRunner().invoke(app, ...)`` behave alike.
Outputs go through :mod:`asp.atomic`, so a failed command never leaves a half-written file.
"""

from __future__ import annotations

import importlib
import sys
import warnings
from enum import StrEnum

import typer
from typer.core import TyperGroup

_EXCEPTIONS = importlib.import_module(typer.BadParameter.__module__)
"""The exceptions of the click that Typer runs on (its own copy from Typer 0.25 on)."""
ClickException = _EXCEPTIONS.ClickException
UsageError = _EXCEPTIONS.UsageError
NoArgsIsHelpError = getattr(_EXCEPTIONS, "NoArgsIsHelpError", ())

BAD_INPUT = (ValueError, OSError, RecursionError, OverflowError)
"""Exceptions that mean bad input or an unusable path (``AsmplanError`` is a ``ValueError``)."""
EXIT_BAD_INPUT = 2


def error_line(exc: BaseException) -> str:
    """The one-line message of ``exc`` (an ``OSError`` names its file and its reason)."""
    if isinstance(exc, RecursionError):
        return "input nested too deeply to read (recursion limit reached)"
    if isinstance(exc, OSError) and exc.strerror:
        where = exc.filename if exc.filename is not None else ""
        return f"{where}: {exc.strerror.lower()}" if where else exc.strerror.lower()
    text = exc.format_message() if isinstance(exc, ClickException) else str(exc)
    lines = text.strip().splitlines()
    return lines[0].strip() if lines else type(exc).__name__


def _usage_line(exc: UsageError) -> str:
    line = error_line(exc)
    if exc.ctx is not None:
        line += f" (see '{exc.ctx.command_path} --help')"
    return line


class AsmplanGroup(TyperGroup):
    """The command group: runs a command and applies the one-line error policy."""

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        with warnings.catch_warnings():
            warnings.showwarning = _show_warning
            return self._run(args, prog_name, complete_var, standalone_mode, **extra)

    def _run(self, args, prog_name, complete_var, standalone_mode, **extra):
        try:
            code = super().main(
                args=args,
                prog_name=prog_name or "asmplan",
                complete_var=complete_var,
                standalone_mode=False,
                **extra,
            )
        except NoArgsIsHelpError as exc:
            exc.show()
            code = EXIT_BAD_INPUT
        except UsageError as exc:
            code = _report(_usage_line(exc))
        except typer.Abort:
            typer.echo("asmplan: aborted", err=True)
            code = 1
        except ClickException as exc:
            typer.echo(f"asmplan: error: {error_line(exc)}", err=True)
            code = exc.exit_code
        except BAD_INPUT as exc:
            code = _report(error_line(exc))
        if not standalone_mode:
            return code
        sys.exit(code if isinstance(code, int) else 0)


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """A library warning as one line: ``asmplan: warning: <message>``."""
    text = " ".join(str(message).split())
    print(f"asmplan: warning: {text}", file=sys.stderr if file is None else file, flush=True)


def _report(message: str) -> int:
    typer.echo(f"asmplan: error: {message}", err=True)
    return EXIT_BAD_INPUT


app = typer.Typer(
    name="asmplan",
    cls=AsmplanGroup,
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


def choices(name: str, values: tuple[str, ...], doc: str = "") -> type[StrEnum]:
    """A Typer choice enum built from a domain tuple (the CLI never copies the constants)."""
    enum = StrEnum(name, {v.replace("-", "_"): v for v in values})
    enum.__doc__ = doc or f"One of {', '.join(values)}."
    return enum


def fail(message: str) -> None:
    """Print ``asmplan: error: message`` on stderr and exit with code 2."""
    typer.echo(f"asmplan: error: {message}", err=True)
    raise typer.Exit(code=EXIT_BAD_INPUT)


def main(argv: list[str] | None = None) -> None:
    """Console entry point: run the app (exit 2 and one line on bad input)."""
    app(args=argv)
