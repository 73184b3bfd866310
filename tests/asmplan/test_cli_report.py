"""``asmplan report PLAN_DIR``: report.html redrawn from plan.json alone (issue 22 B3); two
runs of ``asmplan plan`` write the same plan.json (issue 26 item 7)."""

from __future__ import annotations

import json

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
    ("asmplan.pipeline", "alternate_preview"),
    ("asp.graph.state_graph", "build_state_graph"),
    ("asp.game.solve", "solve"),
    ("asp.concurrent.plan", "plan_concurrent"),
    ("asp.concurrent.robustness", "robustness"),
    ("asp.schedule.assembly_makespan", "assembly_makespan"),
    ("asp.schedule.makespan", "min_makespan"),
)
"""Every entry that plans or solves: ``asmplan report`` calls none of them."""


def plan_into(out, turn_model: str):
    args = ["plan", str(PUMP), "-o", str(out), "--time-limit", "20", "--turn-model", turn_model]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    return out


@pytest.fixture(scope="module", params=["alternate", "concurrent"])
def plan_dir(request, tmp_path_factory):
    return plan_into(tmp_path_factory.mktemp(request.param) / "plan", request.param)


def refuse_to_solve(monkeypatch):
    import importlib

    def refuse(*_args, **_kwargs):
        raise AssertionError("asmplan report must not solve anything")

    for module, name in SOLVERS:
        monkeypatch.setattr(importlib.import_module(module), name, refuse)


def test_the_redrawn_report_is_byte_identical(plan_dir, tmp_path, monkeypatch):
    """The alternate plan's report is drawn to ``-o``, the concurrent one's in place."""
    written = (plan_dir / "report.html").read_bytes()
    refuse_to_solve(monkeypatch)
    alternate = json.loads((plan_dir / "plan.json").read_text())["turn_model"] == "alternate"
    again = tmp_path / "again.html" if alternate else plan_dir / "report.html"
    output = ["-o", str(again)] if alternate else []
    result = CliRunner().invoke(app, ["report", str(plan_dir), *output])
    assert result.exit_code == 0, result.output
    assert result.output.strip().splitlines()[-1] == f"wrote {again}"
    assert again.read_bytes() == written


def test_a_second_run_writes_the_same_plan_json(plan_dir, tmp_path):
    """Issue 26 item 7: the times measured while planning go to ``timings.json`` (named
    by the manifest), so ``plan.json`` is a function of its inputs: byte-identical."""
    from asmplan.planfile import TIMING_KEYS
    from asp.atomic import MANIFEST

    doc = json.loads((plan_dir / "plan.json").read_text())
    second = plan_into(tmp_path / "second", doc["turn_model"])
    assert (second / "plan.json").read_bytes() == (plan_dir / "plan.json").read_bytes()
    timings = json.loads((plan_dir / "timings.json").read_text())
    assert timings["format"] == "asmplan-timings/1"
    assert {"wall_s", "stage_s", "improvements"} <= set(timings["schedule"])
    assert ("seconds" in timings.get("concurrent", {})) == (doc["turn_model"] == "concurrent")
    for part, keys in TIMING_KEYS.items():
        assert not set(keys) & set(doc.get(part, {})), part
    assert "timings.json" in json.loads((plan_dir / MANIFEST).read_text())["files"]


def test_the_alternate_plan_keeps_its_concurrent_preview(plan_dir):
    doc = json.loads((plan_dir / "plan.json").read_text())
    page = (plan_dir / "report.html").read_text()
    if doc["turn_model"] == "alternate":
        preview = doc["concurrent_preview"]
        assert set(preview) == {"robustness", "concurrent", "schedule", "states", "sequences"}
        assert "solved on the state graph a concurrent plan uses" in page
    else:
        assert "concurrent_preview" not in doc
    assert "The concurrent game was not solved" not in page
    for alt in ("price of robustness", "gantt cooperative", "gantt worst", "CP-SAT Gantt chart"):
        assert f'alt="{alt}"' in page
    assert ('alt="game DAG"' in page) == (doc["turn_model"] == "alternate")


def test_one_solution_one_set_of_figures(plan_dir, tmp_path, monkeypatch):
    """Issue 23 item 4: a concurrent plan's report shows its concurrent game's figures only
    (its metrics are that game's), never the alternating game's DAG picture ("TCT 259, W*
    259" under metrics that say 215): no dag.png is written, and one found in the folder is
    not drawn (the page stays a function of plan.json)."""
    doc = json.loads((plan_dir / "plan.json").read_text())
    page = (plan_dir / "report.html").read_text()
    if doc["turn_model"] == "alternate":
        assert (plan_dir / "dag.png").is_file() and "<h2>The game DAG</h2>" in page
        return
    assert not (plan_dir / "dag.png").exists()
    assert "The game DAG" not in page and "alternating game" not in page
    folder = tmp_path / "plan"
    folder.mkdir()
    for name in ("plan.json", "report.html"):
        (folder / name).write_bytes((plan_dir / name).read_bytes())
    (folder / "dag.png").write_bytes(b"\x89PNG an alternating game's picture")
    refuse_to_solve(monkeypatch)
    result = CliRunner().invoke(app, ["report", str(folder)])
    assert result.exit_code == 0, result.output
    assert (folder / "report.html").read_bytes() == (plan_dir / "report.html").read_bytes()


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


def test_the_concurrent_figures_are_drawn_from_plan_json(plan_dir, tmp_path, monkeypatch):
    """robustness.png and the Gantt PNGs of a concurrent plan are a function of plan.json."""
    from asmplan.planfile import read_plan
    from asmplan.report.gantt import write_figures

    doc = read_plan(plan_dir)
    if doc["turn_model"] != "concurrent":
        pytest.skip("an alternate plan writes no concurrent figures")
    refuse_to_solve(monkeypatch)
    written = write_figures(doc, tmp_path)
    assert [p.name for p in written] == [
        "robustness.png",
        "gantt_cooperative.png",
        "gantt_worst.png",
    ]
    for path in written:
        assert path.read_bytes() == (plan_dir / path.name).read_bytes(), path.name
