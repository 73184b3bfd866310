"""Scholl's .IN2 precedence graphs (Scholl 1993) as assemblies open to either side."""

from __future__ import annotations

import json

import pytest

from asp.game.solve import solve
from asp.graph.game_dag import game_dag
from asp.graph.state_graph import build_state_graph
from asp.salbp import read_in2
from asp.spec import load_spec
from tests.asp.helpers_assembly import brute_force_downsets, brute_force_sequences

# name: tasks, precedence pairs, states, transitions
SIZES = {
    "MERTENS": (7, 22, 39),
    "BOWMAN8": (8, 16, 22),
    "JAESCHKE": (9, 18, 27),
    "JACKSON": (11, 52, 112),
    "MITCHELL": (21, 200, 557),
    "SAWYER30": (30, 3996, 16580),
}


@pytest.mark.parametrize("name", sorted(SIZES))
def test_state_graph_sizes_and_tct(shared_data, name):
    n, states, transitions = SIZES[name]
    path = shared_data / "salbp" / f"{name}.IN2"
    inst = read_in2(path)
    assert inst.n_tasks == n
    graph = build_state_graph(load_spec(path))
    assert (graph.n_states, graph.n_transitions) == (states, transitions)
    steps = solve(game_dag(graph))
    assert steps.tct == steps.minimax == n
    timed = solve(game_dag(graph, cost="time"))
    assert timed.tct == sum(inst.times)


@pytest.mark.parametrize("name", ["MERTENS", "BOWMAN8", "JAESCHKE"])
def test_counts_match_brute_force(shared_data, name):
    inst = read_in2(shared_data / "salbp" / f"{name}.IN2")
    pairs = [(i - 1, j - 1) for i, j in inst.precedences]
    graph = build_state_graph(load_spec(shared_data / "salbp" / f"{name}.IN2"))
    assert graph.n_states == brute_force_downsets(inst.n_tasks, pairs)
    if inst.n_tasks <= 8:
        assert graph.count_sequences() == brute_force_sequences(inst.n_tasks, pairs)


def test_reader_details(shared_data):
    inst = read_in2(shared_data / "salbp" / "JACKSON.IN2")
    assert inst.times == (6, 2, 5, 7, 1, 2, 3, 6, 5, 5, 4)
    assert inst.precedences[:3] == ((1, 2), (1, 3), (1, 4))
    spec = load_spec(shared_data / "salbp" / "JACKSON.IN2")
    assert spec.operation("7").after == ("3", "4", "5")
    assert spec.agents[0].side == "any" and "Scholl (1993)" in spec.credit


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("x\n", "line 1: expected the number of tasks"),
        ("2\n3\n", "unexpected end of file"),
        ("2\n3\n4\n1,3\n", r"line 4: task 3 is not in 1\.\.2"),
        ("2\n3\n4\n1;2\n", "line 4: expected 'i,j'"),
        ("2\n3\n4\n1,2\n2,1\n-1,-1\n", "cyclic predecessors"),
        ("2\n3\n-4\n", "negative task time"),
    ],
)
def test_reader_errors(tmp_path, text, message):
    path = tmp_path / "BAD.IN2"
    path.write_text(text)
    with pytest.raises(ValueError, match=message):
        load_spec(path)


def test_text_after_end_mark_is_ignored(tmp_path):
    path = tmp_path / "T.IN2"
    path.write_text("2\r\n3\r\n4\r\n1,2\r\n-1,-1\r\n\r\nSome source (1960)\r\n")
    assert read_in2(path).precedences == ((1, 2),)


def test_cli_graph_lists_the_sequence_table(shared_data):
    from typer.testing import CliRunner

    from asmplan.cli import app

    result = CliRunner().invoke(
        app, ["graph", str(shared_data / "salbp" / "JACKSON.IN2"), "--list", "5"]
    )
    assert result.exit_code == 0, result.output
    data = json.loads(result.output)
    table = data["sequence_table"]
    assert len(table) == 5 and len({tuple(s) for s in table}) == 5
    assert all(sorted(s, key=int) == [str(i) for i in range(1, 12)] for s in table)
    assert data["sequences"] == 756
