"""``asmplan solve``: the exact robust solution of a game DAG and its metrics."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from asmplan.cli.app import OutputFormat, app
from asmplan.cli.options import GAMES_MAX, finite_or_none, seed_option


@app.command("solve")
def solve_command(
    graph: Path = typer.Argument(..., help="Game DAG (.json asmplan-dag/1 or .graphml)."),
    fmt: OutputFormat = typer.Option(OutputFormat.text, "--format", help="Output format."),
    games: int = typer.Option(
        1000, "--games", min=1, max=GAMES_MAX, help="Simulated random-human games."
    ),
    seed: int = seed_option("Seed of the simulation."),
    wcpl: float | None = typer.Option(
        None,
        "--wcpl",
        callback=finite_or_none,
        help="Reference WCPL for RR (default: the certified one).",
    ),
) -> None:
    """Solve the robot-vs-human game exactly and print the robust plan and its metrics."""
    from asmplan.report.metrics import metrics_text
    from asp.game.io import load_dag
    from asp.game.metrics import plan_metrics

    dag = load_dag(graph)
    metrics = plan_metrics(dag, wcpl=wcpl, n_games=games, seed=seed)
    if fmt is OutputFormat.json:
        typer.echo(json.dumps(metrics.to_dict(), allow_nan=False))
    else:
        typer.echo(metrics_text(metrics, title=f"{graph} ({dag.cost_model})"))
