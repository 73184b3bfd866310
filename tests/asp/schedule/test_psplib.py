"""PSPLIB j30 (Kolisch and Sprecher 1996): reader, optimum, the baseline command."""

from __future__ import annotations

import csv
import json

import pytest
from typer.testing import CliRunner

from asmplan.cli import app
from asp.schedule.makespan import min_makespan
from asp.schedule.psplib import read_sm


def optimum(shared_data, name):
    with open(shared_data / "psplib_j30" / "optimum.csv") as handle:
        return {r["problem"]: int(r["optimum"]) for r in csv.DictReader(handle)}[name]


def test_reader(shared_data):
    problem = read_sm(shared_data / "psplib_j30" / "j301_1.sm")
    assert len(problem.tasks) == 32
    assert problem.resources == (("R1", 12), ("R2", 13), ("R3", 4), ("R4", 12))
    assert problem.tasks[1].modes == (("", 8),) and problem.tasks[1].demands == (4, 0, 0, 0)
    assert (0, 1) in problem.precedences and (30, 31) in problem.precedences
    assert len(problem.precedences) == 48
    assert "Kolisch and Sprecher 1996" in problem.credit


@pytest.mark.parametrize("name", ["j301_1.sm", "j301_2.sm", "j3010_1.sm"])
def test_small_instances_reach_the_published_optimum(shared_data, name):
    result = min_makespan(read_sm(shared_data / "psplib_j30" / name), time_limit=30, workers=1)
    assert result.status == "OPTIMAL"
    assert result.objective == optimum(shared_data, name)


def test_baseline_command_json(shared_data):
    path = shared_data / "psplib_j30" / "j301_1.sm"
    out = CliRunner().invoke(app, ["baseline", str(path), "--format", "json", "--seed", "3"])
    assert out.exit_code == 0, out.output
    data = json.loads(out.output)
    assert {"status", "objective", "bound", "wall_s"} <= set(data)
    assert data["status"] == "OPTIMAL" and data["objective"] == data["bound"] == 43
    again = json.loads(
        CliRunner().invoke(app, ["baseline", str(path), "--format", "json", "--seed", "3"]).output
    )
    assert again["schedule"] == data["schedule"]


def test_reader_errors(tmp_path):
    bad = tmp_path / "bad.sm"
    bad.write_text("nothing here\n")
    with pytest.raises(ValueError, match="missing section 'PRECEDENCE RELATIONS'"):
        read_sm(bad)
