"""``asmplan study``: a trust study's data (:mod:`asmplan.study`).

``asmplan study export DIR [--format csv|json] [--table events|sessions] [-o FILE]``
writes the record of the sessions folder ``DIR`` of ``asmplan serve`` (one row per event,
or per session with the questionnaire's answers; :mod:`asmplan.study.export`), to stdout or
atomically to ``FILE``.
"""

from __future__ import annotations

from pathlib import Path

import typer

from asmplan.cli.app import app, choices

study_app = typer.Typer(help="A trust study's data: export the sessions of asmplan serve.")
app.add_typer(study_app, name="study")

ExportFormat = choices("ExportFormat", ("csv", "json"), "Output format of the export.")
ExportTable = choices("ExportTable", ("events", "sessions"), "One row per event or per session.")


@study_app.command("export")
def export_command(
    folder: Path = typer.Argument(..., help="The sessions folder of asmplan serve (--sessions)."),
    fmt: ExportFormat = typer.Option(ExportFormat.csv, "--format", help="csv or json."),
    table: ExportTable = typer.Option(
        ExportTable.events, "--table", help="CSV: events (one row each) or sessions."
    ),
    output: Path | None = typer.Option(None, "--output", "-o", help="File (default: stdout)."),
) -> None:
    """Export every event (wall-clock time, state, instruction, move, deviation, worst case
    before and after, condition) or every session with its answers."""
    from asmplan.study.export import export
    from asp.atomic import write_text

    text = export(folder, fmt.value, table.value)
    if output is None:
        typer.echo(text, nl=False)
    else:
        write_text(output, text)
        typer.echo(f"wrote {output}", err=True)
