"""The certified worst case of any robot policy on the concurrent game (:func:`certify`).

A robot policy is a function ``choose(position, commits) -> index``: at a position of
:class:`asp.concurrent.rules.Rules` (the robot side on turn) it picks one of the
commitments :meth:`~asp.concurrent.rules.Rules.commits` lists. Fixing it leaves a one-player
game for the human side, much smaller than the concurrent game: from the start positions,
the robot's single commitment at each position and *every* reply of the human side to it.
That *policy game* is walked here from the rules, with the same node and edge layout as the
policy games of :mod:`asp.concurrent.search` (so it is an ordinary
:class:`asp.concurrent.build.ConcurrentGame`), and solved exactly by :func:`asp.game.solve.solve`:
the value at a start is the exact best response of the human side to the policy, the
policy's *certified worst case* for that budget.

Exactness: every human reply is a branch of the walk (the rules give each reply that leads
to a distinct position or cost), the robot side has one move per position, so the solved
value at a robot node is the maximum over the human side's strategies of the makespan
against the policy, i.e. the certified worst case. Positions are the rules' canonical
positions (budgets that no longer bind capped, alike operations identified), so a policy
is a function of the canonical position; a budget ``None`` (``k = inf``) is the start at
the budget cap. When ``choose`` does not look at :attr:`Position.budget`, a human allowed
``k + 1`` deviations can play every strategy of ``k`` against the same moves, so the
certified worst case never falls as ``k`` grows.

The walk is plain Python over the compiled move generators (:func:`commit_rows`,
:func:`reply_rows`): ``choose`` may be anything, a learned network included.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from asp.concurrent.build import Commit, ConcurrentGame
from asp.concurrent.model import UNBOUNDED
from asp.concurrent.rules import (
    NONE,
    Position,
    Rules,
    commit_rows,
    committed_row,
    key_of,
    reply_rows,
)
from asp.concurrent.search import as_policy_game, node_row

Choose = Callable[[Position, list[Commit]], int]
"""A robot policy: the index of the commitment it takes at a position."""

DEFAULT_MAX_NODES = 2_000_000
"""Nodes of a policy game above which :func:`certify` stops with a ``GameLimit``."""


@dataclass(frozen=True, eq=False)
class Certificate:
    """The certified worst case of a robot policy, per budget.

    Attributes
    ----------
    worst : dict
        Budget (``None``: ``k = inf``) -> the policy's exact worst-case makespan (spec units).
    game : asp.concurrent.build.ConcurrentGame
        The policy game (one start per budget); ``solution`` its exact solution: each
        robot node's value is the policy's worst case from there.
    solution : asp.game.solve.Solution
    seconds : float
    """

    worst: dict
    game: ConcurrentGame
    solution: object
    seconds: float

    @property
    def nodes(self) -> int:
        return self.game.dag.n_nodes

    def to_list(self) -> list[dict]:
        """``[{"k": 0, "bound": ...}, ..., {"k": None, "bound": ...}]`` (budgets in order,
        ``None`` last)."""
        ks = sorted(self.worst, key=lambda b: (b is None, b or 0))
        return [{"k": b, "bound": self.worst[b]} for b in ks]


def as_commits(rows: np.ndarray) -> list[Commit]:
    """The :class:`Commit` of each row of :func:`commit_rows` (None for a busy worker)."""
    return [Commit(ops=tuple(None if o == NONE else int(o) for o in row)) for row in rows]


def certify(
    rules: Rules,
    choose: Choose,
    budgets: list[int | None],
    *,
    max_nodes: int = DEFAULT_MAX_NODES,
) -> Certificate:
    """The exact best response of the human side to the robot policy ``choose``.

    Parameters
    ----------
    rules : asp.concurrent.rules.Rules
    choose : callable ``(Position, list of Commit) -> int``
        The robot policy (module docstring).
    budgets : list of int or None
        The deviation budgets to certify (``None``: the fully adversarial human).
    max_nodes : int
        The policy game's largest size.

    Raises
    ------
    asp.errors.GameError
        ``choose`` gave no valid index, or a negative budget.
    asp.errors.GameLimit
        The policy game has more than ``max_nodes`` nodes.
    """
    from asp.errors import GameError, GameLimit
    from asp.game.solve import solve

    t0 = time.perf_counter()
    T = rules.tables
    nw = rules.n_workers
    none = np.full(nw, NONE, dtype=np.int64)
    end = np.full(2 + 2 * nw, -1, dtype=np.int64)
    nodes = [node_row(end, 2, none, nw)]
    index: dict[bytes, int] = {}
    stack: list[np.ndarray] = []
    src, dst, cost, side, e_ops, e_dur, e_dev = [], [], [], [], [], [], []

    def node_of(row: np.ndarray) -> int:
        key = key_of(T, row).tobytes()
        v = index.get(key)
        if v is None:
            if len(nodes) >= max_nodes:
                raise GameLimit(
                    f"{rules.model.spec.source or rules.model.spec.name}: the policy game "
                    f"exceeds {max_nodes:,} nodes"
                )
            v = index[key] = len(nodes)
            nodes.append(node_row(row, 0, none, nw))
            stack.append(row)
        return v

    def add_edge(a, b, c, s, ops, durs, dev):
        src.append(a)
        dst.append(b)
        cost.append(c)
        side.append(s)
        e_ops.append(ops)
        e_dur.append(durs)
        e_dev.append(dev)

    start_ids = np.array([node_of(rules.start(b).row()) for b in budgets], dtype=np.int64)
    while stack:
        row = stack.pop()
        v = index[key_of(T, row).tobytes()]
        commits = commit_rows(T, row)
        i = choose(Position.of_row(row), as_commits(commits))
        if not 0 <= int(i) < commits.shape[0]:
            raise GameError(
                f"robot policy: expected a commitment index in 0..{commits.shape[0] - 1} at "
                f"{Position.of_row(row)}, got {i}"
            )
        commit = commits[int(i)]
        cur, told = committed_row(T, row, commit)
        u = len(nodes)
        nodes.append(node_row(cur, 1, told, nw))
        add_edge(v, u, 0, 0, commit, none, 0)
        ops, durs, dev, delta, rws = reply_rows(T, row, commit)
        for r in range(delta.shape[0]):
            t = 0 if rws[r, 0] < 0 else node_of(rws[r])
            add_edge(u, t, int(delta[r]), 1, ops[r], durs[r], int(dev[r]))
    edges = (
        np.array(src, dtype=np.int64),
        np.array(dst, dtype=np.int64),
        np.array(cost, dtype=np.int64),
        np.array(side, dtype=np.int64),
        np.array(e_ops, dtype=np.int64).reshape(-1, nw),
        np.array(e_dur, dtype=np.int64).reshape(-1, nw),
        np.array(e_dev, dtype=np.int64),
    )
    rows = np.array(nodes, dtype=np.int64)
    game = as_policy_game(rules, budgets, rows, start_ids, edges, t0)
    solution = solve(game.dag)
    worst = {
        (None if b == UNBOUNDED else b): float(solution.value[s, 0]) for b, s in game.starts.items()
    }
    return Certificate(worst=worst, game=game, solution=solution, seconds=time.perf_counter() - t0)
