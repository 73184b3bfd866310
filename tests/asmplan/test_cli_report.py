"""``asmplan report PLAN_DIR``: report.html redrawn from plan.json alone (issue 22 B3)."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

from asmplan.cli import app
from tests.conftest import REPO

PUMP = REPO / "examples" / "vacuum_pump"

SOLVERS = (
    ("asmplan.pipeline", "plan"),
    ("asmplan.pipeline", "state_graph"),
    ("asmplan.pipeline", "solve_game"),
    ("asmplan.pipeline", "schedule"),
    ("asmplan.pipeline", "concurrent_preview"),
    ("asp.graph.state_graph", "build_state_graph"),
    ("asp.game.solve", "solve"),
    ("asp.concurrent.plan", "plan_concurrent"),
    ("asp.concurrent.robustness", "robustness"),
    ("asp.schedule.assembly_makespan", "assembly_makespan"),
    ("asp.schedule.makespan", "min_makespan"),
)
"""Every entry that plans or solves: ``asmplan report`` calls none of them."""


@pytest.fixture(scope="module", params=["alternate", "concurrent"])
def plan_dir(request, tmp_path_factory):
    out = tmp_path_factory.mktemp(request.param) / "plan"
    args = ["plan", str(PUMP), "-o", str(out), "--time-limit", "20"]
    result = CliRunner().invoke(app, [*args, "--turn-model", request.param])
    assert result.exit_code == 0, result.output
    return out


def refuse_to_solve(monkeypatch):
    import importlib

    def refuse(*_args, **_kwargs):
        raise AssertionError("asmplan report must not solve anything")

    for module, name in SOLVERS:
        monkeypatch.setattr(importlib.import_module(module), name, refuse)


def test_the_redrawn_report_is_byte_identical(plan_dir, tmp_path, monkeypatch):
    written = (plan_dir / "report.html").read_bytes()
    refuse_to_solve(monkeypatch)
    again = tmp_path / "again.html"
    result = CliRunner().invoke(app, ["report", str(plan_dir), "-o", str(again)])
    assert result.exit_code == 0, result.output
    assert again.read_bytes() == written
    in_place = CliRunner().invoke(app, ["report", str(plan_dir)])
    assert in_place.exit_code == 0, in_place.output
    assert (plan_dir / "report.html").read_bytes() == written


def test_the_alternate_plan_keeps_its_concurrent_preview(plan_dir):
    import json

    doc = json.loads((plan_dir / "plan.json").read_text())
    page = (plan_dir / "report.html").read_text()
    if doc["turn_model"] == "alternate":
        assert set(doc["concurrent_preview"]) == {"robustness", "concurrent", "schedule"}
    else:
        assert "concurrent_preview" not in doc
    assert "The concurrent game was not solved" not in page
    assert page.count("<img") >= 4  # the curve, two timelines and the game DAG


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda p: p / "nope", "no such plan folder"),
        (lambda p: p, "no such plan file"),
        (lambda p: (p / "f.json").write_text("{}") and p / "f.json", "no such plan folder"),
    ],
)
def test_a_bad_plan_folder_is_one_line_and_exit_2(tmp_path, make, message):
    result = CliRunner().invoke(app, ["report", str(make(tmp_path))])
    assert result.exit_code == 2
    assert message in result.output and len(result.output.strip().splitlines()) == 1
