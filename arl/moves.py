"""Pure game logic of the robot-vs-human game, shared by every RL adapter.

This module knows nothing of Gymnasium, PettingZoo or SB3 (like the board logic of
PettingZoo's tic-tac-toe): it turns a :class:`asp.game.dag.GameDAG` into move tables, plays moves
and passes by the rules of :mod:`asp.game.rules` (the same the exact solver plays by), and
defines the rewards (``../shared/DESIGN.md``, "The game" and "Alternating
PPO").

Moves and actions
-----------------
At node ``v`` the player ``p`` may take the edges ``dag.moves(v, p)``, in CSR order. The RL
action is the *index* into that list, so the action space is ``Discrete(max_moves)`` where
``max_moves`` is the largest move list of either player at any node. ``moves[p, v, a]`` is
the edge of action ``a`` (``-1`` padding past ``n_moves[p, v]``).

An action at or past ``n_moves[p, v]`` is invalid. Masked learners never pick one; without
masking it is mapped deterministically to ``a % n_moves[p, v]`` (``invalid="modulo"``), or
it raises (``invalid="raise"``).

Rewards
-------
``reward="paper"`` (DESIGN.md, Table 1 of the paper): the robot gets ``-cost`` for each of
its own moves and ``+n`` (the number of nodes) when the end is reached, whoever moved last;
the human gets ``+cost`` for each of its own moves. A move's cost is
:func:`asp.game.rules.move_costs`: the edge's cost, 1 per operation on a ``steps`` graph unless its
file gives other costs (a GraphML with ``cost`` edges is trained on those costs, the ones it
is certified on).

``reward="zero_sum"``: every move (either player's) costs the robot ``cost`` and pays the
human ``cost``, with no end bonus. With ``gamma = 1`` the robot's return is then exactly
minus the game cost, the quantity W* is defined on.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from asp.game import rules
from asp.game.dag import GameDAG
from asp.game.rules import HUMAN, ROBOT

AGENTS = rules.PLAYER_NAMES
"""Agent names, indexed by player code (``ROBOT = 0``, ``HUMAN = 1``)."""
REWARDS = ("paper", "zero_sum")
INVALID = ("modulo", "raise")
NO_MOVE = rules.PASS


def player_of(agent: str | int) -> int:
    """Player code of ``"robot"`` / ``"human"`` (or of a code already)."""
    if isinstance(agent, int | np.integer) and int(agent) in (ROBOT, HUMAN):
        return int(agent)
    if agent in AGENTS:
        return AGENTS.index(agent)
    raise ValueError(f"agent: expected 'robot' or 'human', got {agent!r}")


def check_choice(name: str, value: str, choices: tuple[str, ...]) -> str:
    """Return ``value`` if it is one of ``choices``, else raise a one-line ``ValueError``."""
    if value not in choices:
        raise ValueError(f"{name}: expected one of {', '.join(choices)}, got {value!r}")
    return value


@dataclass(frozen=True, eq=False)
class GameTables:
    """Array form of a game DAG for fast move lookup.

    Attributes
    ----------
    dag : GameDAG
    n : int
        Number of nodes.
    max_moves : int
        Size of the action space (at least 1).
    moves : (2, n, max_moves) int64
        ``moves[p, v, a]``: edge index of action ``a`` of player ``p`` at node ``v``, or -1.
    n_moves : (2, n) int64
        Number of moves of each player at each node.
    move_cost : (m,) float64
        Cost of each edge (:func:`asp.game.rules.move_costs`).
    can_move : (2, n) bool
        Whether each player has a move at each node (:func:`asp.game.rules.has_move`).
    """

    dag: GameDAG
    n: int
    max_moves: int
    moves: np.ndarray
    n_moves: np.ndarray
    move_cost: np.ndarray
    can_move: np.ndarray

    @classmethod
    def from_dag(cls, dag: GameDAG) -> GameTables:
        """Build the move tables of ``dag``."""
        n = dag.n_nodes
        src = dag.sources
        n_moves = rules.move_counts(dag)
        k = max(1, int(n_moves.max(initial=0)))
        moves = np.full((2, n, k), NO_MOVE, dtype=np.int64)
        for p in rules.PLAYERS:
            first, edges = rules.move_table(dag, p)
            # Rank of each allowed edge among its node's allowed edges (edges are CSR-sorted).
            rank = np.arange(edges.size) - first[src[edges]]
            moves[p, src[edges], rank] = edges
        move_cost = np.asarray(rules.move_costs(dag), dtype=np.float64)
        return cls(
            dag=dag,
            n=n,
            max_moves=k,
            moves=moves,
            n_moves=n_moves,
            move_cost=move_cost,
            can_move=n_moves > 0,
        )

    @property
    def start(self) -> int:
        return self.dag.start

    @property
    def end(self) -> int:
        return self.dag.end

    def masks(self, player: int) -> np.ndarray:
        """(n, max_moves) bool: the valid actions of ``player`` at every node."""
        return np.arange(self.max_moves)[None, :] < self.n_moves[player][:, None]

    def mask(self, player: int, node: int) -> np.ndarray:
        """(max_moves,) bool: the valid actions of ``player`` at ``node``."""
        return np.arange(self.max_moves) < self.n_moves[player, node]

    def edge(self, player: int, node: int, action: int, invalid: str = "modulo") -> int:
        """Edge index of ``action`` of ``player`` at ``node`` (see the module notes)."""
        count = int(self.n_moves[player, node])
        if count == 0:
            raise ValueError(f"{AGENTS[player]} has no move at node {self.dag.node_ids[node]!r}")
        a = int(action)
        if not 0 <= a < count:
            if invalid == "raise":
                raise ValueError(
                    f"invalid action {a} for the {AGENTS[player]} at node "
                    f"{self.dag.node_ids[node]!r}: expected 0..{count - 1}"
                )
            a %= count
        return int(self.moves[player, node, a])

    def to_edges(self, player: int, actions: np.ndarray) -> np.ndarray:
        """(n,) edge indices of one action per node (``NO_MOVE`` where ``player`` has none)."""
        actions = np.asarray(actions, dtype=np.int64)
        count = self.n_moves[player]
        safe = np.where(count > 0, actions % np.maximum(count, 1), 0)
        edges = self.moves[player, np.arange(self.n), safe]
        return np.where(count > 0, edges, NO_MOVE)

    def to_actions(self, player: int, edges: np.ndarray) -> np.ndarray:
        """(n,) action indices of one edge per node (-1 where ``edges`` has ``NO_MOVE``)."""
        edges = np.asarray(edges, dtype=np.int64)
        hit = self.moves[player] == edges[:, None]
        hit &= edges[:, None] >= 0
        return np.where(hit.any(axis=1), hit.argmax(axis=1), -1)

    def can_move_somewhere(self, player: int) -> bool:
        """Whether ``player`` has a move at any node (else it never acts)."""
        return bool(self.n_moves[player].any())

    def end_bonus(self, reward: str) -> tuple[float, float]:
        """(robot, human) reward for reaching the end."""
        return (float(self.n), 0.0) if reward == "paper" else (0.0, 0.0)


def move_rewards(mover, cost, reward: str):
    """(robot, human) rewards of a move by ``mover`` costing ``cost`` (scalars or arrays)."""
    if reward == "paper":
        robot = np.where(np.equal(mover, ROBOT), -cost, 0.0)
        human = np.where(np.equal(mover, HUMAN), cost, 0.0)
    else:
        robot, human = -np.asarray(cost, dtype=np.float64), np.asarray(cost, dtype=np.float64)
    if np.ndim(robot) == 0:
        return float(robot), float(human)
    return robot, human


class Game:
    """One game in progress: the node, the player on turn and the cost so far.

    Passes are automatic: after every move (and at the start) :meth:`settle` hands the turn
    over while the player on turn has no move, so a player is only ever asked when it can
    act, or the game is over.
    """

    def __init__(self, tables: GameTables) -> None:
        self.tables = tables
        self.node = tables.start
        self.player = rules.FIRST_PLAYER
        self.cost = 0.0
        self.settle()

    def reset(self, node: int | None = None, player: int = rules.FIRST_PLAYER) -> None:
        """Start again at ``node`` (default: the start) with ``player`` on turn."""
        self.node = self.tables.start if node is None else int(node)
        self.player = int(player)
        self.cost = 0.0
        self.settle()

    @property
    def done(self) -> bool:
        return self.node == self.tables.end

    def settle(self) -> None:
        """Pass (at zero cost) while the player on turn has no move."""
        self.player = rules.settle(self.tables.can_move, self.node, self.player, self.tables.end)

    def legal_actions(self) -> np.ndarray:
        """(max_moves,) bool mask of the player on turn (all False once the game is over)."""
        if self.done:
            return np.zeros(self.tables.max_moves, dtype=bool)
        return self.tables.mask(self.player, self.node)

    def play(self, action: int, invalid: str = "modulo") -> tuple[int, float]:
        """Play ``action`` for the player on turn; return ``(edge, move cost)``.

        The turn then flips (and :meth:`settle` passes for a player without a move).
        """
        if self.done:
            raise ValueError("the game is over")
        edge = self.tables.edge(self.player, self.node, action, invalid)
        return edge, self.play_edge(edge)

    def play_edge(self, edge: int) -> float:
        """Play edge ``edge`` (one of the moves of the player on turn); return its cost."""
        self.node, self.player, cost = rules.step(self.tables.dag, self.node, self.player, edge)
        self.cost += cost
        self.settle()
        return cost


def layer_features(dag: GameDAG) -> np.ndarray:
    """Default node features for policies that generalise across nodes: (n, d) float32.

    One-hot of the node's depth (longest edge count from the start), then the normalised
    depth and the normalised shortest edge count to the end. For assembly DAGs pass your own
    features (e.g. the done-operation bits) instead.
    """
    from asp.game.solve import node_order

    n, order = dag.n_nodes, node_order(dag)
    depth = np.zeros(n, dtype=np.int64)
    for v in order:
        lo, hi = dag.indptr[v], dag.indptr[v + 1]
        if hi > lo:
            heads = dag.targets[lo:hi]
            depth[heads] = np.maximum(depth[heads], depth[v] + 1)
    to_end = np.zeros(n, dtype=np.float64)
    for v in order[::-1]:
        lo, hi = dag.indptr[v], dag.indptr[v + 1]
        if hi > lo:
            to_end[v] = 1.0 + to_end[dag.targets[lo:hi]].min()
    levels = int(depth.max()) + 1
    onehot = np.zeros((n, levels), dtype=np.float32)
    onehot[np.arange(n), depth] = 1.0
    extra = np.stack([depth / max(1, levels - 1), to_end / max(1.0, to_end.max())], axis=1)
    return np.concatenate([onehot, extra.astype(np.float32)], axis=1)
