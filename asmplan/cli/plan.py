"""``asmplan plan``: plan an assembly end to end (:func:`asmplan.pipeline.plan`).

The pipeline computes; this module prints the summary for a person and writes the outputs
(:func:`asmplan.pipeline.write_plan`: ``plan.json``, ``report.html``, the figures of the
plan's game and ``manifest.json``, one unit). Progress goes to stderr, each step numbered
once and in order: ``[1/5]`` relations, ``[2/5]`` state graph, ``[3/5]`` and ``[4/5]`` the
alternating game then CP-SAT (turn model ``alternate``) or CP-SAT then the concurrent game
(``concurrent``, which builds no alternating game), ``[5/5]`` the files.
"""

from __future__ import annotations

import time
from pathlib import Path

import typer

from asmplan.cli.app import app
from asmplan.cli.graph import say
from asmplan.cli.options import (
    CostModel,
    TurnModel,
    check_output,
    finite_or_none,
    gravity_option,
    max_memory_option,
    max_states_option,
    seed_option,
    time_limit_option,
    tolerance_option,
    turn_model_option,
    units_option,
)
from asmplan.pipeline import SEARCH_SECONDS
from asp.atomic import check_output_folder
from asp.schedule.assembly_makespan import AUTO_PATIENCE, AUTO_TIME_LIMIT

AUTO_TIME_LIMIT_HELP = (
    "Search seconds for CP-SAT's minimum-makespan search: its deterministic time, about a "
    "second of one core's search each, so the same plan at any load (the wall clock stops it "
    "only as a safety net, at 3x + 30 s). "
    f"Default: automatic, {AUTO_TIME_LIMIT:g} s, stopping once neither a better schedule nor a "
    f"new cut has come for {AUTO_PATIENCE:g} s, or when proven optimal; give a number to let "
    "CP-SAT search that long."
)


def plan_summary(result) -> list[str]:
    """The lines ``asmplan plan`` prints for an :class:`~asmplan.pipeline.AssemblyPlan`."""
    from asmplan.report.plan import plan_text, relations_summary_text
    from asp.numbers import cost_unit

    spec, graph = result.assembly.spec, result.graph
    lines = [
        f"{spec.name}: {len(spec.parts)} parts, {len(spec.operations)} operations, "
        f"agents {', '.join(f'{a.name} ({a.side})' for a in spec.agents)}"
    ]
    if result.relations_summary:
        if spec.frame is not None:
            from cad.frame import frame_text

            lines.append(f"build frame: {frame_text(spec.frame)} (directions below are its axes)")
        lines.append("part relations (contacts with directions; free directions in the assembly):")
        lines.append(relations_summary_text(result.relations_summary))
    lines += units_text(result.units, graph.spec)
    lines.append(
        f"state graph: {graph.n_states:,} states, {graph.n_transitions:,} transitions, "
        f"{result.sequences:,} feasible sequences"
    )
    if result.concurrent is not None:
        from asp.concurrent.plan import robustness_table, timeline_text

        plan = result.concurrent
        lines.append("concurrent game (the person and the robots working at once), makespan:")
        lines.append(robustness_table(plan))
        lines.append(f"robust plan (k = {plan.curve.k}), the person following it:")
        lines.append(timeline_text(*plan.cooperative))
        lines.append(f"worst line: the robust plan (k = {plan.curve.k}) against the worst person:")
        lines.append(timeline_text(*plan.worst))
        return lines
    game = result.played_game.policy  # the game's sizes and values (the game may be gone)
    unit = cost_unit(game.cost_model)
    doc = result.to_dict()
    lines += [
        f"game DAG ({game.cost_model}): {game.n_nodes} nodes, {game.n_edges} edges",
        f"TCT (cooperative) {game.tct:g}{unit}, W* (robust) {game.minimax:g}{unit}",
        f"robust plan (the person following it; {doc['metrics']['w0']:g}{unit}):",
        plan_text(doc["robust_plan"]),
        f"worst line (the robust plan against a delaying person; {game.minimax:g}{unit}):",
        plan_text(doc["worst_line"]),
    ]
    sched = result.schedule
    note = sched.result.detail.get("status_note", "")
    if sched.result.objective is None:
        found = f"none ({sched.result.status}: {note}; --time-limit raises it)"
    elif sched.result.status == "OPTIMAL":
        found = f"{sched.result.objective:g} s ({sched.result.status}: {note})"
    else:
        found = (
            f"{sched.result.objective:g} s ({sched.result.status}: {note}; --time-limit gives "
            "CP-SAT more time)"
        )
    lines.append(
        f"CP-SAT makespan (agents in parallel): {found}; "
        f"state-graph lower bound {sched.lower_bound:g} s"
    )
    return lines


