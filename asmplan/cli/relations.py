"""``asmplan relations``: contact and translational-freedom tables of an assembly."""

from __future__ import annotations

from pathlib import Path

import typer

from asmplan.cli.app import TableFormat, app
from asmplan.cli.options import tolerance_option


@app.command("relations")
def relations_command(
    assembly: Path = typer.Argument(
        ..., help="Folder of part meshes, multi-body scene (GLB/glTF/3MF/STEP) or assembly.yaml."
    ),
    fmt: TableFormat = typer.Option(TableFormat.text, "--format", help="Output format."),
    contact_tol: float | None = tolerance_option("contact_tol"),
    penetration_tol: float | None = tolerance_option("penetration_tol"),
    units: str | None = typer.Option(
        None, "--units", help="Unit of mesh files that declare none (default mm)."
    ),
    progress: bool = typer.Option(False, "--progress", help="Show progress on stderr."),
    why: str | None = typer.Option(
        None,
        "--why",
        metavar="PART",
        help="Explain PART instead: per direction, the parts that block it and its depth "
        "(layers of parts to take out first along that direction).",
    ),
) -> None:
    """Compute TC (contact) and TT (translational freedom) for every pair of parts.

    A folder with an assembly.yaml is read through it (its parts, files and units).
    """
    from asmplan.pipeline import part_relations
    from asmplan.report.relations import (
        relations_csv,
        relations_json,
        relations_markdown,
        relations_text,
        why_json,
        why_text,
    )

    relations = part_relations(
        assembly,
        units=units,
        contact_tol=contact_tol,
        penetration_tol=penetration_tol,
        progress=progress,
    )
    if why is not None:
        render_why = why_json if fmt is TableFormat.json else why_text
        typer.echo(render_why(relations, why), nl=False)
        return
    render = {
        TableFormat.text: relations_text,
        TableFormat.json: relations_json,
        TableFormat.csv: relations_csv,
        TableFormat.markdown: relations_markdown,
    }[fmt]
    typer.echo(render(relations), nl=False)
