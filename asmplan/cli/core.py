"""Core commands: ``asmplan synth`` and ``asmplan solve``."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from asmplan.cli.app import OutputFormat, app


@app.command("synth")
def synth_command(
    layers: int = typer.Option(..., "--layers", help="Inner layers L."),
    max_nodes: int = typer.Option(..., "--max-nodes", help="Maximum nodes per layer M."),
    max_actions: int = typer.Option(4, "--max-actions", help="Maximum actions per node A."),
    seed: int = typer.Option(0, "--seed", help="Generator seed."),
    output: Path = typer.Option(..., "--output", "-o", help="Graph file (.json or .graphml)."),
) -> None:
    """Generate a synthetic assembly DAG (paper, section 3.2)."""
    from asp.io import save_dag
    from asp.synth import synthetic_dag

    dag = synthetic_dag(layers, max_nodes, max_actions, seed=seed)
    save_dag(dag, output)
    typer.echo(f"wrote {output}: {dag.n_nodes} nodes, {dag.n_edges} edges")


@app.command("solve")
def solve_command(
    graph: Path = typer.Argument(..., help="Game DAG (.json asmplan-dag/1 or .graphml)."),
    fmt: OutputFormat = typer.Option(OutputFormat.text, "--format", help="Output format."),
    games: int = typer.Option(1000, "--games", help="Simulated random-human games."),
    seed: int = typer.Option(0, "--seed", help="Seed of the simulation."),
    wcpl: float | None = typer.Option(
        None, "--wcpl", help="Reference WCPL for RR (default: the certified one)."
    ),
) -> None:
    """Solve the robot-vs-human game exactly and print the robust plan and its metrics."""
    from asp.io import load_dag
    from asp.metrics import plan_metrics
    from asp.report import metrics_text

    dag = load_dag(graph)
    metrics = plan_metrics(dag, wcpl=wcpl, n_games=games, seed=seed)
    if fmt is OutputFormat.json:
        typer.echo(json.dumps(metrics.to_dict()))
    else:
        typer.echo(metrics_text(metrics, title=f"{graph} ({dag.cost_model})"))
