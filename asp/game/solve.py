"""Exact solution of the robot-vs-human game by backward induction.

Game states are ``(node, player on turn)`` (``../shared/DESIGN.md``, "The game"). Sweeping
nodes in reverse topological order, each state gets:

- ``value[v, p]``: the minimax cost to the end (robot minimises, human maximises);
- ``coop[v, p]``: the cooperative cost (both minimise): TCT at the start;
- ``expected[v, p]``: the expected cost when the robot follows the robust policy and the
  human moves uniformly at random among its moves;

and the robust robot move (a move achieving the minimax value; ties broken by lower
``expected`` cost, then by lower move index) and the human's maximising move (ties by
lower index). The rules of play (moves, passes, costs, the cost tolerance) come from
:mod:`asp.game.rules` as tables (:func:`asp.game.rules.kernel_tables`).

The sweeps are compiled with numba (``cache=True``): a 1M-node, 3M-edge game solves in
well under a second.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numba
import numpy as np

from asp.errors import GameError
from asp.game import rules
from asp.game.dag import GameDAG, ids_topological, topological_order
from asp.game.rules import HUMAN, ROBOT, edge_cost
from asp.game.rules import close_kernel as _close

NO_MOVE = rules.PASS
"""Policy entry of a state whose player has no move (it passes) or of the end node."""


@dataclass(frozen=True, eq=False)
class Solution:
    """The exact solution of a game DAG.

    Attributes
    ----------
    tct : float
        Cooperative minimum cost from the start (robot on turn).
    minimax : float
        The game value W* from the start (robot on turn).
    robot_policy : (n,) int64
        Robust robot move (edge index) at each node with the robot on turn, or ``NO_MOVE``.
    human_policy : (n,) int64
        A maximising human move (edge index) at each node with the human on turn.
    value, coop, expected : (n, 2) float64
        Per game state ``[node, player]``: minimax cost, cooperative cost, and expected cost
        of the robust robot policy against a uniformly random human.
    """

    tct: float
    minimax: float
    robot_policy: np.ndarray
    human_policy: np.ndarray
    value: np.ndarray
    coop: np.ndarray
    expected: np.ndarray


def node_order(dag: GameDAG) -> np.ndarray:
    """Topological order of ``dag``; ``arange(n)`` when ids are already topological."""
    if ids_topological(dag):
        return np.arange(dag.n_nodes, dtype=np.int64)
    return topological_order(dag)


def solve(dag: GameDAG) -> Solution:
    """Solve the game exactly: TCT, W*, the robust robot policy and the human's best reply."""
    t = rules.kernel_tables(dag)
    value, coop, expected, robot, human = _solve_kernel(*t.moves, node_order(dag), t.tol)
    return Solution(
        tct=float(coop[dag.start, ROBOT]),
        minimax=float(value[dag.start, ROBOT]),
        robot_policy=robot,
        human_policy=human,
        value=value,
        coop=coop,
        expected=expected,
    )


@dataclass(frozen=True, eq=False)
class PolicyEvaluation:
    """Exact evaluation of a fixed robot policy.

    Attributes
    ----------
    worst : (n, 2) float64
        Cost against an exact best-response human (the certified worst case).
    expected : (n, 2) float64
        Expected cost against a uniformly random human.
    best : (n, 2) float64
        Cost against the most helpful human (the shortest the policy can be).
    human_best_response : (n,) int64
        A maximising human move at each node (ties by lower index).
    """

    worst: np.ndarray
    expected: np.ndarray
    best: np.ndarray
    human_best_response: np.ndarray


def evaluate_policy(dag: GameDAG, robot_policy: np.ndarray | Mapping) -> PolicyEvaluation:
    """Evaluate any robot policy exactly against best-response, random and helpful humans.

    Parameters
    ----------
    robot_policy : (n,) int array of edge indices, or mapping node id -> successor node id
        The robot's move at each node where it is on turn. Every node where the robot has
        a move and that the policy can reach must have a valid entry.

    Raises
    ------
    ValueError
        If the policy names an edge the robot may not take, or has no entry at a node where
        the robot must move.
    """
    policy = as_policy_array(dag, robot_policy)
    t = rules.kernel_tables(dag)
    worst, expected, best, reply = _evaluate_kernel(*t.moves, node_order(dag), policy, t.tol)
    bad = _first_invalid_state(dag, policy, worst)
    if bad >= 0:
        raise GameError(
            f"robot policy has no valid move at node {dag.node_ids[bad]!r}: expected one of "
            f"the robot's out-edges {dag.moves(bad, ROBOT)}, got {int(policy[bad])}"
        )
    return PolicyEvaluation(worst=worst, expected=expected, best=best, human_best_response=reply)


