"""Plan real CAD assemblies as a new user would and check every plan independently.

For each assembly (a CAD file, a folder of part meshes or an ``assembly.yaml``), in a child
process of its own: ``asmplan plan PATH -o OUT`` with default settings (the command line, a
time limit per assembly), then :func:`asp.graph.checker.check_line` on the plan's principal
line against relations loaded afresh from the same file. Prints one row per assembly: format,
parts, parts ``held``, subassemblies, length unit and size, the generated spec's gravity and
why (``asp/fromcad/gravity.py``), the exit code, seconds, peak memory of the plan command,
states, TCT, W*, the CP-SAT status and the checker's verdict, or the error (the command's
last stderr line, cut; below the table, whole). A file whose error names the spec lines
that accept its overlaps gets a second row: ``asmplan init`` writes the spec with those
lines commented, they are uncommented (``overlap_ok:``, ``flex:``) and the spec is planned.

Assemblies, by default: the Fabrica assemblies in ``../shared/data/cad/fabrica/`` (or
``$ASMPLAN_FABRICA``), the built
rod tower, bolted bracket, finger box, gear pair and bearing stack (tests/cad), and every
public CAD file found under the folders of ``$ASMPLAN_REAL_CAD`` (``:``-separated; default
``/tmp/realcad``), skipped when absent: STEP, 3DXML, GLB/glTF, 3MF and OBJ files, and
folders of part meshes (OBJ/STL/PLY).
Public files are never copied into the repository.

Run: ``.venv/bin/python benchmarks/plan_real_cad.py [--timeout S] [--out DIR] [PATH ...]``
(a PATH that is a folder of CAD files is searched like the default folders).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # run from a checkout

FABRICA = Path(
    os.environ.get("ASMPLAN_FABRICA", ROOT.parent / "shared" / "data" / "cad" / "fabrica")
)
BUILT = ("rod_tower", "bolted_bracket", "finger_box", "gear_pair", "bearing_stack", "tilted_pins")
SCENES = {".step", ".stp", ".3dxml", ".glb", ".gltf", ".3mf"}
MESHES = {".obj", ".stl", ".ply", ".off"}
COLUMNS = (
    "format",
    "parts",
    "held",
    "units",
    "unit",
    "down",
    "exit",
    "total_s",
    "peak_mb",
    "states",
    "tct",
    "w_star",
    "cpsat",
    "checker",
)
HEADER = (
    "assembly", "format", "parts", "held", "units", "unit, size", "down (why)", "exit", "s",
    "peak MB", "states", "TCT", "W*", "CP-SAT", "checker",
)  # fmt: skip


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


def find_assemblies(folder: Path) -> list[Path]:
    """Every CAD scene file under ``folder``, every folder holding two or more part meshes
    (or an ``assembly.yaml``) and a folder's only OBJ, sorted."""
    found: list[Path] = []
    for here, dirs, files in os.walk(folder):
        dirs.sort()
        here_path = Path(here)
        if "assembly.yaml" in files:
            found.append(here_path)
            dirs.clear()
            continue
        meshes = [f for f in sorted(files) if Path(f).suffix.lower() in MESHES]
        if len(meshes) >= 2:
            found.append(here_path)
        elif meshes and meshes[0].lower().endswith(".obj"):  # one OBJ: its objects are parts
            found.append(here_path / meshes[0])
        found.extend(here_path / f for f in sorted(files) if Path(f).suffix.lower() in SCENES)
    return found


def source_unit(path: str) -> str:
    """The length unit read from the file and the assembly's size in mm (``"m, 120 mm"``)."""
    from asmplan import pipeline

    try:
        geometry = pipeline.part_geometry(path)
        lo = min(p.mesh.bounds[0].min() for p in geometry.parts)
        hi = max(p.mesh.bounds[1].max() for p in geometry.parts)
    except Exception as exc:  # noqa: BLE001 - reported in the row
        return f"? ({str(exc)[:80]})"
    return f"{geometry.units}, {hi - lo:.0f} mm"


