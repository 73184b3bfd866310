"""``asmplan synth`` and ``asmplan solve`` as a user runs them (exit codes, JSON keys)."""

import json
import subprocess
import sys

import pytest

from asp.game.io import save_dag
from tests.asp.figures import SOLVE_KEYS, figure4

REQUIRED = SOLVE_KEYS


def run(*args):
    return subprocess.run(
        [sys.executable, "-c", "from asmplan.cli import main; main()", *args],
        capture_output=True,
        text=True,
        timeout=120,
    )


@pytest.mark.parametrize(
    ("layers", "max_nodes"), [(4, 10), (10, 4), (10, 10), (15, 10), (20, 10), (20, 20)]
)
def test_synth_then_solve_json(tmp_path, layers, max_nodes):
    out = tmp_path / "g.json"
    r = run(
        "synth",
        "--layers",
        str(layers),
        "--max-nodes",
        str(max_nodes),
        "--max-actions",
        "4",
        "--seed",
        "3",
        "--output",
        str(out),
    )
    assert r.returncode == 0, r.stderr
    r = run("solve", str(out), "--format", "json")
    assert r.returncode == 0, r.stderr
    result = json.loads(r.stdout)
    assert all(key in result for key in REQUIRED)
    assert result["minimax"] >= result["tct"] and result["rr"] == 1.0


def test_solve_figure4_text_and_graphml(tmp_path):
    path = save_dag(figure4(), tmp_path / "fig4.graphml")
    r = run("solve", str(path))
    assert r.returncode == 0, r.stderr
    assert "W* (minimax value)" in r.stdout and "1 -> 3 -> 4 -> 9" in r.stdout


@pytest.mark.parametrize(
    ("content", "message"),
    [("{oops", "malformed JSON"), ('{"nodes": [1, 2, 3], "edges": [[1, 2]]}', "malformed")],
)
def test_bad_input_exit_code_2_one_line(tmp_path, content, message):
    path = tmp_path / "bad.json"
    path.write_text(content)
    r = run("solve", str(path))
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0] and "bad.json" in lines[0]


def test_missing_file_exit_code_2(tmp_path):
    r = run("solve", str(tmp_path / "none.json"))
    assert r.returncode == 2 and "none.json" in r.stderr


def test_graph_state_limit_flag_exists_and_is_named_in_the_error():
    from pathlib import Path

    pump = Path(__file__).resolve().parents[2] / "examples" / "vacuum_pump"
    r = run("graph", str(pump), "--max-states", "10")
    assert r.returncode == 2
    assert "exceeds the limit of 10 states" in r.stderr and "--max-states N" in r.stderr
