"""arl: adversarial reinforcement learning of the robot policy on game DAGs.

Public API (imported lazily, so that ``import arl`` does not load torch):

- :func:`arl.train` / :class:`arl.TrainResult`: alternating PPO (:mod:`arl.trainer`);
- :func:`arl.evaluate`: exact metrics of a learned policy or run folder;
- :class:`arl.TrainConfig`, :data:`arl.CONFIGS` (``paper``, ``fast``): :mod:`arl.config`;
- environments: :class:`arl.RobotEnv`, :class:`arl.HumanEnv`, :class:`arl.GameVecEnv`
  (:mod:`arl.envs`) and the PettingZoo :class:`arl.GameAEC` (:mod:`arl.pettingzoo_env`);
- the concurrent game played on the fly from its rules: :class:`arl.ConcurrentRobotEnv`,
  :class:`arl.ConcurrentHumanEnv` (:mod:`arl.concurrent_env`).
"""

from __future__ import annotations

import importlib

_EXPORTS = {
    "train": "arl.trainer",
    "evaluate": "arl.trainer",
    "load_policies": "arl.trainer",
    "TrainResult": "arl.trainer",
    "TrainConfig": "arl.config",
    "CONFIGS": "arl.config",
    "get_config": "arl.config",
    "RobotEnv": "arl.envs",
    "HumanEnv": "arl.envs",
    "GameVecEnv": "arl.envs",
    "GameAEC": "arl.pettingzoo_env",
    "GameTables": "arl.moves",
    "ConcurrentRobotEnv": "arl.concurrent_env",
    "ConcurrentHumanEnv": "arl.concurrent_env",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name in _EXPORTS:
        return getattr(importlib.import_module(_EXPORTS[name]), name)
    raise AttributeError(f"module 'arl' has no attribute {name!r}")
