"""``asmplan plan``: plan an assembly end to end (:func:`asmplan.pipeline.plan`).

The pipeline computes; this module prints the summary for a person and writes the outputs
(:func:`asmplan.pipeline.write_plan`: ``plan.json``, ``dag.png`` and ``manifest.json``, one
unit).
"""

from __future__ import annotations

import time
from pathlib import Path

import typer

from asmplan.cli.app import app
from asmplan.cli.graph import say
from asmplan.cli.options import SEED_MAX, TIME_LIMIT_MAX, CostModel, check_output


def plan_summary(result) -> list[str]:
    """The lines ``asmplan plan`` prints for an :class:`~asmplan.pipeline.AssemblyPlan`."""
    from asp.numbers import cost_unit
    from asp.plan import plan_text, relations_text

    spec, graph, dag, solution = result.assembly.spec, result.graph, result.dag, result.solution
    lines = [
        f"{spec.name}: {len(spec.parts)} parts, {len(spec.operations)} operations, "
        f"agents {', '.join(f'{a.name} ({a.side})' for a in spec.agents)}"
    ]
    if result.relations_summary:
        lines.append("part relations (contacts with directions; free directions in the assembly):")
        lines.append(relations_text(result.relations_summary))
    lines.append(
        f"state graph: {graph.n_states:,} states, {graph.n_transitions:,} transitions, "
        f"{result.sequences:,} feasible sequences"
    )
    unit = cost_unit(dag.cost_model)
    lines += [
        f"game DAG ({dag.cost_model}): {dag.n_nodes} nodes, {dag.n_edges} edges",
        f"TCT (cooperative) {solution.tct:g}{unit}, W* (robust) {solution.minimax:g}{unit}",
        "robust plan (robust robot vs a delaying human):",
        plan_text(list(result.steps)),
    ]
    sched = result.schedule
    lines.append(
        f"CP-SAT makespan (agents in parallel): {sched.result.objective} s "
        f"({sched.result.status}); state-graph lower bound {sched.lower_bound:g} s"
    )
    return lines


@app.command("plan")
def plan_command(
    assembly: Path = typer.Argument(
        ...,
        help="Folder with assembly.yaml, the YAML, a .IN2, or a CAD file (STEP, glTF/GLB, 3MF, "
        "3DXML) or folder of part meshes (a spec is generated; `asmplan init` writes it).",
    ),
    output: Path | None = typer.Option(
        None, "--output", "-o", help="Folder for plan.json, dag.png (and manifest.json)."
    ),
    cost: CostModel | None = typer.Option(None, "--cost", help="Cost model (default: spec's)."),
    time_limit: float = typer.Option(
        30.0, "--time-limit", min=0.001, max=TIME_LIMIT_MAX, help="CP-SAT time limit, seconds."
    ),
    seed: int = typer.Option(0, "--seed", min=0, max=SEED_MAX, help="CP-SAT random seed."),
    max_states: int | None = typer.Option(
        None, "--max-states", min=1, help="State graph limit (default: spec's, else 20,000,000)."
    ),
) -> None:
    """Plan an assembly end to end: relations, state graph, game, robust plan, CP-SAT."""
    from asmplan import pipeline

    t0 = time.perf_counter()
    check_output(output, folder=True)
    result = pipeline.plan(
        assembly,
        cost=None if cost is None else cost.value,
        time_limit=time_limit,
        seed=seed,
        on_step=say,
        max_states=max_states,
    )
    for line in plan_summary(result):
        typer.echo(line)
    if output is not None:
        say("[5/5] writing plan.json and dag.png ...")
        written = pipeline.write_plan(result, output, on_step=say)
        typer.echo("wrote " + " and ".join(str(p) for p in written))
    say(f"done in {time.perf_counter() - t0:.1f} s")
