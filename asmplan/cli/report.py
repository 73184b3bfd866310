"""``asmplan report``: redraw ``report.html`` from a plan folder, solving nothing.

The page is a function of the folder's ``plan.json`` and, for an alternate plan, its
``dag.png`` (:func:`asmplan.report.html.plan_report`; a concurrent plan's page draws its
concurrent game's figures only), so a report can be drawn again, e.g. after the page's
layout changed, without planning again.
"""

from __future__ import annotations

from pathlib import Path

import typer

from asmplan.cli.app import app
from asmplan.cli.options import check_output


@app.command("report")
def report_command(
    plan_dir: Path = typer.Argument(
        ..., help="A folder written by 'asmplan plan' (its plan.json, alternate: dag.png)."
    ),
    output: Path | None = typer.Option(
        None, "--output", "-o", help="The page to write (default: PLAN_DIR/report.html)."
    ),
) -> None:
    """Redraw report.html from a plan folder's plan.json (and an alternate plan's dag.png)."""
    from asmplan.planfile import read_plan
    from asmplan.report.html import plan_report
    from asp.atomic import write_text

    if not plan_dir.is_dir():
        raise FileNotFoundError(f"{plan_dir}: no such plan folder ('asmplan plan -o' writes one)")
    check_output(output, folder=False)
    doc = read_plan(plan_dir)
    dag = plan_dir / "dag.png"
    page = plan_report(doc, dag.read_bytes() if dag.is_file() else None)
    written = write_text(plan_dir / "report.html" if output is None else output, page)
    typer.echo(f"wrote {written}")
