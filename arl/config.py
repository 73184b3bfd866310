"""Training configurations of the alternating-PPO trainer.

``paper`` is exactly ``../shared/DESIGN.md``, "Alternating PPO": SB3 PPO with the MlpPolicy
and its default hyperparameters, one environment, 2048 steps per phase, the frozen opponent
called as a network at every step, Table 1 rewards, stop when the mean rewards of the last 5
checks differ by at most 0.5 or after 100 cycles. Invalid moves are masked (sb3-contrib's
``MaskablePPO``: PPO with the invalid logits masked). The frozen opponent plays its greedy
move (``predict(deterministic=True)``), so the learner trains against the policy the WCPL is
measured with; a "check" is the mean reward of the games each side played in its phase.

``fast`` keeps the algorithm (PPO through SB3) and changes everything else for time to a
robust policy:

- 64 games stepped at once in numpy (:class:`arl.envs.GameVecEnv`), the opponent tabulated
  once per phase (one forward pass over all nodes) and sampled from its own policy;
- zero-sum rewards (every move costs the robot its cost) and ``gamma = 1``, so the robot's
  return is minus the game cost, the quantity W* is defined on; on a graph of ``time``
  costs the rewards PPO learns from are divided by the cooperative cost TCT, so a return
  is about 1 whatever the time unit (on the vacuum pump's concurrent game, makespans near
  215 s, the unscaled runs settled at 223 s on every seed and the scaled ones reached the
  optimum 215 s; step graphs, the paper's, are left as they are);
- exploring starts: half the episodes start at a random state, so both sides learn every
  state, including those an adversary only reaches by deviating;
- a small network, larger batches, fewer epochs, a higher learning rate and a little
  entropy (0.003: with 0.01 the policies kept flipping between near-tied moves, so runs
  stopped later and on a plateau more often), so a cycle takes a fraction of a second;
- stop when the robot's greedy moves at every state it can reach (against any human) and
  the greedy-vs-greedy cost have not changed for 4 cycles, and not before cycle 8 (runs
  stopped at cycle 4 or 5 before the human had found the robot's weak spot).
  ``benchmarks/arl_fast_quality.py`` measures the robust-optimal share over many graphs.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from arl.envs import OBSERVATIONS
from arl.moves import REWARDS, check_choice
from asp.game.turns import CONCURRENT

ALGOS = ("ppo", "maskable_ppo")
STOPS = ("rewards", "policy")
REWARD_SCALES = ("none", "tct")


@dataclass(frozen=True)
class TrainConfig:
    """Everything that defines a training run (the seed aside).

    Attributes
    ----------
    name : str
        Label written to the log.
    algo : "ppo" or "maskable_ppo"
        SB3 ``PPO`` (invalid actions mapped modulo the move count) or sb3-contrib
        ``MaskablePPO`` (invalid actions masked).
    net_arch : tuple of int
        Hidden layers of the policy and value networks (``MlpPolicy``).
    learning_rate, n_steps, batch_size, n_epochs, gamma, gae_lambda, clip_range, ent_coef
        PPO hyperparameters (``n_steps`` per environment).
    phase_steps : int
        Environment steps each side trains for in a cycle (rounded up by SB3 to a multiple
        of ``n_steps * n_envs``).
    n_envs : int
        Parallel games.
    vectorized : bool
        ``True``: :class:`arl.envs.GameVecEnv` with the opponent tabulated once per phase;
        ``False``: :class:`arl.envs.RobotEnv` / :class:`arl.envs.HumanEnv` in a
        ``DummyVecEnv`` with the frozen SB3 model called at every opponent move.
    opponent_deterministic : bool
        Whether the frozen opponent plays its greedy move (else it samples its policy).
    opponent_epsilon : float
        Share of uniformly random opponent moves (vectorised envs only).
    reward : "paper" or "zero_sum"
        See :mod:`arl.moves`.
    reward_scale : "none" or "tct"
        ``tct``: on a graph of ``time`` costs, PPO learns from the rewards divided by the
        graph's cooperative cost TCT (the logged episode rewards stay in the graph's units).
    obs : "node" or "features"
    explore_starts : float
        Share of episodes starting at a uniformly random state.
    max_cycles : int
    stop : "rewards" or "policy"
        ``rewards``: the mean robot and human rewards of the last ``window`` cycles each
        differ by at most ``tolerance`` (the paper's). ``policy``: the robot's greedy moves
        at every state it can reach and the greedy-vs-greedy cost are unchanged over the
        last ``window`` cycles.
    window, tolerance, min_cycles
        Parameters of the stop rule.
    """

    name: str = "custom"
    algo: str = "maskable_ppo"
    net_arch: tuple[int, ...] = (64, 64)
    learning_rate: float = 3e-4
    n_steps: int = 2048
    batch_size: int = 64
    n_epochs: int = 10
    gamma: float = 0.99
    gae_lambda: float = 0.95
    clip_range: float = 0.2
    ent_coef: float = 0.0
    phase_steps: int = 2048
    n_envs: int = 1
    vectorized: bool = False
    opponent_deterministic: bool = True
    opponent_epsilon: float = 0.0
    reward: str = "paper"
    reward_scale: str = "none"
    obs: str = "node"
    explore_starts: float = 0.0
    max_cycles: int = 100
    stop: str = "rewards"
    window: int = 5
    tolerance: float = 0.5
    min_cycles: int = 1

    def __post_init__(self) -> None:
        check_choice("algo", self.algo, ALGOS)
        check_choice("reward", self.reward, REWARDS)
        check_choice("reward_scale", self.reward_scale, REWARD_SCALES)
        check_choice("obs", self.obs, OBSERVATIONS)
        check_choice("stop", self.stop, STOPS)
        for name in ("n_steps", "batch_size", "n_epochs", "phase_steps", "n_envs", "window"):
            if int(getattr(self, name)) < 1:
                raise ValueError(f"{name}: expected a positive integer, got {getattr(self, name)}")
        if self.max_cycles < 1:
            raise ValueError(f"max_cycles: expected a positive integer, got {self.max_cycles}")
        if not self.vectorized and self.n_envs != 1:
            raise ValueError("n_envs: the non-vectorised environments run one game; use 1")
        for name in ("opponent_epsilon", "explore_starts"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ValueError(f"{name}: expected a share in [0, 1], got {getattr(self, name)}")

    def replace(self, **changes) -> TrainConfig:
        """A copy with ``changes`` applied (validated again)."""
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: dict) -> TrainConfig:
        known = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise ValueError(f"config: unknown fields {', '.join(unknown)}")
        values = dict(data)
        if "net_arch" in values:
            values["net_arch"] = tuple(values["net_arch"])
        return cls(**values)


PAPER = TrainConfig(name="paper")

FAST = TrainConfig(
    name="fast",
    algo="maskable_ppo",
    net_arch=(64,),
    learning_rate=3e-3,
    n_steps=16,
    batch_size=256,
    n_epochs=4,
    gamma=1.0,
    gae_lambda=0.95,
    clip_range=0.2,
    ent_coef=0.003,
    phase_steps=1024,
    n_envs=64,
    vectorized=True,
    opponent_deterministic=False,
    opponent_epsilon=0.05,
    reward="zero_sum",
    reward_scale="tct",
    explore_starts=0.5,
    max_cycles=100,
    stop="policy",
    window=4,
    tolerance=0.0,
    min_cycles=8,
)

CONFIGS: dict[str, TrainConfig] = {"paper": PAPER, "fast": FAST}

TURN_MODEL_CHANGES: dict[tuple[str, str], dict] = {("fast", CONCURRENT.name): {"n_steps": 32}}
"""What a named configuration changes on a game of a turn model. ``fast`` on the concurrent
game: ``n_steps`` 32 (robust-optimal on the pump for 10 of 10 seeds, against 7 of 10 with 16;
``benchmarks/arl_concurrent_pump.py --n-steps``)."""


def get_config(config: str | TrainConfig, turn_model: str | None = None) -> TrainConfig:
    """The named configuration (``"paper"`` or ``"fast"``, with its changes for
    ``turn_model``, :data:`TURN_MODEL_CHANGES`) or ``config`` itself."""
    if isinstance(config, TrainConfig):
        return config
    if config not in CONFIGS:
        raise ValueError(f"config: expected one of {', '.join(CONFIGS)}, got {config!r}")
    changes = TURN_MODEL_CHANGES.get((config, turn_model))
    return CONFIGS[config].replace(**changes) if changes else CONFIGS[config]
