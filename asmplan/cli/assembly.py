"""Assembly commands: ``asmplan graph``, ``asmplan baseline`` and ``asmplan plan``.

``ASSEMBLY`` is a folder holding ``assembly.yaml``, an ``assembly.yaml`` itself, a Scholl
``.IN2`` precedence graph, or a CAD file (STEP, glTF/GLB, 3MF, 3DXML) or folder of part
meshes, for which a spec is generated (``asmplan init`` writes it). Heavy libraries (cad,
OR-Tools, matplotlib) load inside the commands.
"""

from __future__ import annotations

import json
import sys
import time
from enum import StrEnum
from pathlib import Path

import typer

from asmplan.cli.app import OutputFormat, app


class CostModel(StrEnum):
    """Cost of a move."""

    steps = "steps"
    time = "time"


def _progress(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def _load(assembly: Path, *, progress: bool):
    """The spec and (when it has meshes) the cad relations of ``assembly``."""
    from asp.feasibility import load_relations
    from asp.spec import load_spec

    spec = load_spec(assembly)
    if spec.generated:
        _progress(
            f"no assembly.yaml: generated a spec from {assembly} ({len(spec.parts)} parts, one "
            "placement each, agents H and R1, durations from part size); "
            f"`asmplan init {assembly} -o assembly.yaml` writes it for editing"
        )
    relations = None
    if spec.has_geometry:
        if progress:
            _progress(f"computing part relations of {len(spec.parts)} parts ...")
        relations = load_relations(spec, progress=progress)
    return spec, relations


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
        0, "--list", min=0, help="Also list up to N feasible complete sequences (the AST)."
    ),
) -> None:
    """Build the assembly state graph and the game DAG; print the sizes, write the DAG."""
    from asp.game import game_dag
    from asp.io import save_dag
    from asp.state_graph import build_state_graph

    t0 = time.perf_counter()
    spec, relations = _load(assembly, progress=progress)
    graph = build_state_graph(spec, relations, progress=progress)
    sequences = graph.count_sequences()
    dag = game_dag(graph, cost=None if cost is None else cost.value)
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
        typer.echo(json.dumps(result))
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


def _baseline_result(source: Path, *, time_limit: float, workers: int, seed: int):
    """Dispatch by input: PSPLIB ``.sm``, a game DAG file, or an assembly."""
    from asp.baseline import assembly_schedule, min_cost_path, min_makespan

    suffix = source.suffix.lower()
    if suffix == ".sm":
        from asp.psplib import read_sm

        return min_makespan(read_sm(source), time_limit=time_limit, workers=workers, seed=seed)
    if suffix in (".json", ".graphml", ".xml"):
        from asp.io import load_dag

        dag = load_dag(source)
        return min_cost_path(dag, time_limit=time_limit, workers=workers, seed=seed)
    from asp.state_graph import build_state_graph

    spec, relations = _load(source, progress=False)
    graph = build_state_graph(spec, relations)
    sched = assembly_schedule(spec, graph)
    result = min_makespan(sched.problem, time_limit=time_limit, workers=workers, seed=seed)
    result.detail.update(
        lower_bound=sched.lower_bound, chain_bound=sched.chain_bound, load_bound=sched.load_bound
    )
    return result


@app.command("baseline")
def baseline_command(
    source: Path = typer.Argument(
        ..., help="PSPLIB .sm, game DAG (.json/.graphml), or assembly (folder, yaml, .IN2)."
    ),
    fmt: OutputFormat = typer.Option(OutputFormat.text, "--format", help="Output format."),
    time_limit: float = typer.Option(60.0, "--time-limit", help="CP-SAT time limit, seconds."),
    workers: int = typer.Option(1, "--workers", help="CP-SAT workers (1: repeatable)."),
    seed: int = typer.Option(0, "--seed", help="CP-SAT random seed."),
) -> None:
    """CP-SAT baseline: minimum makespan (.sm, assembly) or minimum-cost path (game DAG)."""
    if not source.exists():
        raise FileNotFoundError(f"{source}: no such file or folder")
    result = _baseline_result(source, time_limit=time_limit, workers=workers, seed=seed)
    data = result.to_dict()
    if fmt is OutputFormat.json:
        typer.echo(json.dumps(data))
        return
    what = "minimum-cost path" if result.kind == "path" else "minimum makespan"
    typer.echo(f"{result.name}: CP-SAT {what}")
    typer.echo(f"  status     {result.status}")
    typer.echo(f"  objective  {data['objective']}")
    typer.echo(f"  bound      {data['bound']}")
    if "lower_bound" in data:
        typer.echo(f"  state-graph lower bound  {data['lower_bound']:g}")
    typer.echo(f"  wall       {data['wall_s']} s")
    if result.kind == "path" and "operations" in data:
        typer.echo("  path: " + " -> ".join(data["operations"]))
    if result.kind == "schedule" and "schedule" in data and len(data["schedule"]) <= 60:
        for row in data["schedule"]:
            agent = f" {row['agent']}" if row["agent"] else ""
            typer.echo(f"    {row['task']:>6s}{agent:4s} {row['start']:>7} .. {row['end']}")
    if result.credit:
        typer.echo(result.credit)


