"""Alternating PPO on the concurrent game's rules: seeded, saved, certified exactly."""

from __future__ import annotations

import json

import pytest

from arl.concurrent_trainer import (
    ConcurrentConfig,
    get_config,
    learned_policy,
    load_robot,
    train_concurrent,
)
from asp.concurrent.certify import certify
from asp.concurrent.search import Search
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
