"""``asmplan synth``: a synthetic assembly DAG (paper, section 3.2)."""

from __future__ import annotations

from pathlib import Path

import typer

from asmplan.cli.app import app
from asmplan.cli.options import check_output, seed_option

MAX_LAYERS = 1_000
MAX_NODES_PER_LAYER = 1_000
MAX_ACTIONS = 100


@app.command("synth")
def synth_command(
    layers: int = typer.Option(
        ..., "--layers", min=1, max=MAX_LAYERS, help="Inner layers L (1 to 1000)."
    ),
    max_nodes: int = typer.Option(
        ...,
        "--max-nodes",
        min=1,
        max=MAX_NODES_PER_LAYER,
        help="Maximum nodes per layer M (1 to 1000).",
    ),
    max_actions: int = typer.Option(
        4, "--max-actions", min=1, max=MAX_ACTIONS, help="Maximum actions per node A (1 to 100)."
    ),
    seed: int = seed_option("Generator seed."),
    output: Path = typer.Option(..., "--output", "-o", help="Graph file (.json or .graphml)."),
) -> None:
    """Generate a synthetic assembly DAG (paper, section 3.2)."""
    from asp.game.io import save_dag
    from asp.game.synth import synthetic_dag

    check_output(output, folder=False)
    dag = synthetic_dag(layers, max_nodes, max_actions, seed=seed)
    save_dag(dag, output)
    typer.echo(f"wrote {output}: {dag.n_nodes} nodes, {dag.n_edges} edges")