def check_plan(path: str, doc: dict) -> str:
    """``"ok"`` if the independent checker accepts the plan's principal line, else why not.

    The spec is loaded afresh from ``path``; the plan's units are added (each inserted by
    an operation named as the unit), each operation is ``held`` as the plan says (what it
    claims an agent holds), and each unit is built along its workspace's gravity."""
    from dataclasses import replace

    from asmplan import pipeline
    from asp.graph.checker import PlanCheckError, check_line, plan_operations
    from asp.spec import with_subassemblies

    assembly = pipeline.load(path, on_step=lambda _: None)
    spec = assembly.spec
    units = doc.get("subassemblies") or {}
    own = {u for u, _ in spec.subassemblies}
    spec = with_subassemblies(spec, [(u, ms) for u, ms in units.items() if u not in own])
    held = {op: bool(info.get("held")) for op, info in doc["operations"].items()}
    ops = tuple(replace(op, held=held.get(op.id, op.held)) for op in spec.operations)
    spec = replace(spec, operations=ops)
    down = {w["id"]: w["gravity"] for w in doc.get("workspaces") or () if w["id"] != "main"}
    try:
        check_line(spec, assembly.relations, plan_operations(doc), units=units, gravity=down)
    except PlanCheckError as exc:
        return f"REJECTED: {exc}"
    return "ok"


def follow_message(path: str, out: str, timeout: float, message: str = "") -> dict | None:
    """The plan after the one message a file gets: ``asmplan init`` writes the spec with the
    lines the message names commented (``overlap_ok:``, and ``flex:`` when parts then
    lock); uncommented, and a line of ``message`` init does not write added (a ``flex:``
    found by the state graph), the spec is planned as :func:`plan_one` plans a file.
    None when init fails."""
    folder = Path(out) / "spec"
    folder.mkdir(parents=True, exist_ok=True)
    spec = folder / "assembly.yaml"
    cmd = [sys.executable, "-c", "from asmplan.cli import main; main()", "init", path]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    made = subprocess.run([*cmd, "-o", str(spec)], capture_output=True, text=True, env=env)
    if made.returncode != 0 or not spec.is_file():
        return None
    text = spec.read_text()
    text = re.sub(r"(?m)^# ((overlap_ok|flex): \[)", r"\1", text)
    for line in re.findall(r"`((?:overlap_ok|flex): \[[^`]*\])`", message):
        if not re.search(rf"(?m)^{line.split(':')[0]}:", text):
            text = text.replace("\noperations:", f"\n{line}\noperations:", 1)
    spec.write_text(text)
    return plan_one(str(spec), str(Path(out) / "followed"), timeout)


def plan_one(path: str, out: str, timeout: float) -> dict:
    """Run ``asmplan plan path -o out`` in a child and check its plan (this process is a
    child of :func:`main`, so its children's peak memory is the plan command's)."""
    row: dict = {"assembly": Path(path).name, "format": source_format(path)}
    cmd = [sys.executable, "-c", "from asmplan.cli import main; main()", "plan", path, "-o", out]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    t0 = time.perf_counter()
    try:
        run = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env)
    except subprocess.TimeoutExpired as exc:
        row["error"] = f"timeout after {timeout:.0f} s"
        stderr = exc.stderr.decode() if isinstance(exc.stderr, bytes) else exc.stderr or ""
        last = [s for s in re.split(r"[\r\n]", stderr) if s.strip()]
        row["error"] += f" (last: {last[-1][:200]})" if last else ""
        run = None
    row["total_s"] = round(time.perf_counter() - t0, 1)
    row["peak_mb"] = round(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024)
    if run is None:
        return row
    text = run.stdout + run.stderr
    row["exit"] = run.returncode
    held = re.search(r"held: true for ([^(]*)\(", text)
    row["held"] = len(held.group(1).split(",")) if held else 0
    gravity = re.search(r"generated spec: gravity (\S+): (.*)", text)
    row["down"] = f"{gravity.group(1)}: {gravity.group(2).strip()}" if gravity else ""
    parts = re.search(r"generated a spec from .* \((\d+) parts", text)
    row["parts"] = int(parts.group(1)) if parts else ""
    row["unit"] = source_unit(path)
    if run.returncode != 0:
        lines = [s for s in run.stderr.splitlines() if s.strip()]
        row["error"] = lines[-1] if lines else f"exit code {run.returncode}"
        return row
    doc = json.loads((Path(out) / "plan.json").read_text())
    sched = doc.get("schedule") or {}
    row.update(
        parts=len(doc["parts"]),
        units=len(doc.get("subassemblies") or {}),
        states=doc.get("states"),
        tct=doc["tct"],
        w_star=doc["minimax"],
        cpsat=f"{sched.get('status', '')} {sched.get('objective', '')}".strip(),
    )
    try:
        row["checker"] = check_plan(path, doc)
    except Exception as exc:  # noqa: BLE001 - a row per assembly, whatever went wrong
        row["checker"] = f"check failed: {str(exc)[:200]}"
    return row


