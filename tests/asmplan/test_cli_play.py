"""``asmplan play``: scripted moves, piped input (bad input, help, quit), EOF, the pump."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

import asmplan.cli.play  # noqa: F401  registers the command
from asmplan.cli.app import app, main
from asp.game.io import save_dag
from tests.asp.figures import figure4

PUMP = Path(__file__).resolve().parents[2] / "examples" / "vacuum_pump"
runner = CliRunner()


@pytest.fixture
def fig4(tmp_path) -> Path:
    return save_dag(figure4(), tmp_path / "figure4.json")


def _play(*args, input=None):
    return runner.invoke(app, ["play", *map(str, args)], input=input)


def test_scripted_human_game(fig4):
    result = _play(fig4, "--moves", "2", input="")
    assert result.exit_code == 0, result.output
    out = result.output
    assert "TCT 2, W* 3" in out
    assert "robot: moves -> node 3 [cost 1]: keeps the worst case at 3" in out
    assert "would allow up to 5" in out
    assert "your move [1-2, ? help, q quit]: 2 (scripted)" in out
    assert "you (human): moves -> node 5" in out
    assert "total cost 3" in out
    assert "the robot's guarantee held: cost 3 <= W* 3" in out


def test_the_move_table_shows_the_worst_case_of_each_move(fig4):
    out = _play(fig4, "--as", "robot", input="q\n").output
    rows = re.findall(r"^\s+(\d)\s+to node (\d)\s+1\s+\d\s+(\d)\s+(\d)$", out, re.M)
    assert rows == [("1", "2", "5", "2"), ("2", "3", "3", "3")]


def test_piped_input_with_bad_input_help_and_a_move(fig4):
    result = _play(fig4, input="x\n9\n?\n\n1\n")
    assert result.exit_code == 0, result.output
    out = result.output
    assert out.count("please type a number from 1 to 2") == 3
    assert "How to play" in out
    assert "you (human): moves -> node 4" in out
    assert "guarantee held" in out


def test_q_quits_cleanly(fig4):
    result = _play(fig4, input="q\n")
    assert result.exit_code == 0
    assert "game not finished (quit after 1 turn): cost so far 1" in result.output
    assert "guarantee" not in result.output


def test_eof_quits_cleanly(fig4):
    result = _play(fig4, input="")
    assert result.exit_code == 0
    assert "end of input: quitting" in result.output
    assert "game not finished" in result.output


def test_as_robot_against_the_best_response_human(fig4):
    result = _play(fig4, "--as", "robot", "--moves", "1,1,1")
    assert result.exit_code == 0, result.output
    out = result.output
    assert "against a best-response human" in out
    assert "(that raises the worst case to 5, +2)" in out
    assert "human: moves -> node 6 [cost 1]: delays as much as it can" in out
    assert "total cost 5" in out
    assert "your choices cost 2 more" in out
    assert "step 1: to node 2 raised the worst case by 2" in out


def test_fast_greedy_robot(fig4):
    out = _play(fig4, "--robot", "fast-greedy", "--moves", "2,1,1").output
    assert "cooperative fastest path" in out
    assert "the fast-greedy robot's certified worst case: 5 (W* 3)" in out
    assert "total cost 5" in out


def test_passes_are_announced(tmp_path):
    from asp.game.dag import HUMAN, ROBOT, from_edges

    dag = from_edges(
        ["a", "b", "c"], [("a", "b"), ("b", "c")], sides=[HUMAN, ROBOT], operations=["o1", "o2"]
    )
    path = save_dag(dag, tmp_path / "sided.json")
    out = _play(path, "--moves", "1").output
    assert "step 1: robot at node a has no move it may do: passes at zero cost" in out
    assert "robot: o2 -> node c" in out


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--moves", "3"], "--moves: move 3 at step 2: expected 1 to 2"),
        (["--moves", "1,x"], "--moves: expected comma-separated move numbers"),
        (["--robot", "nowhere"], "--robot: expected robust or fast-greedy or a run folder"),
        (["--as", "robot", "--robot", "fast-greedy"], "--robot applies when you play the human"),
        (["--cost", "time"], "--cost applies to assemblies only"),
    ],
)
def test_bad_options_exit_2_with_one_line(fig4, capsys, args, message):
    with pytest.raises(SystemExit) as exc:
        main(["play", str(fig4), *args])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("asmplan: error: ") and message in err and err.count("\n") == 1


def test_missing_source_exits_2(tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["play", str(tmp_path / "nope.json")])
    assert exc.value.code == 2
    assert "no such file" in capsys.readouterr().err


def test_pump_scripted_game_keeps_the_guarantee():
    result = _play(PUMP, "--moves", ",".join(["1", "2"] + ["1"] * 30))
    assert result.exit_code == 0, result.output
    out = result.output
    assert "vacuum pump: game DAG (time)" in out
    assert "[start R1.bit=hex]" in out
    assert "robot at node 0 has no move it may do: passes at zero cost" in out
    assert "1.1 H Confirm start of R2 movement" in out
    total = float(re.search(r"total cost ([\d.]+)", out).group(1))
    w_star = float(re.search(r"W\* \(robust minimax\) ([\d.]+)", out).group(1))
    assert total <= w_star
    assert "the robot's guarantee held" in out


def test_pump_as_robot_steps_cost():
    result = _play(PUMP, "--as", "robot", "--cost", "steps", "--moves", ",".join(["1"] * 30))
    assert result.exit_code == 0, result.output
    assert "game DAG (steps)" in result.output
    assert "game over after" in result.output


def test_robot_from_a_trained_run(fig4, tmp_path):
    from arl import get_config, train
    from asp.game.io import load_dag

    tiny = get_config("fast").replace(
        name="tiny", n_envs=16, n_steps=16, phase_steps=256, max_cycles=2
    )
    run = tmp_path / "run"
    trained = train(load_dag(fig4), tiny, seed=0, output=run)
    result = _play(fig4, "--robot", run, "--moves", "1,1,1,1")
    assert result.exit_code == 0, result.output
    out = result.output
    assert "against the trained (run) robot" in out
    assert "the trained (run) policy's choice" in out
    assert f"certified worst case: {trained.certified_wcpl:g} (W* 3)" in out
    assert "the robot's guarantee held" in out


def test_an_alike_part_may_be_typed_by_its_id(monkeypatch, tmp_path):
    """An assembly's game knows one order of its alike pins: the moves show the physical
    ones with those as good, and typing any of them plays the plan's move."""
    from asmplan import pipeline
    from asp.graph.game_dag import game_dag
    from asp.graph.symmetry import reduced_state_graph
    from tests.asp.graph.test_symmetry import pinned_disc

    spec, rel = pinned_disc(3, 2)
    graph = reduced_state_graph(spec, rel)
    game = pipeline.Game(game_dag(graph, cost="time"), {}, graph.model.interchangeable)
    monkeypatch.setattr(pipeline, "load_game", lambda source, cost=None: game)
    result = _play(tmp_path, input="pin2\nzz\nq\n")
    assert result.exit_code == 0, result.output
    out = result.output
    assert "pin0 H (or alike: pin1, pin2)" in out
    assert "you (human): pin2 H" in out
    assert "robot: pin1 R" in out  # the robot's next pin is a physical one still missing
    assert "please type a number from 1 to 1 (or an operation id)" in out
