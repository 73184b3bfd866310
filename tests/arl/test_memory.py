"""The size check before training: refuse a game too large for memory, before any work."""

from __future__ import annotations

import pytest

from arl.config import get_config
from arl.memory import check_training_size, training_bytes
from arl.trainer import train
from asp.game.synth import synthetic_dag


@pytest.mark.parametrize("name", ["paper", "fast"])
def test_estimate_grows_with_the_graph(name):
    cfg = get_config(name)
    small = training_bytes(1_000, 3_000, 4, cfg)
    big = training_bytes(1_000_000, 3_000_000, 4, cfg)
    assert small < big
    # One-hot node observations: the first layers alone are 2 x 2 x n x h x 16 bytes.
    assert big - small >= 2 * 2 * (1_000_000 - 1_000) * cfg.net_arch[0] * 16


def test_over_the_limit_is_one_line_naming_the_size_and_the_option(tmp_path):
    dag = synthetic_dag(10, 10, 4, 0)
    with pytest.raises(ValueError, match=r"--max-memory") as info:
        train(dag, "fast", output=tmp_path / "run", max_memory_gb=0.01)
    message = str(info.value)
    assert "\n" not in message and f"{dag.n_nodes:,} nodes" in message
    assert not (tmp_path / "run").exists()  # refused before anything was written
    check_training_size(dag, get_config("fast"), max_memory_gb=64)  # fits


def test_fast_on_the_concurrent_game_uses_32_steps():
    assert get_config("fast", "concurrent").n_steps == 32
    assert get_config("fast").n_steps == get_config("fast", "alternate").n_steps == 16
    assert get_config("paper", "concurrent") == get_config("paper")


def test_the_default_limit_is_the_one_memory_rule(monkeypatch):
    """Issue 26 item 3: without --max-memory, training may use asp.heap.memory_budget (3/4 of
    the memory available now, not of the machine's physical memory), and the refusal says
    the estimate, the limit, the memory available and the flag."""
    from asp import heap

    dag = synthetic_dag(10, 10, 4, 0)
    cfg = get_config("fast")
    need = training_bytes(dag.n_nodes, dag.n_edges, 4, cfg)
    monkeypatch.setattr(heap, "available_memory", lambda: int(need))  # 3/4 of it: too little
    with pytest.raises(ValueError, match=r"--max-memory") as info:
        check_training_size(dag, cfg)
    message = str(info.value)
    assert "\n" not in message
    gb = 2**30
    assert f"about {need / gb:.1f} GB" in message
    assert f"the {heap.memory_budget() / gb:.1f} GB limit" in message
    assert f"({need / gb:.1f} GB available)" in message
    monkeypatch.setattr(heap, "available_memory", lambda: int(2 * need))  # 3/4 of it fits
    check_training_size(dag, cfg)
