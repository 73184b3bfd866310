"""Gymnasium environments of the concurrent game played on the fly (:mod:`asp.concurrent.rules`).

The game is walked by its rules, never compiled, so a product past the exact solver's size
can be trained on. One side learns (:class:`ConcurrentRobotEnv`, :class:`ConcurrentHumanEnv`);
the other is a frozen opponent that moves inside :meth:`ConcurrentEnv.step`.

Decisions. At an event the robot side commits an operation or *wait* for each free robot
and an instruction for each free human (:meth:`~asp.concurrent.rules.Rules.commits`); the
human side then replies with an operation and a duration for each free human
(:meth:`~asp.concurrent.rules.Rules.replies`). A joint move is taken one worker at a time, in
worker order: the action is that worker's choice, and the mask allows exactly the choices
that some joint move still open has (so every sequence of allowed actions ends in a legal
joint move). A worker whose choice is forced is skipped. Actions:

- robot: ``Discrete(n + 1)``, the operation, ``n`` for *wait*;
- human: ``Discrete((n + 1) * D)``, ``operation * D + r`` with ``r`` the rank of the
  duration among those open for that operation (``D`` the most duration choices).

An action outside the mask (gymnasium's and SB3's checkers sample them) is mapped to the
allowed action of rank ``action % allowed``, deterministically.

Observation (``Box``, float32, :func:`observation`): the position's features
(:meth:`~asp.concurrent.rules.Rules.features`: done operations, the remaining time of the
running ones divided by ``horizon``, free workers), the budget as ``b / (b + 1)`` (zero for
the robot, so its policy is blind to the budget and its certified worst case never falls as
``k`` grows, :mod:`asp.concurrent.certify`), the instructions the persons were given (human
side), the deciding worker (one-hot) and the choices already made at this event. The
network sees what is done and running, not a node id, so it generalises across states.

Rewards: the time until the next event divided by ``horizon`` (the start's lower bound),
negative for the robot and positive for the human (zero-sum; with ``gamma = 1`` the robot's
return is minus the makespan over ``horizon``). ``info["makespan"]`` at the end is the game's
makespan in spec units.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from asp.concurrent.model import WAIT
from asp.concurrent.rules import (
    NONE,
    Position,
    Rules,
    commit_rows,
    committed_row,
    lower_bound_of,
    reply_rows,
)

ROBOT_SIDE, HUMAN_SIDE = "robot", "human"
MAX_RESTARTS = 100
"""Games :meth:`ConcurrentEnv.reset` plays for a decision of the learner before it gives up."""

Opponent = Callable[[np.ndarray, np.ndarray], int] | Any | None
"""A frozen opponent: ``None`` (uniformly random among the allowed actions), a callable
``(observation, mask) -> action``, or an SB3 actor-critic model (``MaskablePPO``)."""


class Turn:
    """One side's joint move at an event, taken one worker at a time (module docstring).

    Parameters
    ----------
    codes : (M, W) int64
        Per open joint move, each worker's action code (:data:`NONE`: takes no part).
    """

    def __init__(self, codes: np.ndarray):
        self.codes = codes
        self.alive = np.ones(codes.shape[0], dtype=bool)
        self.deciders = [w for w in range(codes.shape[1]) if codes.shape[0] and codes[0, w] != NONE]
        self.j = 0
        self.chosen: list[int] = []
        self._allowed: np.ndarray | None = None  # of decider j
        self._skip_forced()

    @property
    def done(self) -> bool:
        return self.j >= len(self.deciders)

    @property
    def worker(self) -> int:
        return self.deciders[self.j]

    @property
    def index(self) -> int:
        """The joint move taken (once :attr:`done`)."""
        return int(np.flatnonzero(self.alive)[0])

    def allowed(self) -> np.ndarray:
        """The action codes open to the deciding worker, sorted."""
        if self._allowed is None:
            self._allowed = np.unique(self.codes[self.alive, self.worker])
        return self._allowed

    def choose(self, action: int) -> None:
        """Take ``action`` for the deciding worker (mapped into the allowed ones)."""
        allowed = self.allowed()
        a = int(action)
        if a not in allowed:
            a = int(allowed[a % len(allowed)])
        self.alive &= self.codes[:, self.worker] == a
        self.chosen.append(a)
        self.j += 1
        self._allowed = None
        self._skip_forced()

    def _skip_forced(self) -> None:
        while not self.done and len(self.allowed()) == 1:
            self.chosen.append(int(self.allowed()[0]))
            self.j += 1
            self._allowed = None


class Encoder:
    """Action codes and observations of a game's rules (module docstring)."""

    def __init__(self, rules: Rules):
        self.rules = rules
        self.n = rules.model.n_ops
        self.nw = rules.n_workers
        self.n_dur = max(1, int(rules.tables.ndur.max(initial=1)))
        start = rules.start(0).row()
        self.horizon = float(max(1, int(lower_bound_of(rules.tables, start))))
        self.size = 4 * self.n + 2 * self.nw + 2
        T = rules.tables
        longest = int(T.dur.max(initial=0)) + int(T.change.max(initial=0))
        self.high = max(1.0, longest / self.horizon)

    def slot(self, op: int) -> int:
        return self.n if op == WAIT else int(op)

    def robot_codes(self, commits: np.ndarray) -> np.ndarray:
        """(M, W) codes of :func:`commit_rows`' commitments."""
        codes = np.where(commits == NONE, NONE, commits)
        return np.where(codes == WAIT, self.n, codes).astype(np.int64)

    def human_codes(self, ops: np.ndarray, durs: np.ndarray) -> np.ndarray:
        """(M, W) codes of :func:`reply_rows`' replies: ``slot * D + duration rank``."""
        codes = np.full(ops.shape, NONE, dtype=np.int64)
        for w in range(ops.shape[1]):
            for r in range(ops.shape[0]):
                o = int(ops[r, w])
                if o == NONE:
                    continue
                if o == WAIT:
                    codes[r, w] = self.n * self.n_dur
                    continue
                same = np.unique(durs[ops[:, w] == o, w])
                rank = int(np.searchsorted(same, durs[r, w]))
                codes[r, w] = o * self.n_dur + min(rank, self.n_dur - 1)
        return codes

    def observation(self, row: np.ndarray, side: str, turn: Turn, told=None) -> np.ndarray:
        """The observation of the deciding worker of ``turn`` at position ``row``."""
        n, nw = self.n, self.nw
        out = np.zeros(self.size, dtype=np.float32)
        pos = Position.of_row(row)
        feats = self.rules.features(pos)
        out[:n] = feats[:n]
        out[n : 2 * n] = feats[n : 2 * n] * (self.rules.scale / self.horizon)
        out[2 * n : 2 * n + nw] = feats[2 * n : 2 * n + nw]
        if side == HUMAN_SIDE:
            out[2 * n + nw] = pos.budget / (pos.budget + 1.0)
        base = 2 * n + nw + 1
        if told is not None:
            for o in told:
                if o >= 0:
                    out[base + o] = 1
        base += n
        if not turn.done:
            out[base + turn.worker] = 1
        base += nw
        div = 1 if side == ROBOT_SIDE else self.n_dur
        for a in turn.chosen:
            out[base + a // div] = 1
        return out

    def space(self) -> spaces.Box:
        return spaces.Box(0.0, self.high, shape=(self.size,), dtype=np.float32)

    def actions(self, side: str) -> spaces.Discrete:
        return spaces.Discrete(self.n + 1 if side == ROBOT_SIDE else (self.n + 1) * self.n_dur)


def act(opponent: Opponent, obs: np.ndarray, mask: np.ndarray, rng, deterministic: bool) -> int:
    """The frozen opponent's action (see :data:`Opponent`). An SB3 model's policy network is
    called directly (:func:`policy_logits`): its greedy action is ``predict``'s, and a
    sampled one is drawn from the masked softmax with ``rng`` (no torch distribution made
    per move, most of the time of a game otherwise)."""
    if opponent is None:
        return int(rng.choice(np.flatnonzero(mask)))
    if hasattr(opponent, "policy"):
        logits = np.where(mask, policy_logits(opponent, obs), -np.inf)
        if deterministic:
            return int(np.argmax(logits))
        p = np.exp(logits - logits.max())
        return int(rng.choice(len(p), p=p / p.sum()))
    return int(opponent(obs, mask))


def policy_logits(model, obs: np.ndarray) -> np.ndarray:
    """The action logits of an SB3 actor-critic model (``MaskablePPO``) at ``obs``, unmasked:
    the path of its ``predict`` (features, actor latent, action net)."""
    import torch
    from stable_baselines3.common.policies import BaseModel

    policy = model.policy
    with torch.no_grad():
        t = torch.as_tensor(obs, dtype=torch.float32)[None]
        features = BaseModel.extract_features(policy, t, policy.pi_features_extractor)
        latent = policy.mlp_extractor.forward_actor(features)
        return policy.action_net(latent)[0].numpy().astype(np.float64)


def mask_of(turn: Turn, n_actions: int) -> np.ndarray:
    mask = np.zeros(n_actions, dtype=bool)
    mask[turn.allowed()] = True
    return mask


def robot_choose(rules: Rules, model: Opponent, *, deterministic: bool = True, seed: int = 0):
    """A robot policy ``(Position, commits) -> index`` (:func:`asp.concurrent.certify.certify`)
    of a learned robot model (or any :data:`Opponent`)."""
    enc = Encoder(rules)
    n_actions = enc.actions(ROBOT_SIDE).n
    rng = np.random.default_rng(seed)

    def choose(pos: Position, commits) -> int:
        rows = np.array([[NONE if o is None else o for o in c.ops] for c in commits])
        turn = Turn(enc.robot_codes(rows.astype(np.int64)))
        row = pos.row()
        while not turn.done:
            obs = enc.observation(row, ROBOT_SIDE, turn)
            turn.choose(act(model, obs, mask_of(turn, n_actions), rng, deterministic))
        return turn.index

    return choose


class ConcurrentEnv(gym.Env):
    """One side of the concurrent game learns; the other is frozen (module docstring).

    Parameters
    ----------
    rules : asp.concurrent.rules.Rules
    side : "robot" or "human"
        The learner.
    opponent : Opponent
        The other side (:meth:`set_opponent` changes it).
    budgets : list of int or None
        Each episode starts at one of these budgets, drawn uniformly (None: ``k = inf``);
        a game in which the learner has no decision is played out and another drawn.
    opponent_deterministic : bool
        An SB3 opponent plays its greedy action (else it samples its policy).
    """

    metadata = {"render_modes": []}

    def __init__(
        self,
        rules: Rules,
        side: str,
        opponent: Opponent = None,
        *,
        budgets: list[int | None] | None = None,
        opponent_deterministic: bool = False,
    ) -> None:
        if side not in (ROBOT_SIDE, HUMAN_SIDE):
            raise ValueError(f"side: expected robot or human, got {side!r}")
        self.rules = rules
        self.side = side
        self.enc = Encoder(rules)
        self.observation_space = self.enc.space()
        self.action_space = self.enc.actions(side)
        self.budgets = list(budgets) if budgets else [None]
        self.opponent = opponent
        self.opponent_deterministic = opponent_deterministic
        self.np_random_opp = np.random.default_rng(0)
        self.row = rules.start(None).row()
        self.phase = ROBOT_SIDE
        self.turn: Turn | None = None

    def set_opponent(self, opponent: Opponent) -> None:
        self.opponent = opponent

    # ---------------------------------------------------------------- game core
    def _new_turn(self) -> None:
        T = self.rules.tables
        if self.phase == ROBOT_SIDE:
            self.commits = commit_rows(T, self.row)
            self.turn = Turn(self.enc.robot_codes(self.commits))
            self.told = None
        else:
            ops, durs, _, delta, rows = reply_rows(T, self.row, self.commit)
            self.replies = (delta, rows)
            self.turn = Turn(self.enc.human_codes(ops, durs))

    def _obs(self) -> np.ndarray:
        row = self.row
        if self.phase == HUMAN_SIDE:
            row = self.shown
        return self.enc.observation(row, self.phase, self.turn, self.told)

    def _play(self) -> float:
        """Play on until the learner decides or the game ends; the learner's reward."""
        reward = 0.0
        while self.row[0] >= 0:
            if self.turn is None:
                self._new_turn()
            if not self.turn.done:
                if self.phase == self.side:
                    return reward
                mask = mask_of(self.turn, self.enc.actions(self.phase).n)
                a = act(
                    self.opponent,
                    self._obs(),
                    mask,
                    self.np_random_opp,
                    self.opponent_deterministic,
                )
                self.turn.choose(a)
                continue
            i = self.turn.index
            self.turn = None
            if self.phase == ROBOT_SIDE:
                self.commit = self.commits[i]
                cur, told = committed_row(self.rules.tables, self.row, self.commit)
                self.shown, self.told = cur, told
                self.phase = HUMAN_SIDE
            else:
                delta, rows = self.replies
                dt = float(delta[i]) / self.enc.horizon
                self.elapsed += int(delta[i])
                reward += dt if self.side == HUMAN_SIDE else -dt
                self.row = rows[i].copy()
                self.phase = ROBOT_SIDE
                self.told = None
        return reward

    # ---------------------------------------------------------------- gymnasium
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        if seed is not None:
            self.np_random_opp = np.random.default_rng(seed + 1)
        for _ in range(MAX_RESTARTS):
            # drawn per game: at some budget the learner may never decide (a person with
            # no deviation left and fixed durations only follows the instructions)
            budget = self.budgets[int(self.np_random.integers(len(self.budgets)))]
            self.row = self.rules.start(budget).row()
            self.phase, self.turn, self.told, self.elapsed = ROBOT_SIDE, None, None, 0
            self._play()
            if self.row[0] >= 0:
                return self._obs(), {}
        # (a random opponent may reach a decision of the learner in another game)
        raise ValueError(
            f"{self.rules.model.spec.name}: the {self.side} side has no decision in "
            f"{MAX_RESTARTS} games"
        )

    def step(self, action):
        self.turn.choose(int(action))
        reward = self._play()
        done = self.row[0] < 0
        info = {"makespan": self.elapsed / self.rules.scale} if done else {}
        obs = np.zeros(self.enc.size, dtype=np.float32) if done else self._obs()
        return obs, float(reward), bool(done), False, info

    def action_masks(self) -> np.ndarray:
        """The allowed actions (sb3-contrib ``MaskablePPO``)."""
        if self.turn is None or self.turn.done:
            return np.ones(self.action_space.n, dtype=bool)
        return mask_of(self.turn, self.action_space.n)


class ConcurrentRobotEnv(ConcurrentEnv):
    """The robot side learns; the frozen human side moves inside ``step``."""

    def __init__(self, rules: Rules, opponent: Opponent = None, **kwargs) -> None:
        super().__init__(rules, ROBOT_SIDE, opponent, **kwargs)


class ConcurrentHumanEnv(ConcurrentEnv):
    """The human side learns; the frozen robot side moves inside ``step``."""

    def __init__(self, rules: Rules, opponent: Opponent = None, **kwargs) -> None:
        super().__init__(rules, HUMAN_SIDE, opponent, **kwargs)
