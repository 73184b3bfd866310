"""How much memory training needs, estimated from the game's size before anything heavy runs.

:func:`train` (and ``asmplan train``) refuses a game whose estimate exceeds the limit with
one line naming the game's size, the estimate and the option that raises the limit
(``--max-memory``, ``max_memory_gb``) and the memory available, before it builds tables,
solves or makes a network. The default limit is the one rule of every build with a memory
bound, :func:`asp.heap.memory_budget` (a share of the memory available when it starts).

The estimate (bytes) adds, for ``n`` nodes, ``E`` edges, ``k`` the most moves at a node and
``w`` the observation width (``n`` for ``obs="node"``, which SB3 feeds one-hot; the feature
count for ``obs="features"``):

- the networks: per learning side a policy and a value network whose first layer is
  ``w x h`` (``h`` the first hidden width), each weight held four times (value, gradient,
  Adam's two moments) in float32: ``2 * 2 * w * h * 16``;
- a minibatch of one-hot observations and its gradient: ``2 * batch * w * 4``, and the
  rollout buffer ``n_steps * n_envs * (w if features else 1) * 4 * 4``;
- the tabulation of a policy (:mod:`arl.tabulate`): a chunk of at most ``CHUNK_CELLS``
  observation floats, and the action probabilities ``n * k * 24`` (float32, float64 and
  the masked copy);
- the game tables and the exact solver: ``n * (2 * k * 9 + 200) + E * 100``;
- the interpreter with torch and SB3 loaded: :data:`BASE_BYTES`.
"""

from __future__ import annotations

import numpy as np

from arl.config import TrainConfig
from arl.tabulate import CHUNK_CELLS
from asp import heap
from asp.errors import GameError

BASE_BYTES = 2**30
"""Python, numpy, torch and Stable-Baselines3 loaded, and their working memory: set so that
a 40,000-node graph, which peaked at 1.56 GB (issue 14), is estimated at about 1.5 GB."""


def learner_bytes(width: int, hidden: int, batch_size: int, rollout_cells: int) -> int:
    """The networks of both learning sides, a minibatch and the rollout buffer (module
    docstring): first layers ``width x hidden``, ``rollout_cells`` observation cells."""
    networks = 2 * 2 * width * hidden * 16
    batch = 2 * batch_size * width * 4
    return networks + batch + rollout_cells * 16


def training_bytes(n_nodes: int, n_edges: int, max_moves: int, cfg: TrainConfig, width=None) -> int:
    """The estimate of the module docstring, in bytes (``width``: the feature count when
    ``cfg.obs == "features"``)."""
    n, k = int(n_nodes), max(1, int(max_moves))
    w = n if cfg.obs == "node" else int(width or 8)
    h = cfg.net_arch[0] if cfg.net_arch else 64
    rollout = cfg.n_steps * cfg.n_envs * (w if cfg.obs != "node" else 1)
    tabulation = min(n * w, CHUNK_CELLS) * 4 + n * k * 24
    tables = n * (2 * k * 9 + 200) + int(n_edges) * 100
    return BASE_BYTES + learner_bytes(w, h, cfg.batch_size, rollout) + tabulation + tables


def concurrent_training_room(width: int, cfg, max_memory_gb: float | None = None) -> int:
    """The bytes left for the certificates (the policy games of
    :func:`asp.concurrent.certify.certify`) once training the concurrent game's learners is
    counted (:data:`BASE_BYTES` and :func:`learner_bytes`: observations of ``width``
    features, one environment a side; :class:`arl.concurrent_trainer.ConcurrentConfig`
    ``cfg``), under the limit ``max_memory_gb`` (default :func:`asp.heap.memory_budget`).

    Raises
    ------
    asp.errors.GameError
        One line: the learners alone are over the limit (the estimate, the limit, the memory
        available and ``--max-memory``).
    """
    gb = 2**30
    limit = heap.memory_budget() if max_memory_gb is None else int(float(max_memory_gb) * gb)
    h = cfg.net_arch[0] if cfg.net_arch else 64
    need = BASE_BYTES + learner_bytes(width, h, cfg.batch_size, cfg.n_steps * width)
    if need > limit:
        raise GameError(
            f"training the concurrent game needs about {need / gb:.2f} GB (observations of "
            f"{width} features, first layer {h} wide) before its certificates, over the "
            f"--max-memory limit of {limit / gb:.3g} GB ({heap.available_memory() / gb:.1f} GB "
            "available); --max-memory GB raises it"
        )
    return limit - need


def check_training_size(dag, cfg: TrainConfig, max_memory_gb: float | None = None) -> None:
    """Raise :class:`asp.errors.GameError` (one line) when training ``dag`` would need more
    memory than the limit.

    Parameters
    ----------
    max_memory_gb : float, optional
        The limit (default :func:`asp.heap.memory_budget`).
    """
    gb = 2**30
    limit = heap.memory_budget() / gb if max_memory_gb is None else float(max_memory_gb)
    k = int(np.diff(dag.indptr).max(initial=1))
    need = training_bytes(dag.n_nodes, dag.n_edges, k, cfg)
    if need > limit * gb:
        raise GameError(
            f"training this game needs about {need / gb:.1f} GB ({dag.n_nodes:,} nodes, "
            f"{dag.n_edges:,} edges, obs {cfg.obs!r}, first layer {cfg.net_arch[0]} wide), "
            f"over the {limit:.1f} GB limit ({heap.available_memory() / gb:.1f} GB available); "
            "--max-memory GB (max_memory_gb) raises it"
        )
