"""``asmplan relations``: contact and translational-freedom tables of an assembly."""

from __future__ import annotations

from pathlib import Path

import typer

from asmplan.cli.app import TableFormat, app


@app.command("relations")
def relations_command(
    assembly: Path = typer.Argument(
        ...,
        help="Folder of part meshes (or with assembly.yaml), multi-body scene "
        "(GLB/glTF/3MF/3DXML/STEP) or assembly.yaml.",
    ),
    fmt: TableFormat = typer.Option(TableFormat.text, "--format", help="Output format."),
    contact_tol: float | None = typer.Option(
        None, "--contact-tol", help="Contact tolerance in mm (default 0.01)."
    ),
    penetration_tol: float | None = typer.Option(
        None,
        "--penetration-tol",
        help="Penetration tolerance in mm for every pair (default: per part, scaled with its "
        "size and thickness, see cad/tolerances.py; a pair gets the sum, at most 0.5 mm).",
    ),
    units: str | None = typer.Option(
        None, "--units", help="Unit of mesh files that declare none (default mm)."
    ),
    progress: bool = typer.Option(False, "--progress", help="Show progress on stderr."),
) -> None:
    """Compute TC (contact) and TT (translational freedom) for every pair of parts."""
    from cad import compute_relations
    from cad.report import relations_csv, relations_json, relations_markdown, relations_text

    loaded = load_geometry(assembly, units)
    relations = compute_relations(
        loaded, contact_tol=contact_tol, penetration_tol=penetration_tol, progress=progress
    )
    render = {
        TableFormat.text: relations_text,
        TableFormat.json: relations_json,
        TableFormat.csv: relations_csv,
        TableFormat.markdown: relations_markdown,
    }[fmt]
    typer.echo(render(relations), nl=False)


def load_geometry(path: Path, units: str | None = None):
    """The parts of ``path``: an assembly spec's (a YAML, or a folder holding
    ``assembly.yaml``), else the meshes of a folder or scene file."""
    from dataclasses import replace

    from asp.generate import spec_geometry
    from asp.spec import SPEC_FILE, load_spec
    from cad import load_assembly

    if path.suffix.lower() in (".yaml", ".yml") or (path.is_dir() and (path / SPEC_FILE).is_file()):
        spec = load_spec(path)
        return spec_geometry(spec if units is None else replace(spec, units=units))
    return load_assembly(path, units=units)