def _first_invalid_state(dag: GameDAG, policy: np.ndarray, worst: np.ndarray) -> int:
    """The first node (in play order) the policy reaches where its robot move is invalid, or
    -1. An invalid entry at a state the game cannot reach does not matter."""
    if not np.isnan(worst[:, ROBOT]).any():
        return -1
    reach = rules.reachable_states(dag, policy)  # stops at an invalid robot move
    e = policy
    lo, hi = dag.indptr[:-1], dag.indptr[1:]
    valid = (e >= lo) & (e < hi)
    valid[valid] = rules.move_mask(dag, ROBOT)[e[valid]]
    bad = reach[:, ROBOT] & rules.has_move(dag)[ROBOT] & ~valid
    order = node_order(dag)
    hits = order[bad[order]]
    return int(hits[0]) if hits.size else -1


def certified_worst_case(dag: GameDAG, robot_policy: np.ndarray | Mapping) -> float:
    """Cost of ``robot_policy`` from the start against an exact best-response human."""
    return float(evaluate_policy(dag, robot_policy).worst[dag.start, ROBOT])


def as_policy_array(dag: GameDAG, policy: np.ndarray | Mapping) -> np.ndarray:
    """Turn a policy into an ``(n,)`` int64 array of edge indices (``NO_MOVE`` elsewhere).

    A mapping is read as node id -> successor node id (the edge taken).
    """
    if isinstance(policy, Mapping):
        out = np.full(dag.n_nodes, NO_MOVE, dtype=np.int64)
        for node, succ in policy.items():
            v = dag.index_of(node)
            w = dag.index_of(succ)
            hits = [e for e in dag.out_edges(v) if dag.targets[e] == w]
            if not hits:
                raise GameError(f"robot policy: no edge from node {node!r} to node {succ!r}")
            out[v] = hits[0]
        return out
    arr = np.asarray(policy, dtype=np.int64)
    if arr.shape != (dag.n_nodes,):
        raise GameError(f"robot policy: expected shape ({dag.n_nodes},), got {arr.shape}")
    return arr


def play(
    dag: GameDAG, robot_policy: np.ndarray, human_policy: np.ndarray
) -> tuple[list[int], float]:
    """Play two deterministic policies from the start; return the node path and its cost."""
    v, player, cost = dag.start, rules.FIRST_PLAYER, 0.0
    path = [v]
    for _ in range(2 * dag.n_nodes + 2):
        if v == dag.end:
            return path, cost
        moves = rules.moves(dag, v, player)
        e = rules.PASS
        if moves:
            e = int((robot_policy if player == ROBOT else human_policy)[v])
            if e not in moves:
                who = rules.player_name(player)
                raise GameError(f"{who} policy has no valid move at node {dag.node_ids[v]!r}")
        v, player, c = rules.step(dag, v, player, e)
        cost += c
        if e != rules.PASS:
            path.append(v)
    raise GameError("play did not reach the end node: is the graph acyclic?")


def robust_path(dag: GameDAG, solution: Solution) -> list:
    """Node ids visited when both sides play minimax (robust robot, maximising human)."""
    path, _ = play(dag, solution.robot_policy, solution.human_policy)
    return [dag.node_ids[v] for v in path]


# --------------------------------------------------------------------------- kernels


