"""A 70-part assembly planned end to end with default settings: time per stage, peak memory.

The assembly (built here, a cycloidal-drive-like stack): a base plate, a housing frame on it,
18 ring pins standing in the base, a disc on the pins, 12 output pins in the disc, a flange on
them, 16 screws in the flange, a cover on the frame and 19 knobs in the cover. Every pin and
hole is drawn at the same diameter with different segment counts, as CAD exports do. Target:
under 60 s and under 2 GB on the 2-core machine.

Run: ``.venv/bin/python benchmarks/plan_70_parts.py``
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


def main() -> None:
    from asmplan import pipeline
    from asp.checker import check_line, plan_operations

    meshes = drive()
    with tempfile.TemporaryDirectory() as tmp:
        for pid, mesh in meshes.items():
            mesh.export(Path(tmp) / f"{pid}.stl")
        t0 = time.perf_counter()
        assembly = pipeline.load(tmp)
        t1 = time.perf_counter()
        graph = pipeline.state_graph(assembly)
        t2 = time.perf_counter()
        game = pipeline.game(graph)
        t3 = time.perf_counter()
        solution = pipeline.solve_game(game)
        t4 = time.perf_counter()
        plan = pipeline.Assembly(graph.spec, assembly.relations)
        sched = pipeline.schedule(plan, graph, time_limit=30, seed=0)
        t5 = time.perf_counter()
        result = pipeline.plan(plan, time_limit=30)
        check_line(graph.spec, assembly.relations, plan_operations(result.to_dict()))
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(
        f"{len(meshes)} parts, {len(graph.spec.operations)} operations, "
        f"{len(graph.spec.subassemblies)} subassemblies, {graph.n_states:,} states, "
        f"{graph.n_transitions:,} transitions, game {game.n_nodes:,} nodes"
    )
    print(
        f"TCT {solution.tct:g}, W* {solution.minimax:g}, CP-SAT {sched.result.objective} "
        f"({sched.result.status}); checker ok"
    )
    for name, dt in (
        ("relations (load + cad)", t1 - t0),
        ("state graph", t2 - t1),
        ("game DAG", t3 - t2),
        ("solve", t4 - t3),
        ("CP-SAT", t5 - t4),
    ):
        print(f"  {name:24s} {dt:7.2f} s")
    print(
        f"  {'end to end':24s} {t5 - t0:7.2f} s (target < 60 s); peak memory {peak:,.0f} MB "
        f"(target < 2048 MB)"
    )


if __name__ == "__main__":
    main()
