"""A product drawn in any orientation plans as it does drawn upright: the build frame.

Each built assembly (tests/cad) is written twice, as one STL per part: upright, and turned
by a seeded random rotation (an axis drawn uniformly, 15 to 60 degrees), as a CAD file drawn
in the product's own orientation is. Both are planned with ``asmplan plan`` and default
settings (:func:`benchmarks.plan_real_cad.plan_one`: a child process, the plan checked
against relations loaded afresh). Prints one row per assembly: the frame the turned one was
given (``asp/fromcad/framing.py``; stderr of the plan command), the seconds and peak memory of
each, and TCT / W* of each, which should agree.

Run: ``.venv/bin/python benchmarks/plan_turned.py [--seed N] [NAME ...]`` (names:
``tilted_pins gear_pair bolted_bracket die_set``; default all but ``die_set``, the heavy one).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # run from a checkout

DEFAULT = ("tilted_pins", "gear_pair", "bolted_bracket")


def write(name: str, folder: Path, rotation: np.ndarray | None) -> Path:
    """The built assembly ``name`` as STL files in ``folder``, turned by ``rotation``."""
    from tests.cad import real_shapes

    builder = getattr(real_shapes, name)
    meshes = builder(upright=True) if name == "tilted_pins" else builder()
    folder.mkdir(parents=True)
    turn = np.eye(4)
    if rotation is not None:
        turn[:3, :3] = rotation
    for pid, mesh in meshes.items():
        mesh.copy().apply_transform(turn).export(folder / f"{pid}.stl")
    return folder


def plan(path: Path, out: Path) -> tuple[dict, str]:
    """``plan_one`` in a child of its own (peak memory per plan), and the command's frame."""
    script = Path(__file__).with_name("plan_real_cad.py")
    cmd = [sys.executable, str(script), "--one", str(path), str(out), "600"]
    row = json.loads(subprocess.run(cmd, capture_output=True, text=True, check=True).stdout)
    frame = "file"
    if (out / "plan.json").is_file():
        rotation = json.loads((out / "plan.json").read_text())["geometry"]["build_rotation"]
        if not np.allclose(rotation, np.eye(3)):
            from cad.frame import frame_text

            frame = frame_text(tuple(map(tuple, rotation)))
    return row, frame


def main(argv: list[str]) -> None:
    from cad.frame import rotation_matrix

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*", default=list(DEFAULT))
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    print("| assembly | frame of the turned file | s upright / turned | peak MB | TCT | W* |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.names:
            axis = rng.normal(size=3)
            degrees = float(rng.uniform(15.0, 60.0))
            rotation = rotation_matrix(axis, degrees)
            rows = []
            for label, turn in (("upright", None), ("turned", rotation)):
                folder = write(name, Path(tmp) / name / label, turn)
                rows.append(plan(folder, Path(tmp) / name / f"{label}_plan"))
            (up, _), (turned, frame) = rows

            def both(key: str, up=up, turned=turned) -> str:
                return " / ".join(str(r.get(key, r.get("error", "?"))) for r in (up, turned))

            print(
                f"| {name} (turned {degrees:.1f} deg) | {frame} | {both('total_s')} | "
                f"{both('peak_mb')} | {both('tct')} | {both('w_star')} |"
            )
            sys.stdout.flush()


if __name__ == "__main__":
    main(sys.argv[1:])
