"""Gymnasium environments of the game for one learner against a frozen opponent.

- :class:`RobotEnv`: the robot acts; the frozen human moves inside :meth:`~TurnEnv.step`.
- :class:`HumanEnv`: the mirror.
- :class:`GameVecEnv`: an SB3 ``VecEnv`` stepping many games at once in numpy against an
  opponent tabulated as an ``(n, max_moves)`` probability table (the ``fast`` config).

Observation (``obs``): ``"node"`` gives the node index, ``Discrete(n)`` (the paper's);
``"features"`` gives ``features[node]`` as a ``Box`` (caller-supplied ``(n, d)`` features,
default :func:`arl.moves.layer_features`). Action: the index of the move among the learner's
moves at the node, ``Discrete(max_moves)``; :meth:`~TurnEnv.action_masks` serves sb3-contrib's
``MaskablePPO``. An invalid action (without masking) is mapped to ``action % n_moves``,
deterministically (``invalid="raise"`` raises instead). Rewards: see :mod:`arl.moves`.

The learner is only asked when it has a move: passes and opponent moves happen inside
``step`` / ``reset``. If the game ends before the learner ever moves (e.g. the robot goes
straight to the end), the episode restarts from a uniformly random state where the learner
is on turn; such episodes and those started by ``explore_starts`` are not counted as games
in ``info["episode"]`` (the SB3 ``Monitor`` convention, read by ``ep_rew_mean``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from stable_baselines3.common.vec_env import VecEnv

from arl.moves import (
    AGENTS,
    INVALID,
    NO_MOVE,
    REWARDS,
    Game,
    GameTables,
    check_choice,
    layer_features,
    move_rewards,
    player_of,
)
from asp.game import rules
from asp.game.dag import GameDAG

OBSERVATIONS = ("node", "features")

Opponent = Callable[[int], int] | np.ndarray | Any | None
"""A frozen opponent: ``None`` (uniformly random), a callable node -> edge index, an ``(n,)``
array of edge indices, an ``(n, max_moves)`` array of action probabilities, or an SB3 model
(anything with ``predict``)."""


class Observer:
    """Maps node indices to observations and knows the observation space."""

    def __init__(self, dag: GameDAG, obs: str = "node", features: np.ndarray | None = None):
        self.kind = check_choice("obs", obs, OBSERVATIONS)
        if obs == "node":
            self.features = None
            self.space: spaces.Space = spaces.Discrete(dag.n_nodes)
            return
        feats = layer_features(dag) if features is None else np.asarray(features, np.float32)
        if feats.ndim != 2 or feats.shape[0] != dag.n_nodes:
            raise ValueError(
                f"features: expected shape ({dag.n_nodes}, d), got {np.shape(features)}"
            )
        self.features = np.ascontiguousarray(feats, dtype=np.float32)
        low = np.minimum(self.features.min(axis=0), 0.0).astype(np.float32)
        high = np.maximum(self.features.max(axis=0), 1.0).astype(np.float32)
        self.space = spaces.Box(low, high, dtype=np.float32)

    def __call__(self, node: int):
        if self.features is None:
            return np.int64(node)
        return self.features[node].copy()

    def batch(self, nodes: np.ndarray) -> np.ndarray:
        """Observations of many nodes: (k,) int64 or (k, d) float32."""
        nodes = np.asarray(nodes, dtype=np.int64)
        return nodes.copy() if self.features is None else self.features[nodes]


def opponent_function(
    tables: GameTables,
    player: int,
    opponent: Opponent,
    observer: Observer,
    deterministic: bool = True,
) -> Callable[[int, np.random.Generator], int]:
    """Normalise any :data:`Opponent` into ``f(node, rng) -> edge index`` for ``player``."""

    def checked(node: int, edge: int) -> int:
        if edge not in tables.moves[player, node, : tables.n_moves[player, node]]:
            raise ValueError(
                f"{AGENTS[player]} opponent chose edge {edge}, not one of its moves at node "
                f"{tables.dag.node_ids[node]!r}"
            )
        return int(edge)

    if opponent is None:
        return lambda node, rng: int(
            tables.moves[player, node, rng.integers(tables.n_moves[player, node])]
        )
    if isinstance(opponent, np.ndarray):
        table = np.asarray(opponent)
        if table.shape == (tables.n,):
            return lambda node, rng: checked(node, int(table[node]))
        if table.shape == (tables.n, tables.max_moves):
            probs = probability_table(tables, player, table)
            return lambda node, rng: int(
                tables.moves[player, node, rng.choice(tables.max_moves, p=probs[node])]
            )
        raise ValueError(
            f"opponent table: expected shape ({tables.n},) or ({tables.n}, {tables.max_moves}), "
            f"got {table.shape}"
        )
    if hasattr(opponent, "predict"):
        maskable = "action_masks" in _parameters(opponent.predict)

        def model_move(node: int, rng: np.random.Generator) -> int:
            kwargs = {"action_masks": tables.mask(player, node)} if maskable else {}
            action, _ = opponent.predict(observer(node), deterministic=deterministic, **kwargs)
            return tables.edge(player, node, int(np.asarray(action).reshape(-1)[0]))

        return model_move
    if callable(opponent):
        return lambda node, rng: checked(node, int(opponent(node)))
    raise ValueError(f"opponent: expected None, a callable, an array or a model, got {opponent!r}")


def _parameters(fn) -> Sequence[str]:
    import inspect

    try:
        return list(inspect.signature(fn).parameters)
    except (TypeError, ValueError):
        return []


def probability_table(
    tables: GameTables, player: int, table: np.ndarray | None, epsilon: float = 0.0
) -> np.ndarray:
    """A valid ``(n, max_moves)`` action distribution of ``player`` from ``table``.

    ``table`` may be ``None`` (uniform), an ``(n,)`` array of edge indices (greedy) or an
    ``(n, max_moves)`` array of non-negative weights. Invalid actions get probability 0;
    ``epsilon`` mixes in the uniform distribution over the valid actions. Rows of nodes
    where ``player`` has no move are all zero.
    """
    mask = tables.masks(player)
    uniform = mask / np.maximum(mask.sum(axis=1, keepdims=True), 1)
    if table is None:
        return uniform
    table = np.asarray(table)
    if table.shape == (tables.n,):
        actions = tables.to_actions(player, table)
        probs = np.zeros(mask.shape)
        rows = np.flatnonzero(actions >= 0)
        probs[rows, actions[rows]] = 1.0
    elif table.shape == mask.shape:
        probs = np.where(mask, np.clip(table.astype(np.float64), 0.0, None), 0.0)
    else:
        raise ValueError(f"opponent table: expected shape {mask.shape}, got {table.shape}")
    total = probs.sum(axis=1, keepdims=True)
    probs = np.where(total > 0, probs / np.where(total > 0, total, 1.0), uniform)
    return (1.0 - epsilon) * probs + epsilon * uniform


class TurnEnv(gym.Env):
    """One learner (``agent``) against a frozen opponent on a game DAG.

    Parameters
    ----------
    dag : GameDAG
    agent : "robot" or "human"
        The learner.
    opponent : Opponent, optional
        The frozen other side (default: uniformly random); replace it with
        :meth:`set_opponent`.
    obs : "node" or "features"
    features : (n, d) array, optional
        Node features for ``obs="features"``.
    reward : "paper" or "zero_sum"
    explore_starts : float
        Share of episodes that start at a uniformly random state with the learner on turn.
    invalid : "modulo" or "raise"
    opponent_deterministic : bool
        Whether an SB3-model opponent predicts greedily.
    """

    metadata = {"render_modes": ["ansi"]}

    def __init__(
        self,
        dag: GameDAG,
        agent: str = "robot",
        opponent: Opponent = None,
        *,
        obs: str = "node",
        features: np.ndarray | None = None,
        reward: str = "paper",
        explore_starts: float = 0.0,
        invalid: str = "modulo",
        opponent_deterministic: bool = True,
        render_mode: str | None = None,
    ) -> None:
        super().__init__()
        self.tables = GameTables.from_dag(dag)
        self.player = player_of(agent)
        if not self.tables.can_move_somewhere(self.player):
            raise ValueError(f"the {AGENTS[self.player]} has no move anywhere in this graph")
        self.reward_kind = check_choice("reward", reward, REWARDS)
        self.invalid = check_choice("invalid", invalid, INVALID)
        if not 0.0 <= explore_starts <= 1.0:
            raise ValueError(f"explore_starts: expected a share in [0, 1], got {explore_starts}")
        self.explore_starts = float(explore_starts)
        self.opponent_deterministic = opponent_deterministic
        self.observer = Observer(dag, obs, features)
        self.observation_space = self.observer.space
        self.action_space = spaces.Discrete(self.tables.max_moves)
        self.render_mode = render_mode
        self._learner_nodes = np.flatnonzero(self.tables.n_moves[self.player] > 0)
        self.game = Game(self.tables)
        self.set_opponent(opponent)
        self._return, self._length, self._from_start = 0.0, 0, True

    # ----------------------------------------------------------------- opponent
    def set_opponent(self, opponent: Opponent) -> None:
        """Freeze a new opponent (takes effect at its next move)."""
        self._opponent = opponent_function(
            self.tables,
            rules.other(self.player),
            opponent,
            self.observer,
            self.opponent_deterministic,
        )

    def _own(self, mover: int, cost: float) -> float:
        return move_rewards(mover, cost, self.reward_kind)[self.player]

    def _opponent_turns(self) -> float:
        """Let the opponent move (and passes happen) until the learner is on turn."""
        reward = 0.0
        while not self.game.done and self.game.player != self.player:
            edge = self._opponent(self.game.node, self.np_random)
            reward += self._own(rules.other(self.player), self.game.play_edge(edge))
        return reward

    # ----------------------------------------------------------------- gym API
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        self._from_start = True
        if self.np_random.random() < self.explore_starts:
            self._random_state()
        else:
            self.game.reset()
            self._opponent_turns()
            if self.game.done:  # the learner never got a move: start somewhere it has one
                self._random_state()
        self._return, self._length = 0.0, 0
        return self.observer(self.game.node), self._info()

    def _random_state(self) -> None:
        self._from_start = False
        self.game.reset(self.np_random.choice(self._learner_nodes), self.player)

    def step(self, action):
        _, cost = self.game.play(int(action), self.invalid)
        reward = self._own(self.player, cost) + self._opponent_turns()
        terminated = self.game.done
        if terminated:
            reward += self.tables.end_bonus(self.reward_kind)[self.player]
        self._return += reward
        self._length += 1
        info = self._info()
        if terminated and self._from_start:
            info["episode"] = {"r": self._return, "l": self._length, "t": 0.0}
        return self.observer(self.game.node), float(reward), terminated, False, info

    def action_masks(self) -> np.ndarray:
        """(max_moves,) bool: the learner's valid actions now (for ``MaskablePPO``)."""
        if self.game.done:
            return np.ones(self.tables.max_moves, dtype=bool)
        return self.tables.mask(self.player, self.game.node)

    def _info(self) -> dict:
        return {"node": int(self.game.node), "cost": float(self.game.cost)}

    def render(self) -> str | None:
        if self.render_mode != "ansi":
            return None
        node_id = self.tables.dag.node_ids[self.game.node]
        return f"node {node_id!r}, {AGENTS[self.game.player]} on turn, cost {self.game.cost:g}"


