"""``asmplan plan --turn-model concurrent`` as a user runs it: outputs, keys, bad input."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

PUMP = Path(__file__).resolve().parents[2] / "examples" / "vacuum_pump"
FIGURES = ("robustness.png", "gantt_cooperative.png", "gantt_worst.png")


def run(*args):
    return subprocess.run(
        [sys.executable, "-c", "from asmplan.cli import main; main()", *args],
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_pump_concurrent_plan(tmp_path):
    out = tmp_path / "out"
    r = run("plan", str(PUMP), "--turn-model", "concurrent", "-o", str(out))
    assert r.returncode == 0, r.stderr
    assert "robust plan W*(k)" in r.stdout and "(fully adversarial)" in r.stdout
    steps = [line[:5] for line in r.stderr.splitlines() if line.startswith("[")]
    assert steps == ["[1/5]", "[2/5]", "[3/5]", "[4/5]", "[5/5]"], r.stderr  # each once
    assert "robot-vs-human" not in r.stderr  # no alternating game (issue 23 item 4)
    for name in ("plan.json", *FIGURES):
        assert (out / name).stat().st_size > 0, name
    assert not (out / "dag.png").exists()  # the figures of the concurrent game only
    plan = json.loads((out / "plan.json").read_text())
    assert plan["turn_model"] == "concurrent"
    assert plan["schedule"]["objective"] == 215 and plan["schedule"]["status"] == "OPTIMAL"
    rows = plan["robustness"]
    assert rows[0] == {"k": 0, "bound": 215, "lower": 215, "upper": 215, "exact": True}
    assert rows[-1]["k"] is None and plan["concurrent"]["certified_policy"] == "robust"
    assert [r["k"] for r in rows[:-1]] == list(range(len(rows) - 1))
    bounds = [r["bound"] for r in rows]
    assert bounds == sorted(bounds)
    policy = plan["policy"]  # one policy table for both turn models
    assert policy["turn_model"] == "concurrent" and "policy" not in plan["concurrent"]
    states, start = policy["states"], policy["start"]
    assert states["done"][start] == "0"
    assert policy["tools"] == {"R1.bit": ["hex", "cross"]}
    assert states["tools"][start] == [0]  # R1.bit = hex
    assert states["running"][start] == []
    assert states["budget"][start] == plan["concurrent"]["plan_budget"]
    assert states["turn"][start] == "robot"
    assert plan["minimax"] == 215 and plan["metrics"]["w0"] == 215
    assert plan["robust_plan"][-1]["elapsed"] == 215


def test_a_search_stopped_by_its_limit_answers_a_certified_interval(tmp_path):
    """Past --max-nodes the plan still answers, exit 0: each W*(k) in [L, U] containing the
    exact value, the plan's policy certified at U (its policy game's bound), and says so."""
    exact = json.loads((_plan(tmp_path / "exact")).read_text())["robustness"]
    path = _plan(tmp_path / "cut", "--max-nodes", "3")
    r_doc = json.loads(path.read_text())
    rows, game = r_doc["robustness"], r_doc["concurrent"]
    assert game["stopped"] and game["certified_policy"] in {"hybrid", "greedy", "schedule"}
    for row, true in zip(rows, exact, strict=True):
        assert row["lower"] <= true["bound"] <= row["upper"] <= row["bound"]
        assert row["exact"] == (row["lower"] == row["upper"])
    for key in ("lower", "upper"):
        assert [r[key] for r in rows] == sorted(r[key] for r in rows)  # never fall with k


def _plan(out: Path, *flags: str) -> Path:
    r = run("plan", str(PUMP), "--turn-model", "concurrent", "-o", str(out), *flags)
    assert r.returncode == 0, r.stderr
    if flags:
        assert "W*(k) lies in [L, U]" in r.stdout, r.stdout
    return out / "plan.json"


def small_spec(**changes) -> dict:
    data = {
        "name": "small",
        "agents": {"H": {"side": "human"}, "R1": {"side": "robot"}},
        "turn_model": "alternate",
        "cost": "time",
        "operations": [
            {"id": "a", "agents": {"H": 3}},
            {"id": "b", "agents": {"R1": 4}, "after": ["a"]},
        ],
    }
    data.update(changes)
    return data


def with_op(**fields) -> dict:
    ops = small_spec()["operations"]
    ops[0] = {**ops[0], **fields}
    return small_spec(operations=ops)


BAD = [
    (with_op(agents={"H": [5, 3]}), "operations[a]"),
    (with_op(agents={"H": -1}), "operations[a]"),
    (with_op(agents={"H": ".nan"}), "operations[a]"),
    (with_op(agents={}), "operations[a]"),
    (
        small_spec(agents={"H": {"side": "human"}, "R1": {"side": "robot"}, "R2": "robot"}),
        "R2",
    ),
]


@pytest.mark.parametrize(("data", "where"), BAD)
def test_bad_input_one_line_exit_2_nothing_written(tmp_path, data, where):
    spec = tmp_path / "assembly.yaml"
    text = yaml.safe_dump(data).replace("'.nan'", ".nan")
    spec.write_text(text)
    out = tmp_path / "out"
    r = run("plan", str(spec), "--turn-model", "concurrent", "-o", str(out))
    assert r.returncode == 2, r.stdout + r.stderr
    # Progress lines may come first on stderr; the error is one line, the last.
    errors = [x for x in r.stderr.strip().splitlines() if x.startswith("asmplan: error:")]
    assert len(errors) == 1 and r.stderr.strip().endswith(errors[0]), r.stderr
    assert where in errors[0]
    assert not out.exists()


def test_negative_k_is_a_usage_error(tmp_path):
    out = tmp_path / "out"
    r = run("plan", str(PUMP), "--turn-model", "concurrent", "--max-k", "-1", "-o", str(out))
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "--max-k" in lines[0]
    assert not out.exists()
