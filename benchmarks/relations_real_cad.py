"""Benchmark of ``cad`` relations on the realistic assemblies of ``tests/cad/real_shapes.py``
at export-grade tessellation: heavy gears and housings, the bolted bracket at 200k
triangles in 10 parts. Prints parts, triangles and seconds per stage.

Run: ``.venv/bin/python benchmarks/relations_real_cad.py [--only NAME] [--profile]``
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a checkout

from cad import (  # noqa: E402
    Assembly,
    check_interpenetration,
    contact_relation,
    translational_freedom,
)
from cad.freedom import eroded_meshes  # noqa: E402
from cad.tolerances import resolve_tolerances  # noqa: E402
from tests.cad.real_shapes import BUILDERS  # noqa: E402

DETAIL = {
    "finger_box": 1.0,  # flat panels: few triangles whatever the export setting
    "bearing_stack": 20.0,  # ~55k triangles, rings of 8k-18k
    "gear_pair": 12.0,  # gears of ~21k and ~31k triangles
    "bolted_bracket": 66.0,  # 10 parts, ~200k triangles (bracket 40k, washers 26k)
}


def run(name: str) -> float:
    t0 = time.perf_counter()
    assembly = Assembly.from_meshes(BUILDERS[name](DETAIL[name]))
    t_build = time.perf_counter() - t0
    tris = [len(p.mesh.faces) for p in assembly.parts]
    stages = {}
    t = time.perf_counter()
    tols = resolve_tolerances(assembly)
    stages["tolerances"] = time.perf_counter() - t
    t = time.perf_counter()
    eroded = eroded_meshes(assembly, tols.shrink)
    stages["erode (offset)"] = time.perf_counter() - t
    t = time.perf_counter()
    check_interpenetration(assembly, penetration_tol=tols, eroded=eroded)
    stages["interpenetration (FCL)"] = time.perf_counter() - t
    t = time.perf_counter()
    contact_relation(assembly, penetration_tol=tols)
    stages["contact TC"] = time.perf_counter() - t
    t = time.perf_counter()
    translational_freedom(assembly, penetration_tol=tols, check=False)
    stages["freedom TT"] = time.perf_counter() - t
    total = sum(stages.values())
    print(
        f"{name}: {len(assembly)} parts, {sum(tris)} triangles (max {max(tris)} per part), "
        f"pair tolerance up to {tols.penetration:.3g} mm; build {t_build:.2f} s (not timed)"
    )
    for stage, seconds in stages.items():
        print(f"  {stage:<26} {seconds:6.2f} s")
    print(f"  {'relations total':<26} {total:6.2f} s")
    return total


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", choices=sorted(BUILDERS), help="run one assembly")
    parser.add_argument("--profile", action="store_true", help="print the top functions")
    args = parser.parse_args()
    profiler = cProfile.Profile() if args.profile else None
    if profiler:
        profiler.enable()
    total = sum(run(name) for name in ([args.only] if args.only else DETAIL))
    if profiler:
        profiler.disable()
        pstats.Stats(profiler).sort_stats("cumulative").print_stats(15)
    print(f"all relations: {total:.2f} s")


if __name__ == "__main__":
    main()