class RobotEnv(TurnEnv):
    """The robot learns; the frozen human moves inside ``step`` (see :class:`TurnEnv`)."""

    def __init__(self, dag: GameDAG, opponent: Opponent = None, **kwargs) -> None:
        super().__init__(dag, "robot", opponent, **kwargs)


class HumanEnv(TurnEnv):
    """The human learns; the frozen robot moves inside ``step`` (see :class:`TurnEnv`)."""

    def __init__(self, dag: GameDAG, opponent: Opponent = None, **kwargs) -> None:
        super().__init__(dag, "human", opponent, **kwargs)


class GameVecEnv(VecEnv):
    """``num_envs`` games of one learner against a tabulated opponent, stepped in numpy.

    The opponent is an ``(n, max_moves)`` action distribution (see :func:`probability_table`)
    set once per training phase with :meth:`set_opponent`, so no network runs inside
    ``step``. Same semantics as :class:`TurnEnv` (auto-reset, ``terminal_observation`` and
    ``episode`` infos as SB3's ``VecMonitor``), masks through :meth:`action_masks`.
    """

    def __init__(
        self,
        dag: GameDAG,
        agent: str = "robot",
        num_envs: int = 16,
        *,
        obs: str = "node",
        features: np.ndarray | None = None,
        reward: str = "paper",
        explore_starts: float = 0.0,
        seed: int | None = None,
    ) -> None:
        self.tables = GameTables.from_dag(dag)
        self.player = player_of(agent)
        if not self.tables.can_move_somewhere(self.player):
            raise ValueError(f"the {AGENTS[self.player]} has no move anywhere in this graph")
        self.reward_kind = check_choice("reward", reward, REWARDS)
        self.explore_starts = float(explore_starts)
        self.observer = Observer(dag, obs, features)
        self.render_mode = None
        super().__init__(num_envs, self.observer.space, spaces.Discrete(self.tables.max_moves))
        self.rng = np.random.default_rng(seed)
        self._learner_nodes = np.flatnonzero(self.tables.n_moves[self.player] > 0)
        self._bonus = self.tables.end_bonus(self.reward_kind)[self.player]
        self.node = np.full(num_envs, self.tables.start, dtype=np.int64)
        self.returns = np.zeros(num_envs)
        self.lengths = np.zeros(num_envs, dtype=np.int64)
        self.from_start = np.ones(num_envs, dtype=bool)
        self._actions = np.zeros(num_envs, dtype=np.int64)
        self.set_opponent(None)

    def set_opponent(self, table: np.ndarray | None, epsilon: float = 0.0) -> None:
        """Freeze the opponent as a probability table (see :func:`probability_table`)."""
        probs = probability_table(self.tables, rules.other(self.player), table, epsilon)
        cdf = np.cumsum(probs, axis=1)
        cdf[:, -1] = 2.0  # guard against rounding: the last bucket catches everything
        self._opp_cdf = cdf

    # ---------------------------------------------------------------- game core
    def _opponent_turns(self, idx: np.ndarray, rewards: np.ndarray) -> None:
        """Opponent moves (and passes) in envs ``idx`` until the learner is on turn."""
        t, me, opp = self.tables, self.player, rules.other(self.player)
        active = idx[self.node[idx] != t.end]
        while active.size:
            movers = active[t.can_move[opp, self.node[active]]]
            if movers.size:
                v = self.node[movers]
                u = self.rng.random(movers.size)
                action = (u[:, None] >= self._opp_cdf[v]).sum(axis=1)
                edge = t.moves[opp, v, action]
                cost = t.move_cost[edge]
                rewards[movers] += move_rewards(opp, cost, self.reward_kind)[me]
                self.node[movers] = t.dag.targets[edge]
            v = self.node[active]  # the learner passes where it has no move
            active = active[(v != t.end) & ~t.can_move[me, v]]

    def _reset_envs(self, idx: np.ndarray) -> None:
        t = self.tables
        self.node[idx] = t.start
        self.from_start[idx] = True
        self.returns[idx] = 0.0
        self.lengths[idx] = 0
        explore = self.rng.random(idx.size) < self.explore_starts
        first = rules.settle(t.can_move, t.start, rules.FIRST_PLAYER, t.end)
        if first != self.player:  # the opponent acts first
            self._opponent_turns(idx[~explore], np.zeros(self.num_envs))
        restart = idx[explore | (self.node[idx] == t.end)]
        self.node[restart] = self.rng.choice(self._learner_nodes, size=restart.size)
        self.from_start[restart] = False

    # ---------------------------------------------------------------- VecEnv API
    def reset(self):
        if self._seeds[0] is not None:
            self.rng = np.random.default_rng(self._seeds[0])
        self._reset_seeds()
        self._reset_envs(np.arange(self.num_envs))
        return self.observer.batch(self.node)

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions, dtype=np.int64).reshape(self.num_envs)

    def step_wait(self):
        t, me = self.tables, self.player
        count = t.n_moves[me, self.node]
        edge = t.moves[me, self.node, self._actions % np.maximum(count, 1)]
        rewards = np.asarray(move_rewards(me, t.move_cost[edge], self.reward_kind)[me], float)
        self.node = t.dag.targets[edge].astype(np.int64)
        self._opponent_turns(np.arange(self.num_envs), rewards)
        dones = self.node == t.end
        rewards[dones] += self._bonus
        self.returns += rewards
        self.lengths += 1
        infos: list[dict] = [{} for _ in range(self.num_envs)]
        done_idx = np.flatnonzero(dones)
        if done_idx.size:
            terminal = self.observer.batch(self.node[done_idx])
            for k, i in enumerate(done_idx):
                infos[i]["terminal_observation"] = terminal[k]
                infos[i]["TimeLimit.truncated"] = False
                if self.from_start[i]:
                    infos[i]["episode"] = {
                        "r": float(self.returns[i]),
                        "l": int(self.lengths[i]),
                        "t": 0.0,
                    }
            self._reset_envs(done_idx)
        return self.observer.batch(self.node), rewards.astype(np.float32), dones, infos

    def action_masks(self) -> np.ndarray:
        """(num_envs, max_moves) bool: the learner's valid actions in every game."""
        return (
            np.arange(self.tables.max_moves)[None, :]
            < self.tables.n_moves[self.player, self.node][:, None]
        )

    def close(self) -> None:
        pass

    def _indices(self, indices) -> list[int]:
        return list(self._get_indices(indices))

    def get_attr(self, attr_name: str, indices=None) -> list[Any]:
        value = getattr(self, attr_name)  # AttributeError if missing (has_attr relies on it)
        return [value for _ in self._indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices=None) -> None:
        setattr(self, attr_name, value)

    def env_method(self, method_name: str, *method_args, indices=None, **method_kwargs):
        idx = self._indices(indices)
        if method_name == "action_masks":
            return list(self.action_masks()[idx])
        result = getattr(self, method_name)(*method_args, **method_kwargs)
        return [result for _ in idx]

    def env_is_wrapped(self, wrapper_class, indices=None) -> list[bool]:
        return [False for _ in self._indices(indices)]


__all__ = [
    "NO_MOVE",
    "GameVecEnv",
    "HumanEnv",
    "Observer",
    "RobotEnv",
    "TurnEnv",
    "opponent_function",
    "probability_table",
]
