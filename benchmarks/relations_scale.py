"""Scale benchmark of ``cad.compute_relations``: 40 parts of about 2,000 triangles each.

Ten bolted joints in a 5 x 2 grid. Each joint is a base plate and a cover plate, both
with two holes, and two screws through them: the screw shafts use the same polygon as the
holes (zero-clearance pins, as CAD draws them), the heads rest on the cover, the plates of
neighbouring joints touch side by side. Prints parts, triangles, pairs, seconds and where
the time goes.

Run: ``.venv/bin/python benchmarks/relations_scale.py [--profile]``
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import sys
import time
from pathlib import Path

import numpy as np
import trimesh

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a checkout

from cad import (  # noqa: E402
    Assembly,
    check_interpenetration,
    contact_relation,
    translational_freedom,
)
from cad.freedom import eroded_meshes  # noqa: E402
from cad.tolerances import resolve_tolerances  # noqa: E402

SECTIONS = 250
PLATE = (40.0, 40.0, 6.0)
HOLE_R = 4.0
HOLES = ((-10.0, 0.0), (10.0, 0.0))


def _cylinder(radius: float, z0: float, z1: float, xy=(0.0, 0.0)) -> trimesh.Trimesh:
    mesh = trimesh.creation.cylinder(radius=radius, height=z1 - z0, sections=SECTIONS)
    mesh.apply_translation((xy[0], xy[1], (z0 + z1) / 2))
    return mesh


def _plate(z0: float) -> trimesh.Trimesh:
    plate = trimesh.creation.box(extents=PLATE)
    plate.apply_translation((0, 0, z0 + PLATE[2] / 2))
    cutters = [_cylinder(HOLE_R, z0 - 1, z0 + PLATE[2] + 1, xy) for xy in HOLES]
    return trimesh.boolean.difference([plate, *cutters], engine="manifold")


def _screw(xy) -> trimesh.Trimesh:
    top = 2 * PLATE[2]
    shaft = _cylinder(HOLE_R, 0.0, top, xy)
    head = _cylinder(HOLE_R * 1.8, top, top + 4.0, xy)
    return trimesh.boolean.union([shaft, head], engine="manifold")


def build_assembly() -> Assembly:
    """Ten joints (base, cover, two screws) in a 5 x 2 grid: 40 parts."""
    base, cover = _plate(0.0), _plate(PLATE[2])
    screws = [_screw(xy) for xy in HOLES]
    meshes = {}
    for gx in range(5):
        for gy in range(2):
            shift = np.array([gx * PLATE[0], gy * PLATE[1], 0.0])
            name = f"j{gx}{gy}"
            for part, mesh in (
                ("base", base),
                ("cover", cover),
                ("s0", screws[0]),
                ("s1", screws[1]),
            ):
                meshes[f"{name}_{part}"] = mesh.copy().apply_translation(shift)
    return Assembly.from_meshes(meshes)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", action="store_true", help="print the top functions")
    args = parser.parse_args()

    t0 = time.perf_counter()
    assembly = build_assembly()
    t_build = time.perf_counter() - t0
    n = len(assembly)
    tris = [len(p.mesh.faces) for p in assembly.parts]
    tols = resolve_tolerances(assembly)
    ctol, ptol = tols.contact, tols.penetration

    profiler = cProfile.Profile() if args.profile else None
    if profiler:
        profiler.enable()
    timings = {}
    t = time.perf_counter()
    eroded = eroded_meshes(assembly, tols.shrink)
    timings["erode parts (offset)"] = time.perf_counter() - t
    t = time.perf_counter()
    check_interpenetration(assembly, penetration_tol=tols, eroded=eroded)
    timings["interpenetration check (FCL)"] = time.perf_counter() - t
    t = time.perf_counter()
    tc = contact_relation(assembly, penetration_tol=tols)
    timings["contact TC"] = time.perf_counter() - t
    t = time.perf_counter()
    tt = translational_freedom(assembly, penetration_tol=tols, check=False)
    timings["freedom TT (erodes again)"] = time.perf_counter() - t
    if profiler:
        profiler.disable()
    total = sum(timings.values())

    print(f"parts            {n}")
    print(f"triangles        {sum(tris)} (min {min(tris)}, max {max(tris)} per part)")
    print(f"ordered pairs    {n * (n - 1)} x 6 directions")
    print(f"tolerances       contact {ctol:g} mm, penetration up to {ptol:.3g} mm per pair")
    print(f"build meshes     {t_build:.2f} s (not part of the relations)")
    for name, seconds in timings.items():
        print(f"  {name:<32} {seconds:6.2f} s")
    print(f"relations total  {total:.2f} s")
    print(f"contacts         {int(tc.sum()) // 2} (pair, direction) facts")
    print(f"blocked          {int((~tt).sum()) - n * 6} of {n * (n - 1) * 6} (pair, direction)")
    if profiler:
        pstats.Stats(profiler).sort_stats("cumulative").print_stats(15)


if __name__ == "__main__":
    main()
