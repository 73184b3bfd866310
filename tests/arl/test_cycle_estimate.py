"""The size check before training (issue 26 item 11): a cycle's seconds estimated from a
short sample, said before training, and a game over ``--max-cycle-seconds`` refused before
the run folder is touched."""

from __future__ import annotations

import itertools
import threading

import pytest

import arl.pace as pace
import arl.trainer as trainer
from arl import get_config, train
from asmplan.cli.app import main
from asp.errors import GameError
from asp.game.io import save_dag
from tests.arl.graphs import figure4

pytestmark = pytest.mark.usefixtures("deterministic_torch")

TINY = get_config("fast").replace(name="tiny", n_envs=16, n_steps=16, phase_steps=256, max_cycles=3)
PAPERISH = get_config("paper").replace(n_steps=512, phase_steps=1000, max_cycles=2)


@pytest.fixture
def clock(monkeypatch):
    """Every reading of the trainer's clock is one second after the last; a tabulation
    takes 2 s."""
    ticks = itertools.count()
    monkeypatch.setattr(trainer.time, "perf_counter", lambda: float(next(ticks)))
    monkeypatch.setattr(trainer, "tabulation_seconds", lambda *_: 2.0)


@pytest.mark.parametrize(
    ("cfg", "sample", "rollouts", "opponent"),
    [
        # 16 games x 16 steps a rollout: the sample is 256 steps (16 x 16, capped at 256),
        # a phase of 256 steps is one rollout; vectorised: the opponent tabulated per phase
        (TINY, 256, 1, 2.0),
        # one game, rollouts of 512 steps: a sample of 256; 1000 steps are 2 rollouts
        (PAPERISH, 256, 2, 0.0),
    ],
)
def test_a_cycle_is_every_learner_s_phase_and_tabulations(clock, cfg, sample, rollouts, opponent):
    est = trainer.estimate_cycle(figure4(), cfg)
    assert est.sample_steps == sample and est.step_s == 1.0 / sample
    phase = rollouts * cfg.n_steps * cfg.n_envs * est.step_s
    assert est.seconds == pytest.approx(2 * (phase + opponent + 2.0))  # both sides learn
    assert est.cycles == cfg.max_cycles
    assert est.size == f"{figure4().n_nodes:,} nodes, {figure4().n_edges:,} edges"
    text = est.text()
    assert "a cycle" in text and f"for {cfg.max_cycles} cycles" in text and "\n" not in text


@pytest.mark.parametrize(
    ("seconds", "text"),
    [
        (0.04, "40 ms"),
        (0.4, "0.4 s"),
        (12.3, "12 s"),
        (450, "450 s"),
        (900, "15.0 min"),
        (4 * 3600, "4.0 h"),
    ],
)
def test_durations_read_as_a_person_says_them(seconds, text):
    assert pace.duration(seconds) == text


def test_a_slow_game_is_refused_before_the_run_folder_is_touched(tmp_path):
    run = tmp_path / "run"
    run.mkdir()
    (run / "notes.txt").write_text("keep")
    with pytest.raises(GameError, match="over --max-cycle-seconds 1e-06") as info:
        train(figure4(), TINY, seed=0, output=run, max_cycle_seconds=1e-6)
    assert "\n" not in str(info.value) and "a cycle" in str(info.value)
    assert sorted(p.name for p in run.iterdir()) == ["notes.txt"]


def test_within_the_limit_the_estimate_is_said_once_and_training_runs():
    seen = []
    result = train(
        figure4(),
        TINY.replace(max_cycles=1),
        seed=0,
        max_cycle_seconds=1e6,
        on_estimate=seen.append,
    )
    assert len(seen) == 1 and seen[0].seconds > 0 and len(result.cycles) == 1


def test_cli_says_the_estimate_and_refuses_over_the_flag(tmp_path, capsys):
    graph = save_dag(figure4(), tmp_path / "g.json")
    run = tmp_path / "run"
    argv = ["train", str(graph), "--config", "fast", "--output", str(run), "--no-progress"]
    with pytest.raises(SystemExit) as info:
        main([*argv, "--max-cycles", "1"])
    assert info.value.code == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert [line for line in err if line.startswith("training: about ")], err
    with pytest.raises(SystemExit) as info:
        main([*argv, "--max-cycle-seconds", "0.001", "--output", str(tmp_path / "slow")])
    assert info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--max-cycle-seconds 0.001" in err[0], err
    assert not (tmp_path / "slow").exists() or not any((tmp_path / "slow").iterdir())


def test_the_heartbeat_says_what_the_run_is_doing(monkeypatch):
    lines, doing, said = [], [], threading.Event()
    monkeypatch.setattr(pace, "HEARTBEAT_S", 0.001)

    def say(line):
        lines.append(line)
        said.set()

    def at_each_phase(run, learner, *args, **kwargs):
        doing.append(run.doing)
        said.clear()
        assert said.wait(10)  # the heartbeat speaks while the phase runs
        return []

    monkeypatch.setattr(trainer, "_train_phase", at_each_phase)
    train(figure4(), TINY.replace(max_cycles=2), seed=0, heartbeat=say)
    assert doing == [
        f"cycle {c} of 2: the {side}'s phase" for c in (1, 2) for side in ("robot", "human")
    ]
    assert any("the robot's phase" in line for line in lines)
    assert all(line.startswith("training: ") and line.endswith(" so far") for line in lines)
