"""The game DAG type: construction, validation, conversion."""

import networkx as nx
import numpy as np
import pytest

from asp.game.dag import (
    ANY,
    HUMAN,
    ROBOT,
    from_arrays,
    from_edges,
    from_networkx,
    topological_order,
)
from tests.asp.figures import FIGURE4_EDGES, figure4


def test_figure4_structure():
    dag = figure4()
    assert (dag.n_nodes, dag.n_edges) == (9, 11)
    assert dag.node_ids[dag.start] == 1 and dag.node_ids[dag.end] == 9
    out_of_1 = {dag.node_ids[int(dag.targets[e])] for e in dag.out_edges(dag.index_of(1))}
    assert out_of_1 == {2, 3}


def test_start_and_end_are_inferred():
    dag = from_edges(list(range(1, 10)), FIGURE4_EDGES)
    assert dag.node_ids[dag.start] == 1 and dag.node_ids[dag.end] == 9


def test_edges_are_sorted_by_tail_and_keep_their_labels():
    dag = from_edges(
        ["a", "b", "c"],
        [("b", "c"), ("a", "b"), ("a", "c")],
        operations=["2", "1", "3"],
        costs=[5, 1, 7],
    )
    assert dag.indptr.tolist() == [0, 2, 3, 3]
    assert list(dag.operations) == ["1", "3", "2"]
    assert dag.costs.tolist() == [1, 7, 5]


@pytest.mark.parametrize(
    ("nodes", "edges", "kwargs", "message"),
    [
        ([], [], {}, "empty graph"),
        ([1, 2, 3], [(1, 2), (2, 3), (3, 2)], {"start": 1, "end": 3}, "cycle"),
        ([1, 2, 3], [(1, 2), (2, 1), (1, 3)], {"start": 1, "end": 3}, "cycle: 1 -> 2 -> 1"),
        ([1, 2, 3], [(1, 2), (1, 3)], {"start": 1, "end": 3}, "node 2 has no out-edge"),
        ([1, 2], [(1, 5)], {}, "unknown node 5"),
        ([1, 2], [(1, 2)], {"costs": [-1]}, "negative"),
        ([1, 2, 3, 4], [(1, 2), (3, 4)], {"start": 1, "end": 4}, "no path from start 1 to end 4"),
        ([1, 2, 3], [(1, 3), (2, 3)], {}, "start node"),
        ([1, 1], [], {}, "duplicate node"),
        ([1, 2], [(1, 2)], {"start": 7}, "start node 7 is not in the graph"),
    ],
)
def test_validation_errors(nodes, edges, kwargs, message):
    with pytest.raises(ValueError, match=message):
        from_edges(nodes, edges, **kwargs)


def test_networkx_round_trip():
    dag = figure4()
    g = dag.to_networkx()
    assert g.number_of_edges() == 11 and g.graph["start"] == 1
    back = from_networkx(g)
    assert back.node_ids == dag.node_ids
    assert back.targets.tolist() == dag.targets.tolist()


def test_from_networkx_plain_graph_uses_cost_attribute():
    g = nx.DiGraph()
    g.add_edge("s", "a", cost=2.5)
    g.add_edge("a", "t")
    dag = from_networkx(g)
    assert dag.costs.tolist() == [2.5, 1.0]
    assert dag.node_ids[dag.start] == "s" and dag.node_ids[dag.end] == "t"


def test_moves_respect_sides():
    dag = from_edges([0, 1, 2, 3], [(0, 1), (0, 2), (0, 3), (1, 3), (2, 3)], sides=[0, 1, 2, 2, 2])
    assert dag.moves(0, ROBOT) == [0, 2]
    assert dag.moves(0, HUMAN) == [1, 2]
    assert dag.sides.tolist()[2] == ANY


def test_topological_order_is_valid_for_shuffled_ids():
    rng = np.random.default_rng(0)
    n = 200
    perm = rng.permutation(n)
    src, dst = [], []
    for u in range(n - 1):
        for v in rng.choice(np.arange(u + 1, n), size=min(3, n - 1 - u), replace=False):
            src.append(perm[u])
            dst.append(perm[v])
    dag = from_arrays(
        list(range(n)), np.array(src), np.array(dst), start=perm[0], end=perm[-1], validate=False
    )
    position = np.empty(n, dtype=np.int64)
    position[topological_order(dag)] = np.arange(n)
    assert np.all(position[dag.sources] < position[dag.targets])
