"""Tabulate a learned policy: one forward pass over all nodes.

A policy over a game DAG with ``n`` nodes is small enough to hold as a table. The trainer
tabulates the frozen opponent once per phase (instead of a network call per step) and the
greedy policies after each cycle (for the exact metrics of :mod:`asp.game.solve`).
"""

from __future__ import annotations

import time

import numpy as np
import torch

from arl.envs import Observer
from arl.moves import NO_MOVE, GameTables


def action_probabilities(model, tables: GameTables, player: int, observer: Observer) -> np.ndarray:
    """(n, max_moves) float64: the model's action distribution at every node.

    Invalid actions get probability 0 (the rest renormalised); rows of nodes where
    ``player`` has no move are all zero.

    Parameters
    ----------
    model : SB3 ``PPO`` or sb3-contrib ``MaskablePPO``
    tables : GameTables
    player : int
        The side ``model`` plays (``ROBOT`` or ``HUMAN``).
    observer : Observer
        Maps nodes to the model's observations.
    """
    rows = tabulation_chunk(tables.n, observer)
    parts = [
        _chunk(model, observer, lo, min(lo + rows, tables.n)) for lo in range(0, tables.n, rows)
    ]
    probs = np.concatenate(parts) if parts else np.zeros((0, tables.max_moves))
    mask = tables.masks(player)
    probs = np.where(mask, probs.astype(np.float64), 0.0)
    total = probs.sum(axis=1, keepdims=True)
    uniform = mask / np.maximum(mask.sum(axis=1, keepdims=True), 1)
    return np.where(total > 0, probs / np.where(total > 0, total, 1.0), uniform)


def _chunk(model, observer: Observer, lo: int, hi: int) -> np.ndarray:
    """(hi - lo, max_moves) float32: the model's action probabilities at nodes ``lo:hi``
    (invalid actions not masked)."""
    policy = model.policy
    with torch.no_grad():
        obs_tensor, _ = policy.obs_to_tensor(observer.batch(np.arange(lo, hi)))
        return policy.get_distribution(obs_tensor).distribution.probs.cpu().numpy()


def tabulation_seconds(model, tables: GameTables, observer: Observer) -> float:
    """The seconds of a tabulation over all nodes (:func:`action_probabilities`), from
    its first chunk timed (every chunk but the last has as many nodes)."""
    rows = tabulation_chunk(tables.n, observer)
    t0 = time.perf_counter()
    _chunk(model, observer, 0, min(rows, tables.n))
    return (time.perf_counter() - t0) * -(-tables.n // rows)


CHUNK_CELLS = 1 << 26
"""Observation cells (floats) fed to the network at once: 256 MB of float32."""


def tabulation_chunk(n: int, observer: Observer) -> int:
    """Nodes per forward pass, so the batch of observations stays within :data:`CHUNK_CELLS`.

    A ``node`` observation is one-hot over all ``n`` nodes inside the network, so a pass
    over every node at once would need ``n * n`` floats (40 GB at 100,000 nodes).
    """
    width = n if observer.features is None else observer.features.shape[1]
    return max(1, min(n, CHUNK_CELLS // max(width, 1)))


def greedy_policy(probs: np.ndarray, tables: GameTables, player: int) -> np.ndarray:
    """(n,) int64 edge indices of the most probable valid action (``NO_MOVE`` where none).

    Ties go to the lower action index.
    """
    return tables.to_edges(player, probs.argmax(axis=1)).astype(np.int64)


def tabulate(model, tables: GameTables, player: int, observer: Observer) -> np.ndarray:
    """The greedy policy of ``model`` as (n,) edge indices (``NO_MOVE`` where no move)."""
    return greedy_policy(action_probabilities(model, tables, player, observer), tables, player)


__all__ = ["NO_MOVE", "action_probabilities", "greedy_policy", "tabulate", "tabulation_seconds"]
