"""``asmplan plan --turn-model concurrent`` writes the same plan.json bytes when its search
budget binds (issue 26 item 7): the search stops on positions, not on the wall clock,
whose safety net is said on stderr and in timings.json only."""

from __future__ import annotations

import json

from typer.testing import CliRunner

from asmplan.cli import app
from asp.concurrent.search import work_positions
from tests.conftest import REPO

RANGES = REPO / "examples" / "vacuum_pump_ranges"
FLAGS = ("--turn-model", "concurrent", "--duration-step", "0.005", "--time-limit", "5")


def plan_into(out, *flags: str):
    result = CliRunner().invoke(app, ["plan", str(RANGES), "-o", str(out), *FLAGS, *flags])
    assert result.exit_code == 0, result.output
    return result


def test_two_runs_stopped_by_the_search_budget_write_the_same_plan_json(tmp_path):
    for name in ("a", "b"):
        plan_into(tmp_path / name, "--search-time-limit", "0.5")
    first, second = ((tmp_path / n / "plan.json").read_bytes() for n in ("a", "b"))
    assert first == second
    game = json.loads(first)["concurrent"]
    assert game["stopped"] == "time limit"  # the budget bound
    assert game["positions_expanded"] == work_positions(0.5)
    timings = json.loads((tmp_path / "a" / "timings.json").read_text())
    assert "seconds" in timings["concurrent"] and "wall_stop" not in timings["concurrent"]


def test_the_safety_net_is_said_on_stderr_and_in_timings_only(tmp_path, monkeypatch):
    from asp.concurrent import search

    monkeypatch.setattr(search, "wall_safety", lambda seconds: 0.0)
    result = plan_into(tmp_path / "net", "--search-time-limit", "100")
    lines = [line for line in result.output.splitlines() if "safety net" in line]
    assert len(lines) == 1 and "100 search seconds" in lines[0], result.output
    doc = json.loads((tmp_path / "net" / "plan.json").read_text())
    assert doc["concurrent"]["positions_expanded"] == 32_768  # the first look at the clock
    assert doc["concurrent"]["certified_policy"] != "robust"  # its game was cut by the net
    assert "wall_stop" not in doc["concurrent"]
    timings = json.loads((tmp_path / "net" / "timings.json").read_text())
    assert timings["concurrent"]["wall_stop"] == 0.0
