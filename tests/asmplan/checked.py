"""Plan a CAD source with ``asmplan plan`` and replay the plan through the checker."""

from __future__ import annotations

import json
from pathlib import Path

from typer.testing import CliRunner

from asmplan import pipeline
from asmplan.cli import app
from asp.checker import check_line, plan_operations


def plan_and_check(source: Path, out: Path, *options: str) -> dict:
    """Run ``asmplan plan SOURCE -o OUT [options]`` with defaults and check its line.

    Asserts the command succeeds, the principal line does every operation of the spec
    loaded afresh from ``source``, and :func:`asp.checker.check_line` accepts it (with the
    plan's subassemblies). Returns ``plan.json`` as a dict.
    """
    result = CliRunner().invoke(app, ["plan", str(source), "-o", str(out), *options])
    assert result.exit_code == 0, result.output
    doc = json.loads((out / "plan.json").read_text())
    ops = plan_operations(doc)
    assembly = pipeline.load(source, on_step=lambda _: None)
    assert sorted(ops) == sorted(assembly.spec.op_ids)
    check_line(assembly.spec, assembly.relations, ops, units=doc["subassemblies"])
    return doc
