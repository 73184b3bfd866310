"""``asmplan baseline``: the CP-SAT baseline of a ``.sm``, a game DAG or an assembly."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from asmplan.cli.app import OutputFormat, app
from asmplan.cli.options import WORKERS_MAX, seed_option, time_limit_option


def baseline_result(source: Path, *, time_limit: float, workers: int, seed: int):
    """Dispatch by input: PSPLIB ``.sm``, a game DAG file, or an assembly."""
    from asmplan import pipeline
    from asp.schedule.makespan import min_makespan
    from asp.schedule.path import min_cost_path

    suffix = source.suffix.lower()
    if suffix == ".sm":
        from asp.schedule.psplib import read_sm

        return min_makespan(read_sm(source), time_limit=time_limit, workers=workers, seed=seed)
    if suffix in pipeline.GRAPH_SUFFIXES:
        from asp.game.io import load_dag

        dag = load_dag(source)
        return min_cost_path(dag, time_limit=time_limit, workers=workers, seed=seed)
    assembly = pipeline.load(source)
    graph = pipeline.state_graph(assembly)
    sched = pipeline.schedule(assembly, graph, time_limit=time_limit, workers=workers, seed=seed)
    sched.result.detail.update(
        lower_bound=sched.lower_bound, chain_bound=sched.chain_bound, load_bound=sched.load_bound
    )
    return sched.result


@app.command("baseline")
def baseline_command(
    source: Path = typer.Argument(
        ..., help="PSPLIB .sm, game DAG (.json/.graphml), or assembly (folder, yaml, .IN2)."
    ),
    fmt: OutputFormat = typer.Option(OutputFormat.text, "--format", help="Output format."),
    time_limit: float = time_limit_option(60.0),
    workers: int = typer.Option(
        1, "--workers", min=1, max=WORKERS_MAX, help="CP-SAT workers (1: repeatable)."
    ),
    seed: int = seed_option("CP-SAT random seed."),
) -> None:
    """CP-SAT baseline: minimum makespan (.sm, assembly) or minimum-cost path (game DAG)."""
    if not source.exists():
        raise FileNotFoundError(f"{source}: no such file or folder")
    result = baseline_result(source, time_limit=time_limit, workers=workers, seed=seed)
    data = result.to_dict()
    if fmt is OutputFormat.json:
        typer.echo(json.dumps(data, allow_nan=False))
        return
    what = "minimum-cost path" if result.kind == "path" else "minimum makespan"
    typer.echo(f"{result.name}: CP-SAT {what}")
    typer.echo(f"  status     {result.status}")
    typer.echo(f"  objective  {data['objective']}")
    typer.echo(f"  bound      {data['bound']}")
    if "lower_bound" in data:
        typer.echo(f"  state-graph lower bound  {data['lower_bound']:g}")
    typer.echo(f"  wall       {data['wall_s']} s")
    if data.get("rounded"):
        typer.echo(
            f"  note       costs rounded to 1/{data['scale']} for CP-SAT (int64); the objective "
            "is the exact cost of the path found"
        )
    if result.kind == "path" and "operations" in data:
        typer.echo("  path: " + " -> ".join(data["operations"]))
    if result.kind == "schedule" and "schedule" in data and len(data["schedule"]) <= 60:
        for row in data["schedule"]:
            agent = f" {row['agent']}" if row["agent"] else ""
            typer.echo(f"    {row['task']:>6s}{agent:4s} {row['start']:>7} .. {row['end']}")
    if result.credit:
        typer.echo(result.credit)