@app.command("plan")
def plan_command(
    assembly: Path = typer.Argument(
        ...,
        help="Folder with assembly.yaml, the YAML, a .IN2, or a CAD file (STEP, glTF/GLB, 3MF, "
        "3DXML) or folder of part meshes (a spec is generated).",
    ),
    output: Path | None = typer.Option(
        None, "--output", "-o", help="Folder for plan.json, dag.png."
    ),
    cost: CostModel | None = typer.Option(None, "--cost", help="Cost model (default: spec's)."),
    time_limit: float = typer.Option(30.0, "--time-limit", help="CP-SAT time limit, seconds."),
    seed: int = typer.Option(0, "--seed", help="CP-SAT random seed."),
) -> None:
    """Plan an assembly end to end: relations, state graph, game, robust plan, CP-SAT."""
    from asp.atomic import write_text
    from asp.baseline import assembly_schedule, min_makespan
    from asp.game import game_dag
    from asp.plan import plan_text, relations_summary, relations_text, robust_plan
    from asp.solve import solve
    from asp.state_graph import build_state_graph

    t0 = time.perf_counter()
    _progress("[1/5] reading the assembly and computing part relations ...")
    spec, relations = _load(assembly, progress=True)
    typer.echo(
        f"{spec.name}: {len(spec.parts)} parts, {len(spec.operations)} operations, "
        f"agents {', '.join(f'{a.name} ({a.side})' for a in spec.agents)}"
    )
    summary = relations_summary(relations) if relations is not None else []
    if summary:
        typer.echo("part relations (contacts with directions; free directions in the assembly):")
        typer.echo(relations_text(summary))

    _progress("[2/5] building the assembly state graph ...")
    graph = build_state_graph(spec, relations)
    sequences = graph.count_sequences()
    typer.echo(
        f"state graph: {graph.n_states:,} states, {graph.n_transitions:,} transitions, "
        f"{sequences:,} feasible sequences"
    )

    _progress("[3/5] solving the robot-vs-human game ...")
    dag = game_dag(graph, cost=None if cost is None else cost.value)
    solution = solve(dag)
    descriptions = {op.id: op.description for op in spec.operations}
    steps = robust_plan(dag, solution, descriptions)
    unit = "" if dag.cost_model == "steps" else " s"
    typer.echo(f"game DAG ({dag.cost_model}): {dag.n_nodes} nodes, {dag.n_edges} edges")
    typer.echo(f"TCT (cooperative) {solution.tct:g}{unit}, W* (robust) {solution.minimax:g}{unit}")
    typer.echo("robust plan (robust robot vs a delaying human):")
    typer.echo(plan_text(steps))

    _progress("[4/5] CP-SAT minimum-makespan schedule ...")
    sched = assembly_schedule(spec, graph)
    result = min_makespan(sched.problem, time_limit=time_limit, workers=1, seed=seed)
    typer.echo(
        f"CP-SAT makespan (agents in parallel): {result.objective} s ({result.status}); "
        f"state-graph lower bound {sched.lower_bound:g} s"
    )

    plan = {
        "format": "asmplan-plan/1",
        "assembly": spec.name,
        "source": spec.source,
        "relations": summary,
        "states": graph.n_states,
        "transitions": graph.n_transitions,
        "sequences": sequences,
        "game_nodes": dag.n_nodes,
        "game_edges": dag.n_edges,
        "cost": dag.cost_model,
        "tct": solution.tct,
        "minimax": solution.minimax,
        "robust_plan": [s.to_dict() for s in steps],
        "schedule": {
            **result.to_dict(),
            "lower_bound": sched.lower_bound,
            "chain_bound": sched.chain_bound,
            "load_bound": sched.load_bound,
        },
    }
    if spec.credit:
        plan["credit"] = spec.credit
    if output is not None:
        _progress("[5/5] writing plan.json and dag.png ...")
        from asp.plot import MAX_PLOT_NODES, plot_dag
        from asp.solve import play

        write_text(output / "plan.json", json.dumps(plan, indent=1) + "\n")
        written = [output / "plan.json"]
        if dag.n_nodes <= MAX_PLOT_NODES:
            path, _ = play(dag, solution.robot_policy, solution.human_policy)
            edges = _path_edges(dag, path)
            plot_dag(
                dag,
                output / "dag.png",
                highlight=edges,
                title=f"{spec.name}: game DAG ({dag.cost_model}), robust plan in red, "
                f"TCT {solution.tct:g}, W* {solution.minimax:g}",
            )
            written.append(output / "dag.png")
        else:
            _progress(f"  dag.png skipped: {dag.n_nodes} nodes > {MAX_PLOT_NODES}")
        typer.echo("wrote " + " and ".join(str(p) for p in written))
    _progress(f"done in {time.perf_counter() - t0:.1f} s")


def _path_edges(dag, path: list[int]) -> list[int]:
    """Edge indices along a node path (a pass repeats no node, so consecutive nodes differ)."""
    edges = []
    for u, v in zip(path, path[1:], strict=False):
        hits = [e for e in dag.out_edges(u) if dag.targets[e] == v]
        edges.append(hits[0])
    return edges
