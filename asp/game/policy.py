"""The robust policy of a solved ``alternate`` game as a table (arrays): every state the
robust robot reaches against any human, with its moves, each move named.

:func:`policy_table` finds the states and moves (a numba kernel); :func:`played_policy`
names each move's operation, agent and cost. The plan file (``asmplan.planfile``) only
writes these tables as a document.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numba
import numpy as np

from asp.game import rules
from asp.game.dag import HUMAN, ROBOT, CodedLabels, GameDAG, ids_topological, index_dtype
from asp.game.rules import close_kernel, edge_cost
from asp.game.solve import Solution, node_order
from asp.numbers import plain

StateDescriber = Callable[[int], dict]
"""Node index -> ``{"done": [op ids], "tools": {name: value}, "running": [...]}``."""


@dataclass(frozen=True, eq=False)
class PolicyTable:
    """The reachable game states of the robust policy and their moves (arrays).

    Attributes
    ----------
    node : (S,) int64
        Game DAG node of each state (states in topological order, robot before human).
    turn : (S,) int8
        Side on turn (``ROBOT`` / ``HUMAN``).
    bound : (S,) float64
        Remaining guaranteed cost (the minimax value of the state).
    ptr : (S + 1,) int64
        Moves of state ``i`` are ``ptr[i]:ptr[i + 1]``.
    edge : (M,) int64
        Game DAG edge of each move (``-1``: a pass).
    next : (M,) int64
        State reached by each move.
    instruction : (S,) int64
        At a human state, the move (index into the move arrays) the person is asked to
        make; ``-1`` elsewhere or when the person can only pass.
    """

    node: np.ndarray
    turn: np.ndarray
    bound: np.ndarray
    ptr: np.ndarray
    edge: np.ndarray
    next: np.ndarray
    instruction: np.ndarray


def policy_table(dag: GameDAG, solution: Solution) -> PolicyTable:
    """Every state the robust robot reaches against any human, with its moves."""
    policy = np.asarray(solution.robot_policy, dtype=np.int64)
    reach = rules.reachable_states(dag, policy)
    flat = np.flatnonzero(reach.ravel())  # index v * 2 + p
    del reach
    nodes, turns = flat // 2, flat % 2
    if not ids_topological(dag):  # else the node index is the topological rank
        rank = np.empty(dag.n_nodes, dtype=np.int64)
        rank[node_order(dag)] = np.arange(dag.n_nodes)
        sort = np.lexsort((turns, rank[nodes]))
        nodes, turns = nodes[sort], turns[sort]
        del rank
    index = np.full((dag.n_nodes, 2), -1, dtype=index_dtype(nodes.size))
    index[nodes, turns] = np.arange(nodes.size)
    t = rules.kernel_tables(dag)
    ptr, edge, nxt, instruction = _moves_kernel(
        *t.moves,
        t.tol,
        policy,
        nodes,
        turns.astype(np.int64),
        index,
        solution.value,
        solution.coop,
        dag.end,
    )
    return PolicyTable(
        node=nodes,
        turn=turns.astype(np.int8),
        bound=solution.value[nodes, turns],
        ptr=ptr,
        edge=edge,
        next=nxt,
        instruction=instruction,
    )


@numba.njit(cache=True)
def _moves_kernel(
    indptr,
    targets,
    costs,
    codes,
    sides,
    may_side,
    tol,
    policy,
    nodes,
    turns,
    index,
    value,
    coop,
    end,
):  # pragma: no cover - compiled
    s_count = nodes.shape[0]
    ptr = np.zeros(s_count + 1, np.int64)
    for i in range(s_count):
        v, p = nodes[i], turns[i]
        k = 0
        if v != end:
            if p == ROBOT:
                k = 1
            else:
                for e in range(indptr[v], indptr[v + 1]):
                    if may_side[sides[e], HUMAN]:
                        k += 1
                k = max(k, 1)
        ptr[i + 1] = ptr[i] + k
    edge = np.full(ptr[s_count], -1, np.int64)
    nxt = np.full(ptr[s_count], -1, np.int64)
    instruction = np.full(s_count, -1, np.int64)
    for i in range(s_count):
        v, p = nodes[i], turns[i]
        if v == end:
            continue
        j = ptr[i]
        if p == ROBOT:
            e = policy[v]
            edge[j] = e
            nxt[j] = index[targets[e], HUMAN] if e >= 0 else index[v, HUMAN]
            continue
        best, best_coop = np.inf, np.inf
        for e in range(indptr[v], indptr[v + 1]):
            if may_side[sides[e], HUMAN]:
                t = targets[e]
                edge[j] = e
                nxt[j] = index[t, ROBOT]
                c = edge_cost(costs, codes, e)
                val = c + value[t, ROBOT]
                cv = c + coop[t, ROBOT]
                same = close_kernel(val, best, tol)
                if (
                    instruction[i] < 0
                    or (val < best and not same)
                    or (same and cv < best_coop and not close_kernel(cv, best_coop, tol))
                ):
                    best, best_coop, instruction[i] = val, cv, j
                j += 1
        if j == ptr[i]:  # the person has no move: a pass
            nxt[j] = index[v, ROBOT]
    return ptr, edge, nxt, instruction


@dataclass(frozen=True, eq=False)
class PlayedPolicy:
    """What the plan file takes from a solved game (turn model ``alternate``): the robust
    policy's table with each move named, the game's sizes and its values.

    Its size is the policy's (the states the robust robot reaches against any human), not
    the game's: once it is made (:func:`played_policy`), the game DAG and its solution can be
    let go, and :func:`asmplan.pipeline.played_document` writes the plan file from it.

    Attributes
    ----------
    table : PolicyTable
    operation, agent : (M,) int64
        Each move's operation and agent, indices into ``operations`` and ``agents`` (-1: a
        pass).
    cost : (M,) float64
        Each move's cost (0 for a pass).
    operations, agents : list of str
        The plan file's operation and agent names (``policy.operations``, ``policy.agents``).
    node_ids : list
        The game node id of each state of the table (JSON scalars).
    turn_model, cost_model : str
    n_nodes, n_edges : int
        Size of the game DAG.
    tct, minimax, avg_random : float
        Cooperative cost, W* and the expected cost against a random person, from the start.
    """

    table: PolicyTable
    operation: np.ndarray
    agent: np.ndarray
    cost: np.ndarray
    operations: list[str]
    agents: list[str]
    node_ids: list
    turn_model: str
    cost_model: str
    n_nodes: int
    n_edges: int
    tct: float
    minimax: float
    avg_random: float


def played_policy(
    dag: GameDAG, solution: Solution, describe: StateDescriber | None = None
) -> PlayedPolicy:
    """The :class:`PlayedPolicy` of a solved ``alternate`` game; ``describe`` names its
    states (its end node's done operations join the operation names)."""
    table = policy_table(dag, solution)
    op_names = operation_names(dag, describe)
    op_index = {op: k for k, op in enumerate(op_names)}
    agent_names = sorted(labels_used(dag.agents))
    agent_index = {a: k for k, a in enumerate(agent_names)}
    moves = table.edge >= 0
    move_op = np.full(table.edge.shape, -1, dtype=np.int64)
    move_agent = np.full(table.edge.shape, -1, dtype=np.int64)
    move_cost = np.zeros(table.edge.shape)
    if dag.operations is not None and len(dag.operations):
        move_op[moves] = label_indices(dag.operations, table.edge[moves], op_index)
        if dag.agents is not None:
            move_agent[moves] = label_indices(dag.agents, table.edge[moves], agent_index)
    move_cost[moves] = rules.move_costs(dag, table.edge[moves])
    return PlayedPolicy(
        table=table,
        operation=move_op,
        agent=move_agent,
        cost=move_cost,
        operations=op_names,
        agents=agent_names,
        node_ids=node_id_list(dag, table.node),
        turn_model=dag.turn_model,
        cost_model=dag.cost_model,
        n_nodes=dag.n_nodes,
        n_edges=dag.n_edges,
        tct=solution.tct,
        minimax=solution.minimax,
        avg_random=float(solution.expected[dag.start, ROBOT]),
    )


def node_id_list(dag: GameDAG, nodes: np.ndarray) -> list:
    """The original ids of the nodes ``nodes`` (JSON scalars)."""
    ids = dag.node_ids
    if isinstance(ids, range):
        return (ids.start + nodes.astype(np.int64) * ids.step).tolist()
    return [plain(ids[v]) for v in nodes.tolist()]


def labels_used(labels) -> list[str]:
    """The distinct edge labels, in the order of their first edge (none: empty)."""
    if labels is None:
        return []
    if not isinstance(labels, CodedLabels):
        return list(dict.fromkeys(labels))
    first: dict[int, int] = {}
    step = 1 << 20
    for lo in range(0, len(labels), step):
        codes, at = np.unique(labels.codes[lo : lo + step], return_index=True)
        for c, k in zip(codes.tolist(), at.tolist(), strict=True):
            first.setdefault(c, lo + k)
        if len(first) == len(labels.names):
            break
    return [labels.names[c] for c in sorted(first, key=first.__getitem__)]


def label_indices(labels, edges: np.ndarray, index: dict) -> np.ndarray:
    """(k,) int64: ``index`` of the label of each edge of ``edges`` (-1: not in ``index``)."""
    if isinstance(labels, CodedLabels):
        table = np.array([index.get(name, -1) for name in labels.names], dtype=np.int64)
        return table[labels.codes[edges]]
    return np.array([index.get(labels[e], -1) for e in edges.tolist()], dtype=np.int64)


def operation_names(dag: GameDAG, describe: StateDescriber | None) -> list[str]:
    names = dict.fromkeys(op for op in labels_used(dag.operations) if op)
    if describe is not None:
        names.update(dict.fromkeys(describe(dag.end)["done"]))
    return list(names)
