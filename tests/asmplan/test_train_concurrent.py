"""Learning in the concurrent game (issue 13, part 5): the Gymnasium and PettingZoo forms
and `asmplan train` / `evaluate` on the vacuum pump, certified by the exact best response."""

import json

import numpy as np
import pytest

from arl.envs import RobotEnv
from arl.pettingzoo_env import GameAEC
from arl.trainer import load_policies
from asmplan import pipeline
from asmplan.cli.app import main
from asp.concurrent.build import build_game
from asp.concurrent.model import concurrent_model
from asp.concurrent.robustness import certified_worst_case, robustness
from asp.game.io import save_dag
from tests.conftest import REPO

PUMP = REPO / "examples" / "vacuum_pump"


@pytest.fixture(scope="module")
def pump():
    """The pump's concurrent game against the unbounded adversary, and its curve."""
    assembly = pipeline.load(PUMP)
    model = concurrent_model(assembly.spec, pipeline.state_graph(assembly))
    return build_game(model, None), robustness(model)


def test_envs_play_the_concurrent_game(pump):
    game, curve = pump
    dag = game.dag
    rng = np.random.default_rng(0)
    for _ in range(5):  # PettingZoo: both sides random; the makespan is the human's reward
        env = GameAEC(dag)
        env.reset(seed=int(rng.integers(1 << 30)))
        total = 0.0
        for _agent in env.agent_iter():
            obs, _, terminated, truncated, _ = env.last()
            if terminated or truncated:
                env.step(None)
                continue
            env.step(int(rng.choice(np.flatnonzero(obs["action_mask"]))))
            total += env.rewards["human"]
        assert total >= curve.bounds[0] - 1e-9  # no schedule beats the cooperative optimum
    env = RobotEnv(dag, reward="zero_sum")  # Gymnasium, against a random human
    _, info = env.reset(seed=1)
    done, makespan = False, 0.0
    while not done:
        action = int(rng.choice(np.flatnonzero(env.action_masks())))
        _, reward, done, _, info = env.step(action)
        makespan -= reward
    assert makespan >= curve.bounds[0] - 1e-9


@pytest.mark.usefixtures("deterministic_torch")
def test_fast_training_on_the_pump_is_certified_robust_optimal(pump, tmp_path, capsys):
    game, curve = pump
    run = tmp_path / "run"
    argv = f"train {PUMP} --turn-model concurrent --config fast --output {run} --no-progress"
    with pytest.raises(SystemExit) as exit_info:
        main(argv.split())
    assert exit_info.value.code == 0
    assert "(robust-optimal)" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        main(
            ["evaluate", str(PUMP), "--turn-model", "concurrent", "--model", str(run)]
            + ["--format", "json", "--games", "100"]
        )
    metrics = json.loads(capsys.readouterr().out)
    robot, _ = load_policies(game.dag, run)
    exact = certified_worst_case(game, robot)  # the exact best response of asp.concurrent
    assert metrics["certified_wcpl"] == exact == metrics["minimax"] == curve.unbounded
    assert metrics["robust_optimal"]


def test_concurrent_needs_an_assembly_and_zero_sum_rewards(pump, tmp_path, capsys):
    graph = save_dag(pump[0].dag, tmp_path / "g.json")
    for argv, message in (
        (f"train {graph} --turn-model concurrent", "needs an assembly"),
        (f"train {PUMP} --turn-model concurrent --config paper", "fast config"),
    ):
        with pytest.raises(SystemExit) as exit_info:
            main([*argv.split(), "--output", str(tmp_path / "run"), "--no-progress"])
        assert exit_info.value.code == 2
        assert message in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.usefixtures("deterministic_torch")
def test_train_config_concurrent_plays_the_rules_and_certifies(tmp_path, capsys):
    run = tmp_path / "run"
    argv = f"train {PUMP} --turn-model concurrent --config concurrent-tiny --max-cycles 1"
    with pytest.raises(SystemExit) as exit_info:
        main([*argv.split(), "--output", str(run), "--no-progress"])
    assert exit_info.value.code == 0
    captured = capsys.readouterr()
    out = captured.out
    assert "certified (exact best response) at k=0: " in out and "k=inf: " in out
    estimate = [x for x in captured.err.splitlines() if x.startswith("training: about ")]
    assert len(estimate) == 1 and "a certification (exact best response)" in estimate[0]
    log = json.loads((run / "log.json").read_text())
    assert len(log["cycles"]) == 1 and (run / "robot.zip").is_file()
    # evaluate certifies the saved robot again, without compiling the game.
    with pytest.raises(SystemExit) as exit_info:
        main(["evaluate", str(PUMP), "--model", str(run), "--format", "json"])
    assert exit_info.value.code == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["certified"] == log["cycles"][0]["certified"]


def test_train_config_concurrent_needs_the_concurrent_game_of_an_assembly(tmp_path, capsys):
    from tests.arl.graphs import figure4

    graph = save_dag(figure4(), tmp_path / "g.json")
    for argv, message in (
        (f"train {graph} --config concurrent", "needs an assembly"),
        (f"train {PUMP} --turn-model alternate --config concurrent", "--turn-model concurrent"),
    ):
        with pytest.raises(SystemExit) as exit_info:
            main([*argv.split(), "--output", str(tmp_path / "run"), "--no-progress"])
        assert exit_info.value.code == 2
        assert message in capsys.readouterr().err


@pytest.mark.parametrize(
    ("flag", "value", "said"),
    [
        # Issue 26 item 11: the concurrent trainer is estimated and limited as the
        # alternating one is (the same --max-cycle-seconds, the same line).
        (
            "--max-cycle-seconds",
            "0.001",
            ("over --max-cycle-seconds 0.001", "a certification (exact best response)"),
        ),
        # Issue 26 item 3: --max-memory bounds it too (the state graph, the learners, the
        # certificates' policy games): a tiny limit is refused before any work, naming
        # --max-memory, the estimate and the memory available.
        ("--max-memory", "0.001", ("--max-memory limit of 0.001 GB", "needs about", "available")),
    ],
)
def test_train_config_concurrent_refuses_a_run_over_the_flag(tmp_path, capsys, flag, value, said):
    run = tmp_path / "run"
    argv = f"train {PUMP} --turn-model concurrent --config concurrent-tiny --no-progress"
    with pytest.raises(SystemExit) as exit_info:
        main([*argv.split(), flag, value, "--output", str(run)])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and all(text in err[0] for text in said), err
    assert not run.exists() or not any(run.iterdir())


def test_the_concurrent_trainers_state_graph_takes_the_memory_limit():
    from asmplan.cli.train import _concurrent_rules
    from asp.errors import StateLimit

    with pytest.raises(StateLimit, match="the state graph needs more memory than it may use"):
        _concurrent_rules(PUMP, "--config concurrent", 1e-7)
    assert _concurrent_rules(PUMP, "--config concurrent", 1.0).model.n_ops > 0
