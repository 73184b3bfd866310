"""A 70-part assembly planned end to end with default settings: time per stage, peak memory.

The assembly (built here, :func:`drive`) has the structure that makes a cycloidal drive
hard: groups of parts that can be built in any interleaving (24 ring pins each carrying a
sleeve, under a ring plate; three posts through bearings, a disc and a cap; nine washers on
bosses), so the states multiply (about 700,000 after the symmetry reduction). Pins and
holes are drawn at the same diameter with different segment counts, as CAD exports do.
Target: under 60 s and under 2 GB on the 2-core machine.

With a path (a CAD file, a folder of meshes or an ``assembly.yaml``), that assembly instead,
e.g. trimesh's public ``models/cycloidal.3DXML`` (72 parts; not in the repository: skipped
when the file is absent). The stages are those of ``asmplan plan``: relations (reading the
file, the geometry, the generated spec), the state graph (with the symmetry reduction of
:mod:`asp.symmetry`), counting sequences, the game DAG, the exact solve, the CP-SAT schedule,
and writing plan.json, dag.png and report.html; the plan's principal line goes through the
independent checker.

Run: ``.venv/bin/python benchmarks/plan_70_parts.py [PATH]``
"""

from __future__ import annotations

import resource
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a checkout

import numpy as np  # noqa: E402

from tests.cad.real_shapes import annulus, box, cylinder, difference, union  # noqa: E402

SIDE, R = 100.0, 1.5
RING_PINS, POSTS, WASHERS = 24, 3, 9


def on_circle(n: int, radius: float, centre: tuple[float, float]) -> list[tuple[float, float]]:
    """``n`` points evenly on a circle."""
    angles = 2 * np.pi * np.arange(n) / n
    return [(centre[0] + radius * np.cos(a), centre[1] + radius * np.sin(a)) for a in angles]


def drive() -> dict:
    """70 parts (mm, z up) in three groups that can be built in any interleaving, as in a
    cycloidal drive: 24 shouldered ring pins in blind holes of the base, each carrying a
    sleeve that rests on its shoulder (pin before sleeve), under a ring plate resting on
    the pin tops; three posts through a lower bearing, a disc, an upper bearing and a cap
    (the posts may go in first or last, through the aligned holes); nine washers on bosses
    of the base."""
    ring = on_circle(RING_PINS, 45.0, (50.0, 0.0))
    posts = [(-70.0, -20.0), (-50.0, 20.0), (-30.0, -20.0)]
    bosses = [(-80.0 + 20.0 * k, -80.0) for k in range(WASHERS)]
    parts = {}
    base = union(
        box((-SIDE, -SIDE, 0), (SIDE, SIDE, 10)),
        *(cylinder(3.0, 9.9, 15.0, 20, xy) for xy in bosses),
    )
    parts["base"] = difference(
        base,
        *(cylinder(R, 5, 11, 20, xy) for xy in ring),
        *(cylinder(4.0, 5, 11, 28, xy) for xy in posts),
    )
    for k, xy in enumerate(ring):
        parts[f"ring_pin_{k + 1}"] = union(
            cylinder(R, 5, 30, 24, xy), cylinder(3.0, 10, 12, 24, xy)
        )
        parts[f"sleeve_{k + 1}"] = annulus(R, 3.0, 12, 28, 16, 24, xy)
    parts["ring_plate"] = cylinder(52.0, 30, 36, 64, (50.0, 0.0))
    disc = box((-90, -40, 16), (-10, 40, 22))
    cap = box((-90, -40, 28), (-10, 40, 34))
    parts["disc"] = difference(disc, *(cylinder(4.0, 15, 23, 32, xy) for xy in posts))
    parts["cap"] = difference(cap, *(cylinder(4.0, 27, 35, 32, xy) for xy in posts))
    for k, xy in enumerate(posts):
        parts[f"post_{k + 1}"] = cylinder(4.0, 5, 50, 24, xy)
        parts[f"lower_bearing_{k + 1}"] = annulus(4.0, 8.0, 10, 16, 20, 32, xy)
        parts[f"upper_bearing_{k + 1}"] = annulus(4.0, 8.0, 22, 28, 20, 32, xy)
    for k, xy in enumerate(bosses):
        parts[f"washer_{k + 1}"] = annulus(3.0, 6.0, 10, 12, 16, 24, xy)
    return parts


def stages(source) -> None:
    """Plan ``source`` (a path, or an ``Assembly`` already loaded) stage by stage, printing
    seconds and the peak memory after each stage."""
    from asmplan import pipeline
    from asp.checker import check_line, plan_operations
    from asp.plan import relations_summary

    times: list[tuple[str, float, float]] = []
    clock = [time.perf_counter()]

    def lap(name: str) -> None:
        now = time.perf_counter()
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        times.append((name, now - clock[0], peak))
        clock[0] = now

    t0 = clock[0]
    assembly = source if isinstance(source, pipeline.Assembly) else pipeline.load(source)
    lap("relations (load + cad)")
    graph = pipeline.state_graph(assembly)
    lap("state graph")
    sequences = graph.count_sequences()
    lap("count sequences")
    plan = pipeline.Assembly(graph.spec, assembly.relations)
    game = pipeline.Game(pipeline.game(graph), plan.descriptions)
    lap("game DAG")
    solution = pipeline.solve_game(game.dag)
    steps = pipeline.robust_plan(game, solution)
    lap("solve + robust plan")
    line = [step.operation for step in steps if step.operation]
    sched = pipeline.schedule(plan, graph, seed=0, sequence=line)  # asmplan plan's default
    lap("CP-SAT (default budget)")
    summary = relations_summary(assembly.relations) if assembly.relations is not None else []
    result = pipeline.AssemblyPlan(
        plan, graph, sequences, game, solution, steps, summary, sched, None
    )
    with tempfile.TemporaryDirectory() as out:
        pipeline.write_plan(result, out)
        lap("outputs (plan.json, dag.png, report.html)")
    check_line(graph.spec, assembly.relations, plan_operations(result.to_dict()))
    lap("checker")
    spec = graph.spec
    alive = int(graph.coreachable().sum())
    print(
        f"{len(spec.part_ids)} parts, {len(spec.operations)} operations, "
        f"{len(spec.subassemblies)} subassemblies, base {spec.base_part}, "
        f"{sum(op.held for op in spec.operations)} held; {graph.n_states:,} states "
        f"({alive:,} can complete), {graph.n_transitions:,} transitions, game "
        f"{game.dag.n_nodes:,} nodes, {sequences:.3g} sequences"
    )
    print(
        f"TCT {solution.tct:g}, W* {solution.minimax:g}, CP-SAT {sched.result.objective} "
        f"({sched.result.status}); checker ok"
    )
    for name, dt, peak in times:
        print(f"  {name:42s} {dt:7.2f} s   peak {peak:7,.0f} MB")
    peak = times[-1][2]
    print(
        f"  {'end to end':42s} {time.perf_counter() - t0:7.2f} s (target < 60 s); peak memory "
        f"{peak:,.0f} MB (target < 2048 MB)"
    )


def main(argv: list[str]) -> None:
    if argv:
        path = Path(argv[0])
        if not path.exists():
            print(f"{path}: not found, skipped (a public file, not in the repository)")
            return
        stages(path)
        return
    meshes = drive()
    with tempfile.TemporaryDirectory() as tmp:
        for pid, mesh in meshes.items():
            mesh.export(Path(tmp) / f"{pid}.stl")
        stages(tmp)


if __name__ == "__main__":
    main(sys.argv[1:])
