"""The rules of play on a game DAG, written once (``../shared/DESIGN.md``, "The game").

Every consumer of the game asks this module what a move is: the exact solver and the
policy evaluator (:mod:`asp.game.solve`), the metrics (:mod:`asp.game.metrics`), the play session
(:mod:`asp.game.play`), the readable plan (:mod:`asp.game.plan`), the CP-SAT path
(:mod:`asp.schedule`), the learners' game, environments and trainer (:mod:`arl`), and the
plan file's policy table (``asmplan.planfile``). The
compiled kernels cannot call Python, so they take the rules as tables built here
(:func:`kernel_tables`): one change here changes every consumer.

The rules (turn model ``alternate``)
------------------------------------
- Two players, :data:`ROBOT` (moves first) and :data:`HUMAN`. Each edge is open to a side:
  :data:`ROBOT`, :data:`HUMAN` or :data:`ANY` (:func:`may_take`).
- On its turn a player takes one out-edge open to it (:func:`moves`); a player with none
  passes at zero cost (:data:`PASS_COST`). Either way the turn flips (:func:`other`).
- Taking edge ``e`` leads to ``targets[e]`` and costs ``move_costs(dag)[e]``: the edge's
  cost under both cost models (:data:`COST_MODELS`): under ``steps`` a DAG's edge costs are
  what it says (1 by default, 1 per operation on an assembly), under ``time`` the durations.
- The game ends at the end node. A game state is ``(node, player on turn)``.
- Two costs are the same when they differ by at most :data:`COST_TOL` relative to their
  size (:func:`costs_close`); ``a <= b`` on costs is :func:`cost_at_most`.

Scalar helpers (:func:`moves`, :func:`step`, :func:`settle`) serve sessions and
environments; table builders (:func:`move_masks`, :func:`move_counts`, :func:`move_costs`,
:func:`has_move`, :func:`kernel_tables`) serve the vectorised and compiled consumers.

Every ``dag`` argument is an :class:`asp.game.dag.GameDAG` (not imported:
:mod:`asp.game.dag` builds on this module, and imports flow one way).

Numba caches a compiled kernel per source file and does not notice a change in a function
it calls from another file: the kernels therefore take the tables and the tolerance as
arguments (data, never stale); only the formula of :func:`costs_close` is compiled into
them (``asp/game/solve.py``, ``asmplan/planfile.py``): after editing it, delete the
``__pycache__`` folders under ``asp/`` and ``asmplan/`` so that those kernels are rebuilt.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from asp.errors import GameError

ROBOT = 0
HUMAN = 1
ANY = 2
PLAYERS = (ROBOT, HUMAN)
"""The two players, in turn order (the robot moves first)."""
PLAYER_NAMES = ("robot", "human")
"""Name of each player, indexed by its code."""
SIDE_NAMES = ("robot", "human", "any")
"""Name of each edge side, indexed by its code."""
COST_MODELS = ("steps", "time")
"""``steps``: 1 per operation (the paper's); ``time``: durations plus tool changes."""
FIRST_PLAYER = ROBOT
PASS = -1
"""The edge index of a pass (and of "no move" in policy arrays)."""
PASS_COST = 0.0
COST_TOL = 1e-9
"""Relative tolerance of cost comparisons (see :func:`costs_close`)."""


# ----------------------------------------------------------------------- names


def side_from_name(name: str) -> int:
    """Return the side code of ``"robot"``, ``"human"`` or ``"any"``."""
    try:
        return SIDE_NAMES.index(str(name).lower())
    except ValueError:
        raise GameError(f"unknown side {name!r}: expected one of {', '.join(SIDE_NAMES)}") from None


def player_name(player: int) -> str:
    """``"robot"`` or ``"human"``."""
    return PLAYER_NAMES[int(player)]


def check_cost_model(name: str) -> str:
    """Return ``name`` if it is a cost model, else raise a one-line ``ValueError``."""
    if name not in COST_MODELS:
        raise GameError(f"cost_model: expected 'steps' or 'time', got {name!r}")
    return name


# ----------------------------------------------------------------------- costs


def costs_close(a, b, tol: float = COST_TOL):
    """Whether costs ``a`` and ``b`` are the same: ``|a - b| <= tol (1 + |a| + |b|)``.

    Scalars or arrays (broadcast). Also compiled for the kernels (:data:`close_kernel`).
    """
    return abs(a - b) <= tol * (1.0 + abs(a) + abs(b))


close_kernel = numba.njit(cache=True)(costs_close)
""":func:`costs_close` for numba kernels (pass ``tol`` explicitly)."""


def cost_at_most(a, b, tol: float = COST_TOL):
    """``a <= b`` on costs: below, or the same within the tolerance (scalars or arrays)."""
    return np.less_equal(a, b) | costs_close(a, b, tol)


def move_costs(dag, edges=None) -> np.ndarray:
    """(m,) float64: the cost of taking each edge (or each of ``edges``, an index array),
    in the DAG's cost model.

    The edge's cost under both ``steps`` and ``time``: a ``steps`` DAG says 1 per move
    unless its file gives other costs, and then the game is played on those. A DAG may
    store its costs as float32 (:func:`asp.game.dag.compact_costs`, exact): they are widened
    here (a copy; pass ``edges`` to widen only those); the compiled kernels take them as
    stored (:func:`kernel_tables`).
    """
    costs = dag.costs if edges is None else dag.costs[edges]
    return np.asarray(costs, dtype=np.float64)


def move_cost(dag, edge: int) -> float:
    """The cost of taking ``edge`` (:data:`PASS_COST` for :data:`PASS`)."""
    return PASS_COST if edge == PASS else float(dag.costs[edge])


# ----------------------------------------------------------------------- moves


def may_take(side, player):
    """Whether ``player`` may take an edge of ``side`` (scalars or arrays)."""
    return (side == ANY) | (side == player)


def other(player):
    """The player on turn after ``player`` moved or passed (scalars or arrays)."""
    return 1 - player


def move_mask(dag, player: int) -> np.ndarray:
    """(m,) bool: the edges ``player`` may take."""
    return may_take(dag.sides, player)


def move_masks(dag) -> np.ndarray:
    """(2, m) bool: ``[player, edge]``, the edges each player may take."""
    return np.stack([move_mask(dag, p) for p in PLAYERS])


def move_counts(dag) -> np.ndarray:
    """(2, n) int64: ``[player, node]``, the number of moves of each player at each node."""
    masks = move_masks(dag)
    return np.stack([np.bincount(dag.sources[masks[p]], minlength=dag.n_nodes) for p in PLAYERS])


def has_move(dag) -> np.ndarray:
    """(2, n) bool: ``[player, node]``, whether the player has a move there (else it passes)."""
    return move_counts(dag) > 0


def move_table(dag, player: int) -> tuple[np.ndarray, np.ndarray]:
    """CSR of ``player``'s moves: ``(indptr (n+1,), edges (k,))``, edges in CSR order."""
    mask = move_mask(dag, player)
    indptr = np.zeros(dag.n_nodes + 1, dtype=np.int64)
    np.cumsum(np.bincount(dag.sources[mask], minlength=dag.n_nodes), out=indptr[1:])
    return indptr, np.flatnonzero(mask).astype(np.int64)


def moves(dag, node: int, player: int) -> list[int]:
    """Edge indices ``player`` may take at ``node``, in edge order (empty: it passes)."""
    if node == dag.end:
        return []
    lo, hi = int(dag.indptr[node]), int(dag.indptr[node + 1])
    return [e for e in range(lo, hi) if may_take(int(dag.sides[e]), player)]


def step(dag, node: int, player: int, edge: int = PASS) -> tuple[int, int, float]:
    """Play ``edge`` (or :data:`PASS`) in state ``(node, player)``.

    Returns
    -------
    (node, player, cost)
        The next state and the cost of the move.

    Raises
    ------
    ValueError
        If the game is over, ``edge`` is not one of ``player``'s moves at ``node``, or the
        player passes although it has a move.
    """
    if node == dag.end:
        raise GameError("the game is over")
    if edge == PASS:
        if moves(dag, node, player):
            raise GameError(
                f"the {player_name(player)} has a move at node {dag.node_ids[node]!r}: "
                "it may not pass"
            )
        return node, other(player), PASS_COST
    lo, hi = int(dag.indptr[node]), int(dag.indptr[node + 1])
    if not (lo <= edge < hi and may_take(int(dag.sides[edge]), player)):
        raise GameError(
            f"edge {edge} is not a move of the {player_name(player)} at node "
            f"{dag.node_ids[node]!r}: expected one of {moves(dag, node, player)}"
        )
    return int(dag.targets[edge]), other(player), move_cost(dag, edge)


def settle(can_move: np.ndarray, node: int, player: int, end: int) -> int:
    """The player who acts in state ``(node, player)`` once passes are made.

    ``can_move`` is :func:`has_move`'s ``(2, n)`` table. Every edge is open to some
    player, so at most one pass happens at a node other than the end.
    """
    if node != end and not can_move[player, node]:
        return other(player)
    return player


# ----------------------------------------------------------------------- kernels


@dataclass(frozen=True, eq=False)
class KernelTables:
    """The rules as arrays for the compiled kernels.

    Attributes
    ----------
    indptr : (n + 1,) int64
        CSR row pointer of out-edges.
    targets : (m,) int32 or int64
        Head of each edge (the next node), as the DAG stores it.
    cost : (m,) or (k,) float32 or float64
        Cost of each move (:func:`move_costs`) as the DAG stores it (float32 only when
        exact); the kernels add costs in float64. With ``code``, the table of distinct
        costs (:class:`asp.game.dag.CodedCosts`).
    code : (m,) int8 or int16, or (0,) int8
        Index into ``cost`` of each edge's cost, or empty when ``cost`` is per edge; a
        kernel reads a cost with :func:`edge_cost`.
    sides : (m,) int8
        The side of each edge.
    may_side : (3, 2) bool
        ``may_side[side, player]``: whether ``player`` may take an edge of ``side``
        (:func:`may_take`); a kernel asks ``may_side[sides[e], player]`` (no per-edge
        table of a large game's size).
    tol : float
        Cost tolerance (:data:`COST_TOL`).
    """

    indptr: np.ndarray
    targets: np.ndarray
    cost: np.ndarray
    code: np.ndarray
    sides: np.ndarray
    may_side: np.ndarray
    tol: float

    @property
    def moves(self) -> tuple:
        """``(indptr, targets, cost, code, sides, may_side)``: the arguments a kernel that
        plays the game takes first."""
        return self.indptr, self.targets, self.cost, self.code, self.sides, self.may_side

    @property
    def may(self) -> np.ndarray:
        """(2, m) bool: ``may[player, edge]`` (:func:`move_masks`; built on each call)."""
        return self.may_side[self.sides.astype(np.intp)].T.copy()


def side_table() -> np.ndarray:
    """(3, 2) bool: ``[side, player]``, whether ``player`` may take an edge of ``side``."""
    sides = np.arange(len(SIDE_NAMES))[:, None]
    return np.asarray(may_take(sides, np.array(PLAYERS)[None, :]), dtype=bool)


@numba.njit(cache=True, inline="always")
def edge_cost(cost, code, e):  # pragma: no cover - compiled
    """The cost of edge ``e`` in a kernel (``cost``, ``code`` of :class:`KernelTables`)."""
    if code.shape[0]:
        return cost[code[e]]
    return cost[e]


def kernel_tables(dag) -> KernelTables:
    """The tables the compiled kernels play by."""
    coded = hasattr(dag.costs, "codes")  # asp.game.dag.CodedCosts (dag imports this module)
    return KernelTables(
        indptr=dag.indptr,
        targets=dag.targets,
        cost=dag.costs.table if coded else np.ascontiguousarray(dag.costs),
        code=dag.costs.codes if coded else np.zeros(0, np.int8),
        sides=np.ascontiguousarray(dag.sides, dtype=np.int8),
        may_side=side_table(),
        tol=COST_TOL,
    )


@numba.njit(cache=True)
def _reachable_kernel(
    indptr, targets, sides, may_side, policy, start, end, stack_v, stack_p
):  # pragma: no cover - compiled
    n = indptr.shape[0] - 1
    seen = np.zeros((n, 2), np.bool_)
    stack_v[0], stack_p[0] = start, ROBOT
    seen[start, ROBOT] = True
    top = 1
    while top > 0:
        top -= 1
        v, p = stack_v[top], stack_p[top]
        if v == end:
            continue
        moved = False
        for e in range(indptr[v], indptr[v + 1]):
            if not may_side[sides[e], p]:
                continue
            moved = True
            if p == ROBOT and e != policy[v]:
                continue
            t = targets[e]
            if not seen[t, 1 - p]:
                seen[t, 1 - p] = True
                stack_v[top], stack_p[top] = t, 1 - p
                top += 1
        if not moved and not seen[v, 1 - p]:  # a pass
            seen[v, 1 - p] = True
            stack_v[top], stack_p[top] = v, 1 - p
            top += 1
    return seen


def reachable_states(dag, robot_policy: np.ndarray) -> np.ndarray:
    """(n, 2) bool: the game states reachable when the robot follows ``robot_policy``
    against any human (the end node's states included)."""
    t = kernel_tables(dag)
    policy = np.asarray(robot_policy, dtype=np.int64)
    # Each state is pushed at most once: stacks of 2n + 2 entries, as narrow as the nodes.
    stack_v = np.empty(2 * dag.n_nodes + 2, dtype=t.targets.dtype)
    stack_p = np.empty(2 * dag.n_nodes + 2, dtype=np.int8)
    return _reachable_kernel(
        t.indptr, t.targets, t.sides, t.may_side, policy, dag.start, dag.end, stack_v, stack_p
    )


__all__ = [
    "ANY",
    "COST_MODELS",
    "COST_TOL",
    "FIRST_PLAYER",
    "HUMAN",
    "PASS",
    "PASS_COST",
    "PLAYERS",
    "PLAYER_NAMES",
    "ROBOT",
    "SIDE_NAMES",
    "KernelTables",
    "check_cost_model",
    "close_kernel",
    "cost_at_most",
    "costs_close",
    "has_move",
    "edge_cost",
    "kernel_tables",
    "may_take",
    "move_cost",
    "move_costs",
    "move_counts",
    "move_mask",
    "move_masks",
    "move_table",
    "moves",
    "other",
    "player_name",
    "reachable_states",
    "settle",
    "side_from_name",
    "side_table",
    "step",
]
