"""Feasibility oracle, assembly state graph, sequence counts and the game DAG."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from asp.game.dag import ANY, HUMAN, ROBOT
from asp.game.solve import solve
from asp.graph.feasibility import insertion_oracle
from asp.graph.game_dag import game_dag
from asp.graph.state_graph import _projected, build_state_graph
from asp.graph.state_keys import operation_model
from asp.spec import spec_from_dict
from tests.asp.helpers_assembly import (
    brute_force_downsets,
    brute_force_sequences,
    precedence_spec,
    relations,
    stack_relations,
    stack_spec,
)


@st.composite
def precedence_sets(draw, max_n=7):
    n = draw(st.integers(1, max_n))
    pairs = draw(
        st.lists(
            st.tuples(st.integers(0, n - 1), st.integers(0, n - 1)).filter(lambda p: p[0] < p[1]),
            max_size=2 * n,
            unique=True,
        )
    )
    return n, pairs


@settings(max_examples=60, deadline=None)
@given(precedence_sets())
def test_counts_match_brute_force(case):
    n, pairs = case
    graph = build_state_graph(precedence_spec(n, pairs))
    assert graph.count_sequences() == brute_force_sequences(n, pairs)
    assert graph.n_states == brute_force_downsets(n, pairs)
    # Every transition adds one operation; states are numbered layer by layer.
    assert np.all(graph.dst > graph.src)
    dag = game_dag(graph)
    assert solve(dag).tct == n


@pytest.mark.parametrize(
    ("n", "pairs", "sequences"),
    [
        (1, [], 1),
        (3, [], 6),
        (3, [(0, 1), (1, 2)], 1),
        (4, [(0, 2), (1, 2), (2, 3)], 2),
        (5, [(0, 1), (0, 2), (0, 3), (0, 4)], 24),
    ],
)
def test_table_of_counts(n, pairs, sequences):
    graph = build_state_graph(precedence_spec(n, pairs))
    assert graph.count_sequences() == sequences
    listed = graph.sequences(limit=1000)
    assert len(listed) == sequences
    assert len({tuple(s) for s in listed}) == sequences
    for seq in listed:
        pos = {int(v): k for k, v in enumerate(seq)}
        assert all(pos[a] < pos[b] for a, b in pairs)


def test_huge_counts_are_exact():
    # 16 independent operations: 16! sequences (the counting runs modulo 57-bit primes).
    graph = build_state_graph(precedence_spec(16, []))
    assert graph.count_sequences() == 20922789888000  # 16!
    assert graph.n_states == 2**16


def test_oracle_rtc_rtt_stability_functional():
    spec = stack_spec()
    oracle = insertion_oracle(spec, stack_relations())
    b, p, s = (oracle.index(x) for x in "BPS")
    sets = np.array([1 << b, (1 << b) | (1 << p), (1 << b) | (1 << s)], dtype=np.uint64)
    assert oracle.feasible(p, sets).tolist() == [True, True, False]
    assert oracle.feasible(s, sets).tolist() == [False, True, False]
    assert oracle.reasons(s, 1 << b) == [
        "no contact with the assembled parts",
        "nothing to rest on below it",
    ]
    assert "no free direction" in oracle.reasons(p, (1 << b) | (1 << s))


def test_stack_has_one_sequence_and_geometry_matters():
    spec = stack_spec()
    graph = build_state_graph(spec, stack_relations())
    assert graph.count_sequences() == 1
    assert graph.sequences() == [["p", "s"]]
    # Without relations only the explicit precedence (none) is left.
    assert build_state_graph(spec).count_sequences() == 2


def test_functional_constraint_and_switch():
    # A part free only along +x, gripper approaches only from +z.
    blocks = [("K", "B", d) for d in ("-x", "+y", "-y", "+z", "-z")]
    rel = relations(("B", "K"), contacts=[("K", "B", "-z")], blocks=blocks)
    data = {
        "parts": [{"id": "B", "file": "b"}, {"id": "K", "file": "k"}],
        "agents": {"R": {"side": "robot"}},
        "base_part": "B",
        "gripper_approach": ["+z"],
        "operations": [{"id": "k", "agents": {"R": 1}, "part": "K"}],
    }
    with pytest.raises(ValueError, match=r"part K \(operation k\) can never be inserted.*gripper"):
        build_state_graph(spec_from_dict(data, source="k.yaml"), rel)
    data["constraints"] = {"functional": False}
    assert build_state_graph(spec_from_dict(data, source="k.yaml"), rel).count_sequences() == 1


@pytest.mark.parametrize(
    ("contacts", "blocks", "reason"),
    [
        ([], [], "no contact"),
        (
            [("K", "B", "-z")],
            [("K", "B", d) for d in ("+x", "-x", "+y", "-y", "+z", "-z")],
            "no free direction",
        ),
        ([("K", "B", "+x")], [], "nothing to rest on"),
    ],
)
def test_infeasible_assembly_names_part_and_reason(contacts, blocks, reason):
    rel = relations(("B", "K"), contacts=contacts, blocks=blocks)
    data = {
        "parts": [{"id": "B", "file": "b"}, {"id": "K", "file": "k"}],
        "agents": {"R": {"side": "robot"}},
        "base_part": "B",
        "operations": [{"id": "k", "agents": {"R": 1}, "part": "K"}],
    }
    with pytest.raises(ValueError, match=reason) as info:
        build_state_graph(spec_from_dict(data, source="k.yaml"), rel)
    assert "part K" in str(info.value) and "\n" not in str(info.value)


def test_held_operations_skip_stability():
    rel = relations(("B", "K"), contacts=[("K", "B", "+z")])  # K hangs under B
    data = {
        "parts": [{"id": "B", "file": "b"}, {"id": "K", "file": "k"}],
        "agents": {"R": {"side": "robot"}},
        "base_part": "B",
        "operations": [{"id": "k", "agents": {"R": 1}, "part": "K", "held": True}],
    }
    assert build_state_graph(spec_from_dict(data, source="k.yaml"), rel).count_sequences() == 1


def toggle_spec(change_time=0):
    """A bit that must be changed for "b" and changed back for "c"."""
    return spec_from_dict(
        {
            "agents": {"H": {"side": "human"}, "R": {"side": "robot"}},
            "tools": {"R.bit": {"initial": "hex", "change_time": change_time}},
            "operations": [
                {"id": "a", "agents": {"R": 2}, "requires": {"R.bit": "hex"}},
                {"id": "x", "agents": {"H": 5}, "sets": {"R.bit": "cross"}},
                {"id": "b", "agents": {"R": 3}, "requires": {"R.bit": "cross"}},
                {"id": "y", "agents": {"H": 5}, "sets": {"R.bit": "hex"}},
            ],
        },
        source="toggle.yaml",
    )


def brute_force_tool_sequences(spec):
    import itertools

    count = 0
    for perm in itertools.permutations(spec.operations):
        bit = "hex"
        ok = True
        for op in perm:
            if any(v != bit for _, v in op.requires):
                ok = False
                break
            for _, v in op.sets:
                bit = v
        count += ok
    return count


def test_tool_states_and_dead_ends():
    spec = toggle_spec()
    graph = build_state_graph(spec)
    assert graph.count_sequences() == brute_force_tool_sequences(spec)
    dag = game_dag(graph)
    # x then y before b leaves the bit on hex for good: b can never run.
    assert dag.metadata["dead_end_states"] > 0
    labels = set(dag.node_labels)
    assert "start R.bit=hex" in labels and "complete" in labels


def test_time_costs_include_tool_changes():
    spec = toggle_spec(change_time=7)
    dag = game_dag(build_state_graph(spec), cost="time")
    for e in range(dag.n_edges):
        op = dag.operations[e]
        assert dag.sides[e] == (HUMAN if dag.agents[e] == "H" else ROBOT)
        base = spec.operation(op).duration(dag.agents[e])
        assert dag.costs[e] in (base, base + 7)
        if op in ("a", "b"):
            assert dag.costs[e] == base
    # Setting the bit to the value it already has costs no change time.
    y_costs = {dag.costs[e] for e in range(dag.n_edges) if dag.operations[e] == "y"}
    assert y_costs == {5.0, 12.0}


def test_one_edge_per_allowed_agent():
    spec = stack_spec()
    dag = game_dag(build_state_graph(spec, stack_relations()), cost="time")
    first = [
        (dag.operations[e], dag.agents[e], dag.costs[e], int(dag.sides[e]))
        for e in dag.out_edges(dag.start)
    ]
    assert sorted(first) == [("p", "H", 3.0, HUMAN), ("p", "R", 2.0, ROBOT)]
    assert dag.cost_model == "time" and dag.n_nodes == 3


def test_any_side_for_open_tasks():
    dag = game_dag(build_state_graph(precedence_spec(3, [(0, 1)])))
    assert set(dag.sides.tolist()) == {ANY}
    assert set(dag.agents) == {"any"}


def test_more_than_64_operations_take_two_words():
    model = operation_model(precedence_spec(65, [(k, k + 1) for k in range(64)]))
    assert model.n_words == 2 and model.op_bits.shape == (65, 2)
    graph = build_state_graph(precedence_spec(65, [(k, k + 1) for k in range(64)]))
    assert graph.keys.shape == (66, 2) and graph.count_sequences() == 1


def test_state_limit():
    # 10 free operations: 1 + 10 + 45 = 56 states after layer 2, 176 after layer 3.
    with pytest.raises(ValueError, match="exceeds the limit of 100 states") as info:
        build_state_graph(precedence_spec(10, []), max_states=100)
    message = str(info.value)
    assert "176 states after layer 3 of 10" in message and "raise max_states" in message
    assert "\n" not in message


def test_figure2_unfolding_one_state_per_set_of_done_operations():
    # Paper, Figure 2: A -> B -> C and A -> C -> B are both admissible. The unfolding has
    # one state per set of done operations ({}, {A}, {A,B}, {A,C}, {A,B,C}): both orders
    # meet again in {A,B,C} instead of duplicating it.
    graph = build_state_graph(precedence_spec(3, [(0, 1), (0, 2)]))
    assert graph.n_states == 5 and graph.n_transitions == 5
    assert graph.count_sequences() == 2
    assert sorted(map(tuple, graph.sequences(limit=10))) == [("0", "1", "2"), ("0", "2", "1")]
    dag = game_dag(graph)
    in_degree = np.bincount(dag.targets, minlength=dag.n_nodes)
    assert in_degree[dag.end] == 2 and dag.n_nodes == 5


def test_a_hopeless_graph_stops_on_its_growth():
    # 40 free operations: layers C(40, k); after layer 5 (760,099 states) the last layer
    # is 7.2 times the one before: far more than 2 x 1,000,000 states are on their way
    with pytest.raises(ValueError, match="exceeds the limit of 1,000,000 states") as info:
        build_state_graph(precedence_spec(40, []), max_states=1_000_000)
    message = str(info.value)
    assert "760,099 states after layer 5 of 40" in message and "projected" in message
    assert "raise max_states" in message and "\n" not in message
    # 24 free operations fit (2**24 states): growth that dies down is not projected over
    assert _projected([1, 24, 276, 2024, 10626], 20) < 20_000_000
