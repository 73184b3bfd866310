"""Alternating PPO on the concurrent game's rules: seeded, saved, certified exactly."""

from __future__ import annotations

import itertools
import json

import pytest

import arl.concurrent_trainer as concurrent_trainer
import arl.pace as pace
from arl.concurrent_trainer import (
    ConcurrentConfig,
    get_config,
    learned_policy,
    load_robot,
    train_concurrent,
)
from asp.concurrent.certify import certify
from asp.concurrent.search import Search
from asp.errors import GameError
from tests.arl.test_concurrent_env import small_rules


def without_times(cycles: list[dict]) -> list[dict]:
    return [{k: v for k, v in c.items() if k != "seconds"} for c in cycles]


@pytest.mark.slow
def test_a_seeded_run_is_repeatable_saved_and_certified_exactly(tmp_path):
    rules = small_rules()
    budgets = [0, 1, None]
    run = train_concurrent(rules, "concurrent-tiny", seed=3, budgets=budgets, output=tmp_path)
    again = train_concurrent(rules, "concurrent-tiny", seed=3, budgets=budgets)
    assert without_times(run.cycles) == without_times(again.cycles)
    assert run.steps == 2 * 2 * 64  # 2 cycles, 2 sides, 64 steps each
    # The best cycle's certificate is the least one, and the saved robot has it.
    best = min(c["certified"][-1]["bound"] for c in run.cycles)
    assert run.certified[None] == best
    robot = load_robot(tmp_path)
    assert certify(rules, learned_policy(rules, robot), budgets).worst == run.certified
    # No robot beats the game's value; a budget-blind robot never gets better with k.
    search = Search(rules)
    for b in budgets:
        assert run.certified[b] * rules.scale >= search.value(b)
    assert run.certified[0] <= run.certified[1] <= run.certified[None]
    log = json.loads((tmp_path / "log.json").read_text())
    assert log["best_cycle"] == run.best_cycle and len(log["cycles"]) == 2
    config = json.loads((tmp_path / "config.json").read_text())
    assert ConcurrentConfig.from_dict(config["config"]) == get_config("concurrent-tiny")


def test_configs_and_folders_are_checked(tmp_path):
    with pytest.raises(ValueError, match="config: expected one of"):
        get_config("huge")
    with pytest.raises(ValueError, match="cycles"):
        ConcurrentConfig(cycles=0)
    with pytest.raises(ValueError, match="train_budgets"):
        ConcurrentConfig(train_budgets=(-1,))
    with pytest.raises(ValueError, match="unknown fields"):
        ConcurrentConfig.from_dict({"speed": 1})
    with pytest.raises(ValueError, match="not a concurrent run folder"):
        load_robot(tmp_path)


# ------------------------------------------- the size check before training (issue 26 item 11)


