"""``asmplan init``: write the spec generated from a CAD file, for the user to edit."""

from __future__ import annotations

from pathlib import Path

import typer

from asmplan.cli.app import app
from asmplan.cli.options import check_output, gravity_option, tolerance_option, units_option


@app.command("init")
def init_command(
    source: Path = typer.Argument(
        ..., help="CAD file (STEP, glTF/GLB, 3MF, 3DXML, mesh) or folder of part meshes."
    ),
    output: Path = typer.Option(
        Path("assembly.yaml"), "--output", "-o", help="Spec file to write."
    ),
    force: bool = typer.Option(False, "--force", help="Overwrite an existing spec file."),
    contact_tol: float | None = tolerance_option("contact_tol"),
    penetration_tol: float | None = tolerance_option("penetration_tol"),
    units: str | None = units_option(),
    gravity: str | None = gravity_option(),
) -> None:
    """Generate assembly.yaml from CAD: parts, a default cell (H, R1), one placement each."""
    import yaml

    from asp.atomic import write_text
    from asp.fromcad.generate import spec_text
    from asp.spec import spec_from_dict
    from asp.subassemblies import file_units
    from cad.yamlfile import DecimalsAsText

    if not source.exists():
        raise FileNotFoundError(f"{source}: no such file or folder")
    check_output(output, folder=False)
    if output.exists() and not force:
        raise ValueError(f"{output} exists (use --force to overwrite it)")

    def say(line: str) -> None:
        typer.echo(line, err=True)

    text = spec_text(
        source,
        spec_folder=output.parent,
        contact_tol=contact_tol,
        penetration_tol=penetration_tol,
        on_note=say,
        decide_units=lambda spec, rel: file_units(spec, rel, on_unit=say),
        units=units,
        gravity=gravity,
    )
    # the text must read back as a valid spec before it is written
    spec = spec_from_dict(yaml.load(text, Loader=DecimalsAsText), source=str(output))  # noqa: S506
    write_text(output, text)
    typer.echo(
        f"wrote {output}: {len(spec.parts)} parts, {len(spec.operations)} operations, "
        f"agents {', '.join(a.name for a in spec.agents)}; edit it, then "
        f"`asmplan plan {output}`"
    )