@numba.njit(cache=True)
def _solve_kernel(
    indptr, targets, costs, codes, sides, may_side, order, tol
):  # pragma: no cover - compiled
    n = indptr.shape[0] - 1
    value = np.zeros((n, 2))
    coop = np.zeros((n, 2))
    expected = np.zeros((n, 2))
    robot = np.full(n, -1, np.int64)
    human = np.full(n, -1, np.int64)
    for k in range(n - 1, -1, -1):
        v = order[k]
        lo, hi = indptr[v], indptr[v + 1]
        if lo == hi:
            continue
        # Robot on turn: minimise value, tie-break on expected cost, then move index.
        r_val, r_exp, r_coop, r_arg = np.inf, np.inf, np.inf, -1
        # Human on turn: maximise value; expected is the mean over its moves.
        h_val, h_sum, h_coop, h_arg, h_cnt = -np.inf, 0.0, np.inf, -1, 0
        for e in range(lo, hi):
            t = targets[e]
            c = edge_cost(costs, codes, e)
            if may_side[sides[e], ROBOT]:
                val = c + value[t, HUMAN]
                ex = c + expected[t, HUMAN]
                better = r_arg < 0 or (val < r_val and not _close(val, r_val, tol))
                tie_better = _close(val, r_val, tol) and ex < r_exp and not _close(ex, r_exp, tol)
                if better or tie_better:
                    r_val, r_exp, r_arg = val, ex, e
                r_coop = min(r_coop, c + coop[t, HUMAN])
            if may_side[sides[e], HUMAN]:
                val = c + value[t, ROBOT]
                if h_arg < 0 or (val > h_val and not _close(val, h_val, tol)):
                    h_val, h_arg = val, e
                h_sum += c + expected[t, ROBOT]
                h_cnt += 1
                h_coop = min(h_coop, c + coop[t, ROBOT])
        if r_arg >= 0:
            value[v, ROBOT], expected[v, ROBOT], coop[v, ROBOT] = r_val, r_exp, r_coop
            robot[v] = r_arg
        if h_cnt > 0:
            value[v, HUMAN], expected[v, HUMAN], coop[v, HUMAN] = h_val, h_sum / h_cnt, h_coop
            human[v] = h_arg
        # A player without a move passes at zero cost.
        if r_arg < 0:
            value[v, ROBOT], expected[v, ROBOT], coop[v, ROBOT] = (
                value[v, HUMAN],
                expected[v, HUMAN],
                coop[v, HUMAN],
            )
        if h_cnt == 0:
            value[v, HUMAN], expected[v, HUMAN], coop[v, HUMAN] = (
                value[v, ROBOT],
                expected[v, ROBOT],
                coop[v, ROBOT],
            )
    return value, coop, expected, robot, human


@numba.njit(cache=True)
def _evaluate_kernel(
    indptr, targets, costs, codes, sides, may_side, order, policy, tol
):  # pragma: no cover
    n = indptr.shape[0] - 1
    worst = np.zeros((n, 2))
    expected = np.zeros((n, 2))
    best = np.zeros((n, 2))
    reply = np.full(n, -1, np.int64)
    for k in range(n - 1, -1, -1):
        v = order[k]
        lo, hi = indptr[v], indptr[v + 1]
        if lo == hi:
            continue
        robot_moves = False
        h_worst, h_sum, h_best, h_cnt = -np.inf, 0.0, np.inf, 0
        for e in range(lo, hi):
            t = targets[e]
            c = edge_cost(costs, codes, e)
            if may_side[sides[e], ROBOT]:
                robot_moves = True
            if may_side[sides[e], HUMAN]:
                val = c + worst[t, ROBOT]
                if h_cnt == 0 or (val > h_worst and not _close(val, h_worst, tol)):
                    h_worst = val
                    reply[v] = e
                h_sum += c + expected[t, ROBOT]
                h_best = min(h_best, c + best[t, ROBOT])
                h_cnt += 1
        if h_cnt > 0:
            worst[v, HUMAN], expected[v, HUMAN], best[v, HUMAN] = h_worst, h_sum / h_cnt, h_best
        if robot_moves:
            e = policy[v]
            if e < lo or e >= hi or not may_side[sides[e], ROBOT]:
                # Only an error if this state can matter: report it, the caller decides.
                worst[v, ROBOT] = np.nan
                expected[v, ROBOT] = np.nan
                best[v, ROBOT] = np.nan
            else:
                t = targets[e]
                c = edge_cost(costs, codes, e)
                worst[v, ROBOT] = c + worst[t, HUMAN]
                expected[v, ROBOT] = c + expected[t, HUMAN]
                best[v, ROBOT] = c + best[t, HUMAN]
        else:
            worst[v, ROBOT], expected[v, ROBOT], best[v, ROBOT] = (
                worst[v, HUMAN],
                expected[v, HUMAN],
                best[v, HUMAN],
            )
        if h_cnt == 0:
            worst[v, HUMAN], expected[v, HUMAN], best[v, HUMAN] = (
                worst[v, ROBOT],
                expected[v, ROBOT],
                best[v, ROBOT],
            )
    return worst, expected, best, reply
