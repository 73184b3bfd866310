"""Plan real CAD assemblies with default settings and check every plan independently.

For each assembly (a CAD file, a folder of part meshes or an ``assembly.yaml``; default: the
Fabrica assemblies in ``../shared/data/cad/fabrica/`` and the built rod tower, bolted bracket
and finger box), in a fresh process each: ``asmplan.pipeline.plan`` with defaults, then
:func:`asp.checker.check_line` on the plan's principal line. Prints one row per assembly:
parts, units (subassemblies), states, seconds per stage, peak memory, TCT, W*, checker.

Run: ``.venv/bin/python benchmarks/plan_real_cad.py [PATH ...]``
"""

from __future__ import annotations

import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # run from a checkout

FABRICA = ROOT.parent / "shared" / "data" / "cad" / "fabrica"
BUILT = ("rod_tower", "bolted_bracket", "finger_box")


def built(name: str, folder: Path) -> Path:
    """Write a built assembly (tests/cad) as one STL per part into ``folder``."""
    from tests.cad import real_shapes
    from tests.cad.test_subassemblies import rod_tower

    meshes = rod_tower() if name == "rod_tower" else getattr(real_shapes, name)()
    out = folder / name
    out.mkdir(parents=True, exist_ok=True)
    for pid, mesh in meshes.items():
        mesh.export(out / f"{pid}.stl")
    return out


def plan_one(path: str) -> dict:
    """Plan ``path`` in this process and return the row (run in a child process)."""
    from asmplan import pipeline
    from asp.checker import check_line, plan_operations

    row: dict = {"assembly": Path(path).name}
    t0 = time.perf_counter()
    try:
        assembly = pipeline.load(path)
        t1 = time.perf_counter()
        graph = pipeline.state_graph(assembly)
        t2 = time.perf_counter()
        result = pipeline.plan(pipeline.Assembly(graph.spec, assembly.relations), time_limit=30)
        t3 = time.perf_counter()
        doc = result.to_dict()
        check_line(graph.spec, assembly.relations, plan_operations(doc))
        row.update(
            parts=len(graph.spec.part_ids),
            units=len(graph.spec.subassemblies),
            states=graph.n_states,
            relations_s=round(t1 - t0, 2),
            graph_s=round(t2 - t1, 2),
            game_cpsat_s=round(t3 - t2, 2),
            tct=doc["tct"],
            w_star=doc["minimax"],
            checker="ok",
        )
    except Exception as exc:  # noqa: BLE001 - a row per assembly, whatever went wrong
        row.update(error=str(exc)[:300])
    row["total_s"] = round(time.perf_counter() - t0, 2)
    row["peak_mb"] = round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
    return row


def main(argv: list[str]) -> None:
    if argv[:1] == ["--one"]:
        print(json.dumps(plan_one(argv[1])))
        return
    with tempfile.TemporaryDirectory() as tmp:
        paths = argv or [
            *(str(p) for p in sorted(FABRICA.iterdir()) if p.is_dir()),
            *(str(built(name, Path(tmp))) for name in BUILT),
        ]
        cols = ("parts", "units", "states", "total_s", "peak_mb", "tct", "w_star", "checker")
        print("| assembly | " + " | ".join(cols) + " |")
        print("|---" * (len(cols) + 1) + "|")
        for path in paths:
            out = subprocess.run(
                [sys.executable, __file__, "--one", path], capture_output=True, text=True
            )
            try:
                row = json.loads(out.stdout.strip().splitlines()[-1])
            except (IndexError, json.JSONDecodeError):
                row = {"assembly": Path(path).name, "error": out.stderr.strip()[-300:]}
            if "error" in row:
                print(f"| {row['assembly']} | error: {row['error']} |")
            else:
                print(f"| {row['assembly']} | " + " | ".join(str(row[c]) for c in cols) + " |")
            sys.stdout.flush()


if __name__ == "__main__":
    main(sys.argv[1:])
