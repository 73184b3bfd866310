"""From the assembly state graph to the game DAG the robot and the human play on.

Nodes are the states from which the assembly can still be completed (dead ends dropped);
every complete state (they may differ in tool values) is merged into one end node. Each
transition ``(state, op)`` becomes one edge per agent allowed to do ``op``, labelled with
the operation id and the agent; its side is the agent's side (``robot``, ``human`` or ``any``)
and its cost 1 (``steps``) or the agent's duration plus the change time of every tool the
operation actually changes (``time``). The turn model (alternating, robot first, zero-cost
passes) is the solver's business (:mod:`asp.game.solve`).
"""

from __future__ import annotations

import numba
import numpy as np

from asp.errors import GameError
from asp.game import rules
from asp.game.dag import ANY, HUMAN, ROBOT, CodedCosts, CodedLabels, GameDAG, index_dtype
from asp.graph.state_graph import StateGraph

LABEL_LIMIT = 100_000
"""Above this many nodes labels are left out unless asked for (they cost memory and time)."""

_SIDE_CODE = {"robot": ROBOT, "human": HUMAN, "any": ANY}


def game_dag(
    graph: StateGraph,
    *,
    cost: str | None = None,
    labels: bool | None = None,
    metadata: dict | None = None,
) -> GameDAG:
    """The game DAG of a state graph.

    Parameters
    ----------
    graph : StateGraph
    cost : {"steps", "time"}, optional
        Cost model (default: the spec's).
    labels : bool, optional
        Give nodes readable labels (done operations and tool values); default when the
        graph has at most :data:`LABEL_LIMIT` nodes.
    metadata : dict, optional
        Extra provenance stored in the DAG.

    Returns
    -------
    GameDAG
        Node ids are ints in topological order (0 the start, the last the end); edge
        ``operations`` and ``agents`` are set.
    """
    spec = graph.spec
    model = graph.model
    cost = spec.cost if cost is None else cost
    if cost not in rules.COST_MODELS:
        raise GameError(f"cost: expected 'steps' or 'time', got {cost!r}")
    alive = graph.coreachable()
    done = graph.complete
    # New index: alive states in order, complete ones merged into the last index.
    keep = alive & ~done
    n_inner = int(keep.sum())
    n = n_inner + 1
    index = index_dtype(n)
    new_id = np.full(graph.n_states, -1, dtype=index)
    new_id[keep] = np.arange(n_inner, dtype=index)
    new_id[done] = n_inner
    del done

    # One edge per (transition, allowed agent), written straight into the CSR arrays (the
    # transitions are sorted by source and ``new_id`` keeps their order).
    ops = spec.operations
    agent_names = [a.name for a in spec.agents]
    agent_side = np.array([_SIDE_CODE[a.side] for a in spec.agents], dtype=np.int8)
    per_op = np.array([len(op.durations) for op in ops], dtype=np.int64)
    op_first = np.concatenate([[0], np.cumsum(per_op)])
    agent_code = _code_type(len(agent_names))
    flat_agent = np.array(
        [agent_names.index(a) for op in ops for a, _ in op.durations], dtype=agent_code
    )
    flat_time = np.array([d for op in ops for _, d in op.durations], dtype=np.float64)
    if cost == "steps":
        flat_time = np.ones_like(flat_time)
    extra = np.zeros(0)
    if cost != "steps" and model.tool_names:
        extra = _tool_change_costs(graph, keep, alive)
    indptr, targets, costs, sides, op_codes, agent_idx, ordered = _build_edges(
        graph, keep, alive, new_id, n, per_op, op_first, flat_agent, flat_time, agent_side, extra
    )
    del new_id, extra
    if labels is None:
        labels = n <= LABEL_LIMIT
    node_labels = None
    if labels:
        order = np.flatnonzero(keep)
        node_labels = tuple(graph.label(int(s)) for s in order) + ("complete",)
    meta = {
        "generator": "asmplan.game/1",
        "assembly": spec.name,
        "source": spec.source,
        "states": graph.n_states,
        "transitions": graph.n_transitions,
        "dead_end_states": int((~alive).sum()),
        "turn_model": spec.turn_model,
        "cost": cost,
        "agents": {a.name: a.side for a in spec.agents},
    }
    if spec.credit:
        meta["credit"] = spec.credit
    meta.update(metadata or {})
    if not alive[0]:
        raise GameError(f"{spec.source}: no complete sequence: the game has no path to the end")
    if not ordered:
        raise GameError(f"{spec.source}: internal: the game DAG is not in topological order")
    values = costs.table if isinstance(costs, CodedCosts) else costs
    if values.size and not (np.all(np.isfinite(values)) and values.min() >= 0):
        raise GameError(f"{spec.source}: internal: a move has a negative or non-finite cost")
    # Built as a DAG in topological order (checked above): no validation pass needed.
    return GameDAG(
        node_ids=range(n),
        indptr=indptr,
        targets=targets,
        costs=costs,
        sides=sides,
        start=0,
        end=n - 1,
        operations=CodedLabels(op_codes, spec.op_ids),
        agents=CodedLabels(agent_idx, agent_names),
        node_labels=node_labels,
        cost_model=cost,
        metadata=meta,
    )


