"""From the assembly state graph to the game DAG the robot and the human play on.

Nodes are the states from which the assembly can still be completed (dead ends dropped);
every complete state (they may differ in tool values) is merged into one end node. Each
transition ``(state, op)`` becomes one edge per agent allowed to do ``op``, labelled with
the operation id and the agent; its side is the agent's side (``robot``, ``human`` or ``any``)
and its cost 1 (``steps``) or the agent's duration plus the change time of every tool the
operation actually changes (``time``). The turn model (alternating, robot first, zero-cost
passes) is the solver's business (:mod:`asp.solve`).
"""

from __future__ import annotations

import numpy as np

from asp import rules
from asp.dag import ANY, HUMAN, ROBOT, CodedLabels, GameDAG, from_arrays
from asp.errors import GameError
from asp.state_graph import StateGraph

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
    new_id = np.full(graph.n_states, -1, dtype=np.int64)
    n_inner = int(keep.sum())
    new_id[keep] = np.arange(n_inner)
    new_id[done] = n_inner
    n = n_inner + 1
    edge_ok = keep[graph.src] & alive[graph.dst]
    e_src = graph.src[edge_ok]
    e_dst = graph.dst[edge_ok]
    e_op = graph.op[edge_ok].astype(np.int64)

    # One edge per (transition, allowed agent).
    ops = spec.operations
    agent_names = [a.name for a in spec.agents]
    agent_side = np.array([_SIDE_CODE[a.side] for a in spec.agents], dtype=np.int8)
    per_op = np.array([len(op.durations) for op in ops], dtype=np.int64)
    op_first = np.concatenate([[0], np.cumsum(per_op)])
    flat_agent = np.array(
        [agent_names.index(a) for op in ops for a, _ in op.durations], dtype=np.int64
    )
    flat_time = np.array([d for op in ops for _, d in op.durations], dtype=np.float64)
    if np.all(per_op == 1):  # one agent per operation: one edge per transition
        base = slice(None)
        slot = e_op
    else:
        reps = per_op[e_op]
        base = np.repeat(np.arange(e_op.shape[0]), reps)
        within = np.arange(base.shape[0]) - np.repeat(np.cumsum(reps) - reps, reps)
        slot = op_first[e_op[base]] + within
    agent_idx = flat_agent[slot].astype(np.int16)
    sides = agent_side[agent_idx]
    costs = np.ones(slot.shape[0]) if cost == "steps" else flat_time[slot]
    del slot
    if cost != "steps" and model.tool_names:
        change = np.array([spec.tool(t).change_time for t in model.tool_names])
        changed = model.tool_changes(graph.keys[e_src], e_op)
        costs += (changed @ change)[base]
    src = new_id[e_src][base]
    dst = new_id[e_dst][base]
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
    if src.size and not (np.all(src < dst) and np.all(np.isfinite(costs)) and costs.min() >= 0):
        raise GameError(f"{spec.source}: internal: the game DAG is not in topological order")
    return from_arrays(
        list(range(n)),
        src,
        dst,
        costs,
        sides,
        start=0,
        end=n - 1,
        operations=CodedLabels(e_op.astype(np.int16)[base], spec.op_ids),
        agents=CodedLabels(agent_idx, agent_names),
        node_labels=node_labels,
        cost_model=cost,
        metadata=meta,
        validate=False,  # checked below: the construction makes it a DAG in topological order
    )