def units_text(units: list[dict], spec=None) -> list[str]:
    """The subassemblies of a plan (``plan.json``'s ``units``): used ones with their parts
    and where they come from (and, for one built upside down, its workspace's gravity:
    ``spec.unit_gravity``), the CAD file's unused ones with the reason."""
    if not units:
        return []
    source = {"spec": "the spec", "cad": "the CAD file", "automatic": "found automatically"}
    turned = dict(spec.unit_gravity) if spec is not None else {}
    lines = ["subassemblies (each built on its own, then inserted as one unit):"]
    for u in units:
        head = f"  {u['id']} [{', '.join(u['parts'])}] from {source[u['source']]}"
        if u["used"] and u["id"] in turned:
            head += (
                f"; built upside down (gravity {turned[u['id']]} in its workspace), then turned "
                f"over and inserted"
            )
        lines.append(head + ("" if u["used"] else f": not used, {u['reason']}"))
    return lines


@app.command("plan")
def plan_command(
    assembly: Path = typer.Argument(
        ...,
        help="Folder with assembly.yaml, the YAML, a .IN2, or a CAD file (STEP, glTF/GLB, 3MF, "
        "3DXML) or folder of part meshes (a spec is generated; `asmplan init` writes it).",
    ),
    output: Path | None = typer.Option(
        None,
        "--output",
        "-o",
        help="Folder for plan.json, report.html, the figures (and manifest.json).",
    ),
    cost: CostModel | None = typer.Option(None, "--cost", help="Cost model (default: spec's)."),
    time_limit: float | None = time_limit_option(None, AUTO_TIME_LIMIT_HELP),
    seed: int = seed_option("CP-SAT random seed."),
    turn_model: TurnModel | None = turn_model_option(
        "alternate (the paper's turns) or concurrent (default: spec's)."
    ),
    max_k: int | None = typer.Option(
        None,
        "--max-k",
        min=0,
        max=1000,
        help="Concurrent: largest deviation budget k tried (default: DEFAULT_MAX_K of "
        "asp.concurrent); the curve stops earlier once flat.",
    ),
    duration_step: float = typer.Option(
        1.0,
        "--duration-step",
        min=0.0,
        help="Concurrent: grid of a person's duration range (0: its two end points).",
        callback=finite_or_none,
    ),
    max_states: int | None = max_states_option(),
    contact_tol: float | None = tolerance_option("contact_tol"),
    penetration_tol: float | None = tolerance_option("penetration_tol"),
    force: bool = typer.Option(
        False,
        "--force",
        help="Write into an --output folder that holds files asmplan did not write (they are "
        "kept; without it such a folder is refused).",
    ),
    units: str | None = units_option(),
    gravity: str | None = gravity_option(),
    search_time_limit: float = typer.Option(
        SEARCH_SECONDS,
        "--search-time-limit",
        min=0.0,
        help="Concurrent: search seconds for W*(k), counted in positions expanded (about a "
        "second of one core's search each: asp.concurrent.search.POSITIONS_PER_SECOND), so "
        "the same plan at any load; the wall clock stops it only as a safety net, at 3x + "
        "30 s, said on stderr and in timings.json (0: no limit). Past it, W*(k) is a "
        "certified interval [L, U] and the plan's policy the one certified at U.",
    ),
    max_nodes: int | None = typer.Option(
        None,
        "--max-nodes",
        min=1,
        help="Concurrent: positions the search may expand (default 50,000,000).",
    ),
    max_memory: float | None = max_memory_option(
        "Concurrent: GB for the search's table and its policy games (default 1)."
    ),
) -> None:
    """Plan an assembly end to end: relations, state graph, game, robust plan, CP-SAT
    (concurrent: CP-SAT, then the concurrent game)."""
    from asmplan import pipeline

    t0 = time.perf_counter()
    check_output(output, folder=True)
    if output is not None:
        check_output_folder(output, force=force)
    result = pipeline.plan(
        assembly,
        cost=None if cost is None else cost.value,
        time_limit=time_limit,
        seed=seed,
        turn_model=None if turn_model is None else turn_model.value,
        max_k=max_k,
        duration_step=duration_step or None,
        on_step=say,
        max_states=max_states,
        contact_tol=contact_tol,
        penetration_tol=penetration_tol,
        units=units,
        gravity=gravity,
        keep_game=False,  # let the game go once solved: less memory for CP-SAT and the files
        search_time_limit=search_time_limit or None,
        max_nodes=max_nodes,
        max_memory=max_memory,
    )
    wall = None if result.concurrent is None else result.concurrent.curve.wall_stop
    if wall is not None:
        say(
            f"the concurrent search was stopped by the wall clock's safety net at {wall:g} s, "
            f"before its {search_time_limit:g} search seconds (a loaded machine): this plan "
            "depends on the load (timings.json: concurrent.wall_stop)"
        )
    for line in plan_summary(result):
        typer.echo(line)
    if output is not None:
        say("[5/5] writing plan.json and the figures ...")
        written = pipeline.write_plan(result, output, on_step=say, force=force)
        typer.echo("wrote " + " and ".join(str(p) for p in written))
    say(f"done in {time.perf_counter() - t0:.1f} s")
