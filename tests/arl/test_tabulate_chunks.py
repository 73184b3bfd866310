"""Tabulating a policy over all nodes runs in chunks (issue 14, item 6: a 100,000-node graph
with one-hot node observations tried to allocate n * n floats, 82 GB, in one pass)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import torch

import arl.tabulate as tabulate
from arl.envs import Observer
from arl.moves import GameTables
from asp.game.dag import HUMAN, ROBOT
from asp.game.synth import synthetic_dag


class FakePolicy:
    """Action probabilities a fixed function of the node; records the largest batch."""

    def __init__(self, max_moves: int):
        self.max_moves = max_moves
        self.largest = 0

    def obs_to_tensor(self, obs):
        return torch.as_tensor(obs), None

    def get_distribution(self, obs_tensor):
        self.largest = max(self.largest, int(obs_tensor.shape[0]))
        nodes = obs_tensor.double().reshape(-1, 1)
        logits = torch.sin(nodes * torch.arange(1, self.max_moves + 1, dtype=torch.float64))
        return SimpleNamespace(distribution=SimpleNamespace(probs=torch.softmax(logits, dim=1)))


def test_chunked_tabulation_equals_one_pass(monkeypatch):
    dag = synthetic_dag(6, 6, 3, seed=2)
    tables = GameTables.from_dag(dag)
    observer = Observer(dag, "node")
    for player in (ROBOT, HUMAN):
        whole = FakePolicy(tables.max_moves)
        one_pass = tabulate.action_probabilities(
            SimpleNamespace(policy=whole), tables, player, observer
        )
        assert whole.largest == tables.n
        monkeypatch.setattr(tabulate, "CHUNK_CELLS", 3 * tables.n)  # three nodes a pass
        chunked = FakePolicy(tables.max_moves)
        in_chunks = tabulate.action_probabilities(
            SimpleNamespace(policy=chunked), tables, player, observer
        )
        monkeypatch.undo()
        assert chunked.largest == 3
        np.testing.assert_array_equal(in_chunks, one_pass)


def test_chunk_bounds_the_one_hot_batch():
    observer = SimpleNamespace(features=None)
    rows = tabulate.tabulation_chunk(100_000, observer)
    assert rows * 100_000 <= tabulate.CHUNK_CELLS and rows >= 1
    assert tabulate.tabulation_chunk(10, observer) == 10
