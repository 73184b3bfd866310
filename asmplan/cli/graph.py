"""``asmplan graph``: the assembly state graph and the game DAG of an assembly."""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import typer

from asmplan.cli.app import OutputFormat, app
from asmplan.cli.options import CostModel, check_output, max_states_option

LIST_MAX = 1_000_000


def say(message: str) -> None:
    """Progress for a person: one line on stderr."""
    print(message, file=sys.stderr, flush=True)


@app.command("graph")
def graph_command(
    assembly: Path = typer.Argument(..., help="Folder with assembly.yaml, the YAML, or a .IN2."),
    output: Path | None = typer.Option(
        None, "--output", "-o", help="Game DAG file to write (.json or .graphml)."
    ),
    fmt: OutputFormat = typer.Option(OutputFormat.json, "--format", help="Output format."),
    cost: CostModel | None = typer.Option(None, "--cost", help="Cost model (default: spec's)."),
    progress: bool = typer.Option(False, "--progress", help="Print progress on stderr."),
    list_sequences: int = typer.Option(
        0,
        "--list",
        min=0,
        max=LIST_MAX,
        help="Also list up to N feasible complete sequences (the AST).",
    ),
    max_states: int | None = max_states_option(),
) -> None:
    """Build the assembly state graph and the game DAG; print the sizes, write the DAG."""
    from asmplan import pipeline
    from asp.game.io import save_dag

    check_output(output, folder=False)
    t0 = time.perf_counter()
    loaded = pipeline.load(assembly, progress=progress, on_step=say if progress else None)
    spec = loaded.spec
    graph = pipeline.state_graph(loaded, progress=progress, max_states=max_states)
    sequences = graph.count_sequences()
    dag = pipeline.game(graph, cost=None if cost is None else cost.value)
    if output is not None:
        save_dag(dag, output)
    result = {
        "assembly": spec.name,
        "operations": len(spec.operations),
        "states": graph.n_states,
        "transitions": graph.n_transitions,
        "sequences": sequences,
        "dead_end_states": dag.metadata["dead_end_states"],
        "game_nodes": dag.n_nodes,
        "game_edges": dag.n_edges,
        "cost": dag.cost_model,
        "output": None if output is None else str(output),
        "wall_s": round(time.perf_counter() - t0, 3),
    }
    if list_sequences:
        result["sequence_table"] = graph.sequences(limit=list_sequences)
    if spec.credit:
        result["credit"] = spec.credit
    if fmt is OutputFormat.json:
        typer.echo(json.dumps(result, allow_nan=False))
        return
    typer.echo(
        f"{spec.name}: {result['operations']} operations, {graph.n_states:,} states, "
        f"{graph.n_transitions:,} transitions, {sequences:,} feasible sequences"
    )
    typer.echo(
        f"game DAG ({dag.cost_model}): {dag.n_nodes:,} nodes, {dag.n_edges:,} edges"
        + ("" if output is None else f" -> {output}")
    )
    for k, seq in enumerate(result.get("sequence_table", []), start=1):
        typer.echo(f"  sequence {k}: " + " ".join(seq))
    if spec.credit:
        typer.echo(spec.credit)
