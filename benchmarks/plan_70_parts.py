"""A 70-part assembly planned end to end with default settings: time per stage, peak memory.

The assembly (built here, :func:`drive`) has the structure that makes a cycloidal drive
hard: groups of parts that can be built in any interleaving (24 ring pins each carrying a
sleeve, under a ring plate; three posts through bearings, a disc and a cap; nine washers on
bosses), so the states multiply (about 700,000 after the symmetry reduction). Pins and
holes are drawn at the same diameter with different segment counts, as CAD exports do.
Target: under 60 s and under 2 GB on the 2-core machine.

With a path (a CAD file, a folder of meshes or an ``assembly.yaml``), that assembly instead,
e.g. trimesh's public ``models/cycloidal.3DXML`` (72 parts; not in the repository: skipped
when the file is absent). The plan is made by ``pipeline.plan(keep_game=False)`` and
``pipeline.write_plan``, the calls of ``asmplan plan``, with each of their steps timed
(:data:`STAGES`: relations, state graph, game DAG, solve, robust plan, what the outputs take
from the game before it is let go, CP-SAT, the plan document and files): wall and CPU
seconds, resident memory at the step's end and the highest during it. The plan's principal
line goes through the independent checker.

Run: ``.venv/bin/python benchmarks/plan_70_parts.py [PATH]``
"""

from __future__ import annotations

import resource
import sys
import tempfile
import threading
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


STAGES = (
    ("load", "relations (file, geometry, generated spec)"),
    ("state_graph", "state graph (+ units, counting sequences)"),
    ("game", "game DAG"),
    ("solve_game", "exact solve"),
    ("robust_plan", "robust plan"),
    ("played_game", "policy, lines, figure taken from the game"),
    ("schedule", "CP-SAT schedule (automatic budget)"),
    ("write_plan", "plan document, plan.json, dag.png, report"),
)
"""The steps of :func:`asmplan.pipeline.plan` and ``write_plan`` timed, as ``asmplan plan``
calls them."""
BETWEEN = "between the steps (imports, units, count, free)"


class Meter:
    """Wall and CPU seconds and resident memory per stage: the memory at the stage's end and
    the highest during it (sampled every 5 ms from ``/proc/self/statm``; elsewhere only the
    process's peak so far)."""

    def __init__(self) -> None:
        self.rows: list[tuple[str, float, float, float, float]] = []
        self.peak = self.rss()
        self.wall, self.cpu = time.perf_counter(), time.process_time()
        threading.Thread(target=self._sample, daemon=True).start()

    @staticmethod
    def rss() -> float:
        """Resident memory now (MB); the process's peak where /proc is missing."""
        try:
            with open("/proc/self/statm") as f:
                return int(f.read().split()[1]) * resource.getpagesize() / 2**20
        except OSError:
            return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024

    def _sample(self) -> None:
        while True:
            self.peak = max(self.peak, self.rss())
            time.sleep(0.005)

    def lap(self, name: str) -> None:
        wall, cpu, now = time.perf_counter(), time.process_time(), self.rss()
        self.rows.append((name, wall - self.wall, cpu - self.cpu, now, max(self.peak, now)))
        self.peak, self.wall, self.cpu = now, time.perf_counter(), time.process_time()


def stages(source) -> None:
    """Plan ``source`` (a path, or an ``Assembly`` already loaded) as ``asmplan plan`` does,
    printing the seconds and memory of each step of :data:`STAGES`."""
    from asmplan import pipeline
    from asp.graph.checker import check_line, plan_operations

    meter = Meter()
    t0, names = time.perf_counter(), dict(STAGES)

    def timed(name: str):
        step = getattr(pipeline, name)

        def run(*args, **kwargs):
            meter.lap(BETWEEN)
            out = step(*args, **kwargs)
            meter.lap(names[name])
            return out

        return run

    saved = {name: getattr(pipeline, name) for name in names}
    for name in names:
        setattr(pipeline, name, timed(name))
    try:
        result = pipeline.plan(source, keep_game=False)  # asmplan plan's call
        with tempfile.TemporaryDirectory() as out:
            pipeline.write_plan(result, out)
    finally:
        for name, step in saved.items():
            setattr(pipeline, name, step)
    doc = result.to_dict()
    check_line(result.graph.spec, result.assembly.relations, plan_operations(doc))
    graph, spec = result.graph, result.graph.spec
    print(
        f"{len(spec.part_ids)} parts, {len(spec.operations)} operations, "
        f"{len(spec.subassemblies)} subassemblies, base {spec.base_part}, "
        f"{sum(op.held for op in spec.operations)} held; {graph.n_states:,} states, "
        f"{graph.n_transitions:,} transitions, game {doc['game_nodes']:,} nodes and "
        f"{doc['game_edges']:,} edges, {result.sequences:.3g} sequences"
    )
    print(
        f"TCT {doc['tct']:g}, W* {doc['minimax']:g}, CP-SAT {doc['schedule']['objective']} "
        f"({doc['schedule']['status']}); checker ok"
    )
    print(f"  {'stage':44s} {'wall s':>7s} {'cpu s':>7s} {'MB after':>9s} {'MB peak':>8s}")
    between = [0.0, 0.0, 0.0]  # wall, cpu, peak MB
    for name, wall, cpu, now, peak in meter.rows:
        if name == BETWEEN:
            between = [between[0] + wall, between[1] + cpu, max(between[2], peak)]
        else:
            print(f"  {name:44s} {wall:7.2f} {cpu:7.2f} {now:9,.0f} {peak:8,.0f}")
    wall, cpu, peak = between
    print(f"  {BETWEEN:44s} {wall:7.2f} {cpu:7.2f} {'':9s} {peak:8,.0f}")
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(
        f"  {'end to end':44s} {time.perf_counter() - t0:7.2f} s (target < 60 s); peak memory "
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
