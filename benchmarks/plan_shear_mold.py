"""Shear die sets planned end to end with default settings, as ``asmplan plan`` does.

The die sets are built here (:func:`tests.cad.real_shapes.die_set`, mm, z up, drawn open):
a lower half on the bench (bottom plate, guide pins, die block, screws) and an upper half
whose screws and bushings go in from below, so it is built upside down as a unit (top
plate first on the bench, :mod:`asp.fromcad.orientation`), turned over and lowered onto the guide
pins (held: drawn open, nothing of the lower half is under it). Cases: two and four
corners (4 pins, 4 bushings, 4 screws in each half: the identical parts would multiply the
states; the symmetry reduction, :mod:`asp.graph.symmetry`, orders them in the main body and in
the upper half's workspace alike), as a folder of STL parts (the upper half found
automatically) and as a Y-up glTF with the product tree a CAD export has. With a path (a
CAD file or folder, e.g. a real die set or the 26-part stand-in
``/tmp/realcad/synth/shear_mold``; not in the repository), that file instead.

Each row: parts, the units with the gravity of their workspace, states, wall time and peak
memory of the ``asmplan plan`` process, TCT and W*, and the relations checker on the
plan's lines (``line_check``). Run: ``.venv/bin/python benchmarks/plan_shear_mold.py [PATH]``
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

from cad import Assembly  # noqa: E402
from tests.cad.real_shapes import die_set  # noqa: E402
from tests.cad.test_loading import write_folder  # noqa: E402
from tests.cad.test_subassemblies import write_glb  # noqa: E402

UPPER = ("top_", "bushing", "punch", "stripper")


def cases(folder: Path) -> list[tuple[str, Path]]:
    """The built die sets, written under ``folder``."""
    out = []
    for corners in (2, 4):
        parts = die_set(corners=corners)
        name = f"die_set_{corners}"
        out.append(
            (f"{name} (STL folder)", write_folder(folder / name, Assembly.from_meshes(parts)))
        )
        upper = [p for p in parts if p.startswith(UPPER)]
        tree = {
            "Product": ["lower_die_set", "upper_die_set"],
            "lower_die_set": [p for p in parts if p not in upper],
            "upper_die_set": upper,
        }
        write_glb(folder / f"{name}.glb", parts, tree)
        out.append((f"{name}.glb (Y up, product tree)", folder / f"{name}.glb"))
    return out


def run(source: Path, out: Path) -> dict:
    """``asmplan plan SOURCE -o OUT`` in a child process: its figures from plan.json."""
    t0 = time.perf_counter()
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    done = subprocess.run(
        [str(Path(sys.executable).parent / "asmplan"), "plan", str(source), "-o", str(out)],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    wall = time.perf_counter() - t0
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    row = {"s": wall, "peak_mb": max(peak, before) / 1024}
    if done.returncode != 0:
        row["error"] = (done.stderr.strip().splitlines() or ["?"])[-1][:160]
        return row
    doc = json.loads((out / "plan.json").read_text())
    spaces = {w["id"]: w["gravity"] for w in doc["workspaces"]}
    row.update(
        parts=len(doc["parts"]),
        units=", ".join(
            f"{u} ({len(m)}, gravity {spaces.get(u)})" for u, m in doc["subassemblies"].items()
        ),
        states=doc.get("states"),
        tct=doc["tct"],
        w=doc["minimax"],
        check="ok" if not any(doc["line_check"].values()) else str(doc["line_check"]),
    )
    return row


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        todo = [(sys.argv[1], Path(sys.argv[1]))] if len(sys.argv) > 1 else cases(folder)
        print(
            "| die set | parts | units (members, gravity) | states | s | peak MB | TCT | W* "
            "| checker |"
        )
        print("|---|---|---|---|---|---|---|---|---|")
        for k, (name, source) in enumerate(todo):
            r = run(source, folder / f"out_{k}")
            if "error" in r:
                print(f"| {name} | | | | {r['s']:.0f} | {r['peak_mb']:,.0f} | | | {r['error']} |")
                continue
            states = f"{r['states']:,}" if isinstance(r["states"], int) else r["states"]
            print(
                f"| {name} | {r['parts']} | {r['units']} | {states} | {r['s']:.0f} | "
                f"{r['peak_mb']:,.0f} | {r['tct']:g} | {r['w']:g} | {r['check']} |"
            )
        print("peak MB: the largest child so far (ru_maxrss of the children), per row")


if __name__ == "__main__":
    main()
