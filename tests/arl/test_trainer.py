"""Alternating PPO: the robust choice on Figure 4, determinism, save/load, resume, CLI."""

import json

import numpy as np
import pytest

from arl import evaluate, get_config, train
from asmplan.cli.app import main
from asp.game.io import save_dag
from asp.game.solve import solve
from tests.arl.graphs import figure4, sided_time_dag

# A smaller `fast` so that each cycle takes a few hundredths of a second.
pytestmark = pytest.mark.usefixtures("deterministic_torch")

TINY = get_config("fast").replace(name="tiny", n_envs=16, n_steps=16, phase_steps=256, max_cycles=3)


def _without_time(cycles):
    return [{k: v for k, v in c.items() if k not in ("wall_s", "elapsed_s")} for c in cycles]


def test_fast_learns_the_robust_choice_on_figure4():
    dag = figure4()
    result = train(dag, "fast", seed=0)
    first = int(dag.targets[result.robot_policy[dag.index_of(1)]])
    assert dag.node_ids[first] == 3
    assert result.certified_wcpl == result.minimax == 3.0
    assert result.robust_optimal and result.converged
    assert set(result.cycles[0]) >= {
        "cycle",
        "robot_mean_reward",
        "human_mean_reward",
        "wcpl",
        "certified_wcpl",
        "wall_s",
        "timesteps",
    }


def test_same_seed_same_cycle_log():
    dag = figure4()
    a = train(dag, TINY.replace(max_cycles=2), seed=3)
    b = train(dag, TINY.replace(max_cycles=2), seed=3)
    assert _without_time(a.cycles) == _without_time(b.cycles)
    assert a.episode_rewards == b.episode_rewards
    assert np.array_equal(a.robot_policy, b.robot_policy)


def test_outputs_round_trip_and_resume(tmp_path):
    dag = sided_time_dag()
    full = train(dag, TINY, seed=1)
    run = tmp_path / "run"
    part = train(dag, TINY.replace(max_cycles=2), seed=1, output=run)
    assert {"robot.zip", "human.zip", "log.json", "rewards.png", "tb"} <= {
        p.name for p in run.iterdir()
    }
    log = json.loads((run / "log.json").read_text())
    assert log["seed"] == 1 and log["config"]["name"] == "tiny" and len(log["cycles"]) == 2
    # Save/load: the saved models tabulate to the same greedy policies.
    metrics = evaluate(dag, run)
    assert metrics["robot_policy"] == part.robot_policy.tolist()
    assert metrics["certified_wcpl"] == part.certified_wcpl
    # Resume continues exactly as the uninterrupted run.
    resumed = train(dag, TINY, seed=1, output=run, resume=True)
    assert _without_time(resumed.cycles) == _without_time(full.cycles)
    assert np.array_equal(resumed.robot_policy, full.robot_policy)
    with pytest.raises(ValueError, match="seed"):
        train(dag, TINY, seed=2, output=run, resume=True)


def test_paper_config_runs_one_cycle_and_callback_stops():
    cfg = get_config("paper")
    assert (cfg.learning_rate, cfg.n_steps, cfg.batch_size, cfg.n_epochs) == (3e-4, 2048, 64, 10)
    assert (cfg.gamma, cfg.gae_lambda, cfg.clip_range, cfg.ent_coef) == (0.99, 0.95, 0.2, 0.0)
    assert (cfg.phase_steps, cfg.window, cfg.tolerance, cfg.max_cycles) == (2048, 5, 0.5, 100)
    small = cfg.replace(n_steps=64, phase_steps=64, n_epochs=1)
    seen = []
    result = train(figure4(), small, seed=0, callback=lambda r: seen.append(r) or False)
    assert len(result.cycles) == len(seen) == 1 and not result.converged
    assert result.certified_wcpl >= solve(figure4()).minimax
    plain = train(sided_time_dag(), small.replace(algo="ppo", max_cycles=1), seed=0)
    assert plain.certified_wcpl >= plain.minimax  # SB3 PPO, invalid actions mapped modulo


def test_cli_train_and_evaluate(tmp_path, capsys):
    import asmplan.cli.train  # noqa: F401  registers the commands

    graph = save_dag(figure4(), tmp_path / "g.json")
    run = tmp_path / "run"
    with pytest.raises(SystemExit) as exit_info:
        main(f"train {graph} --config fast --output {run} --max-cycles 2 --no-progress".split())
    assert exit_info.value.code == 0
    assert "certified wcpl" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        main(["evaluate", str(graph), "--model", str(run), "--format", "json"])
    metrics = json.loads(capsys.readouterr().out)
    keys = "tct minimax wcpl certified_wcpl avg_random max_random rr rr_certified robust_optimal"
    assert set(keys.split()) <= set(metrics)
    with pytest.raises(SystemExit) as exit_info:
        main(["train", str(graph), "--config", "nope", "--output", str(run)])
    assert exit_info.value.code == 2
    assert "expected one of paper, fast" in capsys.readouterr().err


def test_trains_on_an_in2_assembly_with_time_costs(shared_data):
    from asp.graph.game_dag import game_dag
    from asp.graph.state_graph import build_state_graph
    from asp.spec import load_spec

    spec = load_spec(shared_data / "salbp" / "BOWMAN8.IN2")  # Bowman (1960), via Scholl
    dag = game_dag(build_state_graph(spec), cost="time")
    result = train(dag, TINY, seed=0)
    assert len(result.cycles) == TINY.max_cycles
    assert result.certified_wcpl >= result.minimax
    assert evaluate(dag, result.robot_policy)["certified_wcpl"] == result.certified_wcpl


def test_policy_stop_rule_waits_for_min_cycles_and_a_stable_window():
    from arl.trainer import should_stop

    cfg = get_config("fast")
    stable = [{"policy_hash": "a", "wcpl": 5.0}] * (cfg.min_cycles - 1)
    assert cfg.min_cycles > cfg.window
    assert not should_stop(stable, cfg)  # stable for longer than the window, too early
    assert should_stop([*stable, {"policy_hash": "a", "wcpl": 5.0}], cfg)
    changed = [*stable, {"policy_hash": "a", "wcpl": 6.0}]
    assert not should_stop(changed, cfg)  # the greedy-vs-greedy cost moved


def test_a_writer_threads_disk_error_is_raised_in_the_caller_not_printed(capsys):
    """The reliability probe (issue 26): on a full disk TensorBoard's writer thread printed
    an ``OSError`` traceback beside the command's one-line error; the trainer raises it in
    its own thread instead (the command line's error policy makes it one line)."""
    import threading

    from arl.trainer import writer_errors_raised

    def full_disk():
        raise OSError(28, "No space left on device")

    before = threading.excepthook
    with pytest.raises(OSError, match="No space left"), writer_errors_raised():
        worker = threading.Thread(target=full_disk)
        worker.start()
        worker.join()
    assert "Traceback" not in capsys.readouterr().err
    assert threading.excepthook is before
