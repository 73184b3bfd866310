"""Plan a CAD source with ``asmplan plan`` and replay the plan through both checkers."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
from typer.testing import CliRunner

from asmplan import pipeline
from asmplan.cli import app
from asmplan.planfile import build_rotation
from asp.graph.checker import check_line, plan_operations
from asp.spec import with_subassemblies
from tests.asmplan.mesh_replay import replayed


def plan_and_check(
    source: Path,
    out: Path,
    *options: str,
    stderr: list[str] | None = None,
    stdout: list[str] | None = None,
) -> dict:
    """Run ``asmplan plan SOURCE -o OUT [options]`` with defaults and check its line.

    Asserts the command succeeds, the principal line does every operation of the spec
    loaded afresh from ``source`` (with the units the plan used: the CAD file's and the
    automatic ones are decided while planning; each inserted by an operation named as the
    unit), and :func:`asp.graph.checker.check_line` accepts it (the units built in their own
    workspaces along the gravity ``plan.json``'s ``workspaces`` give, ``held`` as the plan's
    operations say: what the plan claims an agent holds), and the mesh replay
    (:mod:`tests.asmplan.mesh_replay`: ``plan.json`` and the meshes alone) accepts both of
    its lines, and ``report.html`` has a picture of each step that places parts (the
    meshes found again from ``parts[].source``). Returns ``plan.json`` as a dict; the
    command's stderr (its notes) is appended to ``stderr`` when given, its stdout (the
    summary) to ``stdout``.
    """
    result = CliRunner().invoke(app, ["plan", str(source), "-o", str(out), *options])
    assert result.exit_code == 0, result.output
    if stderr is not None:
        stderr.append(result.stderr)
    if stdout is not None:
        stdout.append(result.stdout)
    doc = json.loads((out / "plan.json").read_text())
    ops = plan_operations(doc)
    assembly = pipeline.load(source, on_step=lambda _: None)
    spec = assembly.spec
    own = {u for u, _ in spec.subassemblies}
    spec = with_subassemblies(
        spec, [(u, ms) for u, ms in doc["subassemblies"].items() if u not in own]
    )
    held = {op: bool(info.get("held")) for op, info in doc["operations"].items()}
    spec = replace(
        spec, operations=tuple(replace(op, held=held.get(op.id, op.held)) for op in spec.operations)
    )
    assert sorted(ops) == sorted(spec.op_ids)
    if doc.get("geometry"):  # the relations below are in the frame the plan was made in
        assert np.allclose(build_rotation(spec), doc["geometry"]["build_rotation"])
    down = {w["id"]: w["gravity"] for w in doc["workspaces"] if w["id"] != "main"}
    check_line(spec, assembly.relations, ops, units=doc["subassemblies"], gravity=down)
    replayed(doc)
    if doc.get("geometry"):  # report.html pictures each step that places parts, from the meshes
        placing = [s for s in doc["robust_plan"] if s.get("parts")]
        assert (out / "report.html").read_text().count("<figure>") == min(40, len(placing))
    return doc