def test_a_cycle_is_both_phases_and_a_certification(monkeypatch):
    """Every reading of the clock is one second after the last: a step of the sample is
    1/k s, the certification (which reads no clock here) 1 s."""
    ticks = itertools.count()
    monkeypatch.setattr(concurrent_trainer.time, "perf_counter", lambda: float(next(ticks)))
    monkeypatch.setattr(concurrent_trainer, "certify", lambda *_, **__: None)
    cfg = get_config("concurrent-tiny")
    est = concurrent_trainer.estimate_cycle(small_rules(), cfg, budgets=[0, None])
    k = min(cfg.n_steps, pace.SAMPLE_STEPS)
    assert est.sample_steps == k and est.step_s == 1.0 / k and est.check_s == 1.0
    rollouts = -(-cfg.phase_steps // cfg.n_steps)
    assert est.seconds == pytest.approx(2 * rollouts * cfg.n_steps / k + 1.0)
    assert est.cycles == cfg.cycles and est.size.endswith(" workers")
    text = est.text()
    assert "a certification (exact best response)" in text and "\n" not in text


def test_a_slow_concurrent_game_is_refused_before_the_folder_is_touched(tmp_path):
    run = tmp_path / "run"
    run.mkdir()
    (run / "notes.txt").write_text("keep")
    with pytest.raises(GameError, match="over --max-cycle-seconds 1e-06") as info:
        train_concurrent(small_rules(), "concurrent-tiny", output=run, max_cycle_seconds=1e-6)
    assert "\n" not in str(info.value) and "a cycle" in str(info.value)
    assert sorted(p.name for p in run.iterdir()) == ["notes.txt"]


@pytest.mark.slow
def test_the_estimate_changes_no_result_and_the_heartbeat_says_each_step(monkeypatch):
    rules = small_rules()
    seen, lines = [], []
    monkeypatch.setattr(pace, "HEARTBEAT_S", 0.001)
    plain = train_concurrent(rules, "concurrent-tiny", seed=3, budgets=[0, None])
    paced = train_concurrent(
        rules,
        "concurrent-tiny",
        seed=3,
        budgets=[0, None],
        max_cycle_seconds=1e6,
        on_estimate=seen.append,
        heartbeat=lines.append,
    )
    assert len(seen) == 1 and seen[0].seconds > 0
    assert without_times(paced.cycles) == without_times(plain.cycles)
    assert lines and all(x.startswith("training: ") and x.endswith(" so far") for x in lines)
    said = {x.split(", ")[0] for x in lines}
    assert said <= {
        "training: starting",
        "training: estimating a cycle's time (a sample of steps",
        *(f"training: cycle {c} of 2: the {s}'s phase" for c in (1, 2) for s in ("robot", "human")),
        *(f"training: cycle {c} of 2: a certification (exact best response)" for c in (1, 2)),
    }, said


def test_the_memory_limit_reaches_the_state_graph_learners_and_certificates(monkeypatch):
    """Issue 26 item 3: train_concurrent refuses learners over max_memory_gb before any
    work, and hands each certificate's policy game the bytes left."""
    import arl.memory as memory
    from arl.concurrent_env import Encoder

    rules = small_rules()
    cfg = get_config("concurrent-tiny")
    with pytest.raises(GameError, match="--max-memory limit of 0.5 GB") as info:
        train_concurrent(rules, cfg, max_memory_gb=0.5)
    assert "\n" not in str(info.value)
    room = memory.concurrent_training_room(Encoder(rules).size, cfg, 2.0)
    assert 0 < room < 2 << 30
    given = []

    def spy(*args, max_memory=None, **kwargs):
        given.append(max_memory)
        return certify(*args, max_memory=max_memory, **kwargs)

    monkeypatch.setattr(concurrent_trainer, "certify", spy)
    train_concurrent(rules, cfg.replace(cycles=1), budgets=[0], max_memory_gb=2.0)
    assert given == [room]


# ------------------------------------ past the exact size: the budgets that fit (issue 23 item 3)


def test_a_policy_game_too_large_drops_the_largest_budgets_first(monkeypatch, tmp_path):
    """certify_fitting: k = inf goes first, then the largest k; what is kept is exactly
    certify's certificate at the budgets kept; nothing fitting is an error."""
    from asp.errors import GameLimit

    rules = small_rules()
    robot, _ = concurrent_trainer._learners(rules, get_config("concurrent-tiny"), 0)
    choose = learned_policy(rules, robot)
    full = certify(rules, choose, [0, 1, None])

    def fits(budgets, most):
        try:
            certify(rules, choose, budgets, max_nodes=most)
        except GameLimit:
            return False
        return True

    # The largest node limit at which all three budgets do not fit but k = 0 alone does.
    most = max(m for m in range(1, full.nodes) if fits([0], m) and not fits([0, 1, None], m))
    said = []
    cert, kept = concurrent_trainer.certify_fitting(
        rules, choose, [None, 1, 0], max_nodes=most, say=said.append
    )
    assert kept in ([0], [0, 1])
    assert cert.worst == {b: full.worst[b] for b in kept}
    assert said[0].startswith("k = inf not certified (") and "\n" not in said[0]
    with pytest.raises(GameLimit):
        concurrent_trainer.certify_fitting(rules, choose, [0, None], max_nodes=1)
    # A run drops k = inf for good (here: a certificate refusing it), ranks by the largest
    # budget left and saves those.
    asked = []

    def no_inf(rules, choose, budgets, **kwargs):
        asked.append(list(budgets))
        if None in budgets:
            raise GameLimit("the policy game exceeds 1 nodes")
        return certify(rules, choose, budgets, **kwargs)

    monkeypatch.setattr(concurrent_trainer, "certify", no_inf)
    run = train_concurrent(
        rules, get_config("concurrent-tiny"), budgets=[0, 1, None], seed=1, output=tmp_path
    )
    assert asked == [[0, 1, None], [0, 1], [0, 1]]  # cycle 1 tries k = inf once
    assert sorted(run.certified) == [0, 1]
    assert all([r["k"] for r in c["certified"]] == [0, 1] for c in run.cycles)
    config = json.loads((tmp_path / "config.json").read_text())
    assert config["budgets"] == [0, 1]
    # With the estimate first, its certificate drops k = inf and the cycles never retry it.
    asked.clear()
    train_concurrent(
        rules, get_config("concurrent-tiny"), budgets=[0, 1, None], seed=1, max_cycle_seconds=1e6
    )
    assert asked == [[0, 1, None], [0, 1], [0, 1], [0, 1]]