def _code_type(n_names: int) -> type:
    """The narrowest integer type of a code into ``n_names`` names (int8 or int16)."""
    return np.int8 if n_names <= np.iinfo(np.int8).max else np.int16


def _tool_change_costs(graph: StateGraph, keep: np.ndarray, alive: np.ndarray) -> np.ndarray:
    """(E,) float64: per transition, the change time of every tool its operation changes
    (0 for the transitions the game drops); computed in chunks of transitions."""
    spec, model = graph.spec, graph.model
    change = np.array([spec.tool(t).change_time for t in model.tool_names])
    out = np.zeros(graph.n_transitions)
    step = 1 << 20
    for lo in range(0, graph.n_transitions, step):
        src, dst = graph.src[lo : lo + step], graph.dst[lo : lo + step]
        ok = np.flatnonzero(keep[src] & alive[dst])
        if ok.size:
            changed = model.tool_changes(graph.keys[src[ok]], graph.op[lo : lo + step][ok])
            out[lo + ok] = changed @ change
    return out


def _build_edges(
    graph, keep, alive, new_id, n, per_op, op_first, flat_agent, flat_time, side, extra
):
    """The game's CSR arrays: ``indptr, targets, costs, sides, operation codes, agent codes``
    and whether every edge goes to a higher node index.

    Without tool changes a move's cost is its (operation, agent) slot's: the costs are
    :class:`asp.game.dag.CodedCosts`, a code per edge into the distinct durations. Else they are
    float32 when every one is exactly a float32 (:func:`asp.game.dag.compact_costs`), else
    float64: built as float32 first, again as float64 when one is not exact.
    """
    counts = _edge_counts(graph.src, graph.dst, graph.op, keep, alive, new_id, per_op, n)
    indptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(counts, out=indptr[1:])
    del counts
    m = int(indptr[-1])
    tables = (graph.src, graph.dst, graph.op, keep, alive, new_id, op_first, flat_agent)
    table, slot_code = np.unique(flat_time, return_inverse=True)
    if extra.shape[0] == 0 and table.size <= np.iinfo(np.int16).max:
        arrays = (
            np.empty(m, new_id.dtype),
            np.empty(m, _code_type(table.size)),
            np.empty(m, np.int8),
            np.empty(m, _code_type(len(graph.spec.operations))),
            np.empty(m, flat_agent.dtype),
        )
        _, ordered = _fill_edges(*tables, slot_code.astype(np.int64), side, extra, *arrays)
        targets, codes, *rest = arrays
        return (indptr, targets, CodedCosts(codes, table), *rest, ordered)
    for cost_type in (np.float32, np.float64):
        arrays = (
            np.empty(m, new_id.dtype),
            np.empty(m, cost_type),
            np.empty(m, np.int8),
            np.empty(m, _code_type(len(graph.spec.operations))),
            np.empty(m, flat_agent.dtype),
        )
        exact, ordered = _fill_edges(*tables, flat_time, side, extra, *arrays)
        if exact:
            return (indptr, *arrays, ordered)
        del arrays
    raise AssertionError("unreachable: float64 costs are exact")


@numba.njit(cache=True)
def _edge_counts(src, dst, op, keep, alive, new_id, per_op, n):  # pragma: no cover - compiled
    counts = np.zeros(n, np.int64)
    for t in range(src.shape[0]):
        s = src[t]
        if keep[s] and alive[dst[t]]:
            counts[new_id[s]] += per_op[op[t]]
    return counts


@numba.njit(cache=True)
def _fill_edges(
    src,
    dst,
    op,
    keep,
    alive,
    new_id,
    op_first,
    flat_agent,
    flat_time,
    side,
    extra,
    targets,
    costs,
    sides,
    op_codes,
    agent_codes,
):  # pragma: no cover - compiled
    k = 0
    exact = True
    ordered = True
    has_extra = extra.shape[0] > 0
    for t in range(src.shape[0]):
        s = src[t]
        if not (keep[s] and alive[dst[t]]):
            continue
        o = op[t]
        head = new_id[dst[t]]
        if head <= new_id[s]:
            ordered = False
        for slot in range(op_first[o], op_first[o + 1]):
            c = flat_time[slot]
            if has_extra:
                c = c + extra[t]
            costs[k] = c
            if costs[k] != c:
                exact = False
            targets[k] = head
            a = flat_agent[slot]
            agent_codes[k] = a
            sides[k] = side[a]
            op_codes[k] = o
            k += 1
    return exact, ordered
