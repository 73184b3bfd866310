"""The compact game DAG (int32 node indices, float32 costs when exact, the CSR written
straight from the state graph) gives the same game and the same solution as the wide one
(int64 / float64 arrays, the edges built with numpy as before)."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from asmplan.pipeline import plan_document
from asp.game import rules
from asp.game.dag import ANY, HUMAN, ROBOT, GameDAG, compact_costs, from_arrays, ids_topological
from asp.game.solve import evaluate_policy, node_order, solve
from asp.graph.feasibility import load_relations
from asp.graph.game_dag import game_dag
from asp.graph.game_states import alternate_states
from asp.graph.state_graph import build_state_graph
from asp.spec import load_spec
from tests.asp.random_games import random_game

PUMP = Path(__file__).resolve().parents[3] / "examples" / "vacuum_pump"
SIDE_CODE = {"robot": ROBOT, "human": HUMAN, "any": ANY}


def wide(dag: GameDAG) -> GameDAG:
    """The same DAG with int64 targets and float64 costs (the representation before)."""
    return dataclasses.replace(
        dag, targets=dag.targets.astype(np.int64), costs=dag.costs.astype(np.float64)
    )


def reference_edges(graph, cost: str) -> dict[str, np.ndarray]:
    """The game's CSR arrays as ``asp.graph.game_dag.game_dag`` built them with numpy
    (int64/float64)."""
    spec, model = graph.spec, graph.model
    alive, done = graph.coreachable(), graph.complete
    keep = alive & ~done
    new_id = np.full(graph.n_states, -1, dtype=np.int64)
    n_inner = int(keep.sum())
    new_id[keep] = np.arange(n_inner)
    new_id[done] = n_inner
    ok = keep[graph.src] & alive[graph.dst]
    e_src, e_dst, e_op = graph.src[ok], graph.dst[ok], graph.op[ok].astype(np.int64)
    names = [a.name for a in spec.agents]
    per_op = np.array([len(op.durations) for op in spec.operations], dtype=np.int64)
    op_first = np.concatenate([[0], np.cumsum(per_op)])
    flat_agent = np.array([names.index(a) for op in spec.operations for a, _ in op.durations])
    flat_time = np.array([d for op in spec.operations for _, d in op.durations], dtype=float)
    reps = per_op[e_op]
    base = np.repeat(np.arange(e_op.shape[0]), reps)
    slot = op_first[e_op[base]] + np.arange(base.size) - np.repeat(np.cumsum(reps) - reps, reps)
    agent = flat_agent[slot]
    costs = np.ones(slot.shape[0]) if cost == "steps" else flat_time[slot]
    if cost != "steps" and model.tool_names:
        change = np.array([spec.tool(t).change_time for t in model.tool_names])
        costs += (model.tool_changes(graph.keys[e_src], e_op) @ change)[base]
    src = new_id[e_src][base]
    indptr = np.zeros(n_inner + 2, dtype=np.int64)
    np.cumsum(np.bincount(src, minlength=n_inner + 1), out=indptr[1:])
    sides = np.array([SIDE_CODE[a.side] for a in spec.agents], dtype=np.int8)[agent]
    return {
        "indptr": indptr,
        "targets": new_id[e_dst][base],
        "costs": costs,
        "sides": sides,
        "operations": e_op[base],
        "agents": agent,
    }


def assert_same_solution(a: GameDAG, b: GameDAG) -> None:
    """Both DAGs solve, evaluate and tabulate to exactly the same numbers."""
    sa, sb = solve(a), solve(b)
    assert (sa.tct, sa.minimax) == (sb.tct, sb.minimax)
    for name in ("robot_policy", "human_policy", "value", "coop", "expected"):
        np.testing.assert_array_equal(getattr(sa, name), getattr(sb, name), err_msg=name)
    ea, eb = evaluate_policy(a, sa.robot_policy), evaluate_policy(b, sb.robot_policy)
    for name in ("worst", "expected", "best", "human_best_response"):
        np.testing.assert_array_equal(getattr(ea, name), getattr(eb, name), err_msg=name)
    np.testing.assert_array_equal(
        rules.reachable_states(a, sa.robot_policy), rules.reachable_states(b, sb.robot_policy)
    )
    np.testing.assert_array_equal(node_order(a), node_order(b))


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    n=st.integers(2, 40),
    fractional=st.booleans(),
    sided=st.booleans(),
)
def test_random_dags_solve_the_same_compact_or_wide(seed, n, fractional, sided):
    dag = random_game(seed, n, fractional=fractional, sided=sided)
    assert dag.targets.dtype == np.int32
    # 0.1 and 0.2 are not float32 numbers: such costs stay float64, exactly as given.
    exact32 = bool(np.all(dag.costs.astype(np.float32) == dag.costs))
    assert dag.costs.dtype == (np.float32 if exact32 else np.float64)
    assert_same_solution(dag, wide(dag))


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(0, 1e12, allow_nan=False), min_size=0, max_size=30))
def test_compact_costs_keep_every_value(values):
    costs = np.array(values, dtype=np.float64)
    compact = compact_costs(costs)
    np.testing.assert_array_equal(compact.astype(np.float64), costs)
    exact = all(float(np.float32(x)) == x for x in values)
    assert compact.dtype == (np.float32 if exact else np.float64)


def test_wide_input_arrays_are_stored_narrow_and_read_back_exactly():
    costs = np.array([1.0, 0.5, 2.25])
    dag = from_arrays(range(3), np.array([0, 0, 1]), np.array([1, 2, 2]), costs, start=0, end=2)
    assert dag.node_ids == range(3)
    assert (dag.targets.dtype, dag.costs.dtype) == (np.int32, np.float32)
    assert rules.move_costs(dag).dtype == np.float64
    assert rules.move_costs(dag).tolist() == costs.tolist()
    assert rules.move_costs(dag, np.array([2])).tolist() == [2.25]
    assert dag.sources.tolist() == [0, 0, 1] and dag.edge_sources([2, 0]).tolist() == [1, 0]
    assert ids_topological(dag)
    assert not ids_topological(
        from_arrays(range(3), [0, 2, 1], [2, 1, 0], start=0, end=0, validate=False)
    )


def specs(shared: Path | None):
    yield "vacuum_pump", PUMP, True
    if shared is not None:
        yield "JACKSON", shared / "salbp" / "JACKSON.IN2", False
        yield "MITCHELL", shared / "salbp" / "MITCHELL.IN2", False
        yield "SAWYER30", shared / "salbp" / "SAWYER30.IN2", False


@pytest.mark.parametrize("cost", ["steps", "time"])
@pytest.mark.parametrize("name", ["vacuum_pump", "JACKSON", "MITCHELL", "SAWYER30"])
def test_real_specs_build_the_same_game_and_solution(name, cost, request):
    shared = Path(__file__).resolve().parents[4] / "shared" / "data"
    found = {k: (p, geo) for k, p, geo in specs(shared if shared.is_dir() else None)}
    if name not in found:
        pytest.skip("shared data not found")
    path, geometry = found[name]
    spec = load_spec(path)
    graph = build_state_graph(spec, load_relations(spec) if geometry else None)
    dag = game_dag(graph, cost=cost)
    ref = reference_edges(graph, cost)
    assert dag.targets.dtype == np.int32
    for key in ("indptr", "targets", "costs", "sides"):
        np.testing.assert_array_equal(getattr(dag, key), ref[key], err_msg=key)
    np.testing.assert_array_equal(dag.operations.codes, ref["operations"])
    np.testing.assert_array_equal(dag.agents.codes, ref["agents"])
    before = from_arrays(
        list(range(dag.n_nodes)),
        np.repeat(np.arange(dag.n_nodes), np.diff(ref["indptr"])),
        ref["targets"],
        ref["costs"],
        ref["sides"],
        start=0,
        end=dag.n_nodes - 1,
        operations=tuple(dag.operations),  # labels as a tuple of str, as before
        agents=tuple(dag.agents),
        cost_model=cost,
    )
    before = wide(before)
    assert_same_solution(dag, before)
    docs = [
        plan_document(spec=spec, dag=d, solution=solve(d), describe=alternate_states(graph, d))
        for d in (dag, before)
    ]
    assert json.dumps(docs[0]) == json.dumps(docs[1])
