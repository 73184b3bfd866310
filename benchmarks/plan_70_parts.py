"""A 70-part assembly planned end to end with default settings: time per stage, peak memory.

The assembly (built here, a cycloidal-drive-like stack): a base plate, a housing frame on it,
18 ring pins standing in the base, a disc on the pins, 12 output pins in the disc, a flange on
them, 16 screws in the flange, a cover on the frame and 19 knobs in the cover. Every pin and
hole is drawn at the same diameter with different segment counts, as CAD exports do. Target:
under 60 s and under 2 GB on the 2-core machine.

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

from tests.cad.real_shapes import box, cylinder, difference  # noqa: E402

SIDE, WALL, R = 100.0, 6.0, 1.5


def spots(n: int, quadrant: tuple[int, int]) -> list[tuple[float, float]]:
    """``n`` points in one quadrant, 4 mm apart with distinct x and distinct y: no two of a
    kind in a row or column, and the kinds' columns apart (nothing above another's head)."""
    sx, sy = quadrant
    return [(sx * (10 + 4.0 * k), sy * (10 + 4.0 * ((7 * k) % n))) for k in range(n)]


def drive() -> dict:
    ring, output = spots(18, (1, 1)), spots(12, (-1, 1))
    screws, knobs = spots(16, (-1, -1)), spots(19, (1, -1))
    parts = {}
    parts["base"] = difference(
        box((-SIDE, -SIDE, 0), (SIDE, SIDE, 10)),
        *(cylinder(R, 5, 11, 24, xy) for xy in ring),
    )
    parts["housing"] = difference(
        box((-SIDE, -SIDE, 10), (SIDE, SIDE, 60)),
        box((-SIDE + WALL, -SIDE + WALL, 9), (SIDE - WALL, SIDE - WALL, 61)),
    )
    for k, xy in enumerate(ring):
        parts[f"ring_pin_{k + 1}"] = cylinder(R, 5, 30, 24, xy)
    parts["disc"] = difference(
        box((-90, -90, 30), (90, 90, 36)), *(cylinder(R, 33, 37, 24, xy) for xy in output)
    )
    for k, xy in enumerate(output):
        parts[f"output_pin_{k + 1}"] = cylinder(R, 33, 50, 24, xy)
    parts["flange"] = difference(
        box((-90, -90, 50), (90, 90, 56)), *(cylinder(R, 52, 57, 24, xy) for xy in screws)
    )
    for k, xy in enumerate(screws):
        parts[f"screw_{k + 1}"] = cylinder(R, 52, 59, 24, xy)
    parts["cover"] = difference(
        box((-SIDE, -SIDE, 60), (SIDE, SIDE, 66)), *(cylinder(R, 63, 67, 24, xy) for xy in knobs)
    )
    for k, xy in enumerate(knobs):
        parts[f"knob_{k + 1}"] = cylinder(R, 63, 72, 24, xy)
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
    sched = pipeline.schedule(plan, graph, time_limit=30, seed=0)
    lap("CP-SAT (limit 30 s)")
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