def source_format(path: str) -> str:
    """The CAD format of an assembly: its file's suffix, or the meshes of a folder."""
    p = Path(path)
    if p.is_file():
        return p.suffix.lstrip(".").upper()
    kinds = sorted(
        {f.suffix.lstrip(".").upper() for f in p.iterdir() if f.suffix.lower() in MESHES}
    )
    return f"{'/'.join(kinds)} folder" if kinds else "folder"


def print_row(row: dict) -> None:
    """One Markdown row: an error goes in the checker's column, cut to 200 characters."""
    cells = [str(row.get(c, "")) for c in COLUMNS[:-1]]
    last = row.get("checker", "")
    if "error" in row:
        error = row["error"].removeprefix("asmplan: error: ")
        last = f"error: {error[:200]}{' ...' if len(error) > 200 else ''}"
    print(f"| {row['assembly']} | " + " | ".join(cells) + f" | {last} |")
    sys.stdout.flush()


def main(argv: list[str]) -> None:
    if argv[:1] == ["--one"]:
        print(json.dumps(plan_one(argv[1], argv[2], float(argv[3]))))
        return
    if argv[:1] == ["--follow"]:
        print(json.dumps(follow_message(argv[1], argv[2], float(argv[3]), *argv[4:5])))
        return
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("paths", nargs="*", help="assemblies, or folders to search for them")
    parser.add_argument("--timeout", type=float, default=300.0, help="seconds per assembly")
    parser.add_argument("--out", default=None, help="keep each plan in OUT/<name> (default: temp)")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        if args.paths:
            paths = []
            for p in map(Path, args.paths):
                paths += find_assemblies(p) if p.is_dir() else [p]
        else:
            folders = os.environ.get("ASMPLAN_REAL_CAD", "/tmp/realcad").split(":")
            paths = [p for p in sorted(FABRICA.iterdir()) if p.is_dir()] if FABRICA.is_dir() else []
            paths += [built(name, Path(tmp)) for name in BUILT]
            for folder in map(Path, folders):
                if folder.is_dir():
                    paths += find_assemblies(folder)
                else:
                    print(f"skipped {folder}: not found", file=sys.stderr)
        out_root = Path(args.out) if args.out else Path(tmp) / "plans"
        print("| " + " | ".join(HEADER) + " |")
        print("|---" * len(HEADER) + "|")
        errors = []
        for k, path in enumerate(paths):
            out = out_root / f"{k:03d}_{Path(path).name}"
            run = subprocess.run(
                [sys.executable, __file__, "--one", str(path), str(out), str(args.timeout)],
                capture_output=True,
                text=True,
            )
            try:
                row = json.loads(run.stdout.strip().splitlines()[-1])
            except (IndexError, json.JSONDecodeError):
                row = {"assembly": Path(path).name, "error": run.stderr.strip()[-300:]}
            row["assembly"] = str(path)
            print_row(row)
            if "error" in row:
                errors.append(f"{row['assembly']}: {row['error']}")
            message = row.get("error", "")
            if "`overlap_ok: [" in message or "`flex: [" in message:  # the one message, followed
                run = subprocess.run(
                    [sys.executable, __file__, "--follow", str(path), str(out), str(args.timeout)]
                    + [message],
                    capture_output=True,
                    text=True,
                )
                try:
                    row = json.loads(run.stdout.strip().splitlines()[-1]) or {}
                except (IndexError, json.JSONDecodeError):
                    row = {"error": run.stderr.strip()[-300:]}
                row["assembly"] = f"{path} (its message's lines added)"
                print_row(row)
                if "error" in row:
                    errors.append(f"{row['assembly']}: {row['error']}")
        if errors:
            print("\nThe messages of the assemblies that do not plan, whole:\n")
            print("\n".join(f"- {e}" for e in errors))


if __name__ == "__main__":
    main(sys.argv[1:])
