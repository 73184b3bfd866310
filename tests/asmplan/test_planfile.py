"""The plan file ``asmplan-plan/2``: schema, policy table, lines, read/write round trip."""

from __future__ import annotations

import json

import pytest

from asmplan.pipeline import build_plan
from asmplan.planfile import (
    FORMAT,
    read_plan,
    validate_plan,
    write_plan,
)
from asp.graph.checker import check_line, plan_operations
from tests.asmplan.plans import CELL, cell_game, cell_plan, concurrent_cell, concurrent_plan


@pytest.mark.parametrize("cost", ["time", "steps"])
def test_cell_plan_validates_and_round_trips(tmp_path, cost):
    doc = cell_plan(cost)
    validate_plan(doc)
    path = write_plan(tmp_path / "plan.json", doc)
    back = read_plan(tmp_path)
    assert back == json.loads(path.read_text())
    assert back["format"] == FORMAT
    assert back["cost"] == cost
    check_line(cell_game(cost)[0], None, plan_operations(back))


def test_schema_rejects_a_broken_plan():
    doc = cell_plan()
    doc["policy"]["states"]["turn"][0] = "nobody"
    with pytest.raises(ValueError, match="policy/states/turn/0"):
        validate_plan(doc)
    doc = cell_plan()
    del doc["worst_line"]
    with pytest.raises(ValueError, match="worst_line"):
        validate_plan(doc)


def test_read_plan_names_the_fault(tmp_path):
    (tmp_path / "plan.json").write_text('{"format": "asmplan-plan/1"}')
    with pytest.raises(ValueError, match="expected format 'asmplan-plan/2'"):
        read_plan(tmp_path)
    doc = cell_plan()
    doc["policy"]["states"]["bound"].pop()
    write_plan(tmp_path / "plan.json", doc)
    with pytest.raises(ValueError, match=r"policy.states.bound"):
        read_plan(tmp_path)


def test_lines_principal_and_worst():
    doc = cell_plan()
    principal, worst = doc["robust_plan"], doc["worst_line"]
    assert worst[-1]["elapsed"] == pytest.approx(doc["minimax"])
    assert principal[-1]["elapsed"] == pytest.approx(doc["metrics"]["w0"])
    assert doc["metrics"]["w0"] <= doc["minimax"] + 1e-9
    assert doc["metrics"]["w0"] < doc["minimax"]  # this cell: following the plan pays
    # Each line does every operation once, with its parts and a non-increasing bound.
    for line in (principal, worst):
        ops = [s["operation"] for s in line if s["operation"]]
        assert sorted(ops) == sorted(doc["operations"])
        assert all(s["elapsed"] + s["bound"] <= doc["minimax"] + 1e-9 for s in line)
        assert line[-1]["bound"] == 0


def test_states_are_named_by_done_operations_and_tools():
    doc = cell_plan()
    pol = doc["policy"]
    assert pol["tools"] == {"R1.bit": ["hex", "cross"]} or set(pol["tools"]["R1.bit"]) == {
        "hex",
        "cross",
    }
    assert pol["states"]["done"][0] == "0"
    assert pol["states"]["running"][0] == []
    # The end state has every operation done.
    last = max(range(pol["n_states"]), key=lambda i: int(pol["states"]["done"][i], 16))
    assert int(pol["states"]["done"][last], 16) == (1 << len(pol["operations"])) - 1


def test_pump_plan_parts_per_step(tmp_path):
    from pathlib import Path

    pump = Path(__file__).resolve().parents[2] / "examples" / "vacuum_pump"
    doc = build_plan(pump)
    validate_plan(doc)
    placed = [p for s in doc["robust_plan"] for p in s["parts"]]
    assert placed == ["PC", "VT1", "BC", "VT2", "VT1M", "EV", "VT3", "FOR", "VT4"]


def test_salbp_plan(shared_data, tmp_path):
    doc = build_plan(shared_data / "salbp" / "JACKSON.IN2")
    validate_plan(doc)
    assert doc["policy"]["agents"] == ["any"]
    assert doc["robust_plan"][-1]["bound"] == 0


# --------------------------------------------------------------------------- concurrent


RANGES = {
    **CELL,
    "operations": [
        {**op, "agents": {a: ([d, d + 2] if a == "H" else d) for a, d in op["agents"].items()}}
        for op in CELL["operations"]
    ],
}


@pytest.mark.parametrize("data", [CELL, RANGES], ids=["fixed", "ranges"])
def test_concurrent_plan_validates_and_round_trips(tmp_path, data):
    doc = concurrent_plan(data)
    validate_plan(doc)
    assert doc["turn_model"] == doc["policy"]["turn_model"] == "concurrent"
    path = write_plan(tmp_path / "plan.json", doc)
    assert read_plan(tmp_path) == json.loads(path.read_text())
    broken = json.loads(path.read_text())
    del broken["policy"]["moves"]["starts"]
    with pytest.raises(ValueError, match="starts"):
        validate_plan(broken)


@pytest.mark.parametrize("data", [CELL, RANGES], ids=["fixed", "ranges"])
def test_concurrent_policy_is_the_games_robust_policy(data):
    spec, curve = concurrent_cell(data)
    game, sol = curve.game, curve.solution
    doc = concurrent_plan(data)
    pol = doc["policy"]
    states, moves = pol["states"], pol["moves"]
    n = pol["n_states"]
    assert pol["agents"] == ["R1", "R2", "H"]  # the game's workers, robots first
    assert states["node"][pol["start"]] == game.starts[curve.k]
    assert states["budget"][pol["start"]] == curve.k
    assert all(0 <= j < n for j in moves["next"])
    for i in range(n):
        v = states["node"][i]
        lo, hi = moves["ptr"][i], moves["ptr"][i + 1]
        assert states["bound"][i] == pytest.approx(sol.value[v, states["turn"][i] == "human"])
        if states["turn"][i] == "robot" and lo < hi:  # the robots' one planned commitment
            assert hi - lo == 1
            assert [s[:2] for s in moves["starts"][lo]] == states["robots"][i]
            assert moves["deviations"][lo] == 0 and moves["cost"][lo] == 0
            # every free person is told something while the budget is finite
            running = {a for a, _, _ in states["running"][i]}
            free = [a for a in ("H",) if a not in running]
            told = {pol["agents"][a] for _, a in states["instruction"][i] or []}
            assert told == set(free)
        elif states["turn"][i] == "human":
            assert hi - lo == len(game.dag.out_edges(v))  # every reply of the person
            for m in range(lo, hi):  # deviations only while the budget lasts
                assert moves["deviations"][m] <= states["budget"][i]
    # The lines: the worst ends at the guaranteed bound; following the plan never costs more.
    assert doc["minimax"] == pytest.approx(curve.bounds[-1])
    assert doc["worst_line"][-1]["elapsed"] == pytest.approx(doc["minimax"])
    assert curve.bounds[0] - 1e-9 <= doc["metrics"]["w0"] <= doc["minimax"] + 1e-9
    ops = [s["operation"] for line in (doc["robust_plan"],) for st in line for s in st["starts"]]
    assert sorted(ops) == sorted(doc["operations"])
