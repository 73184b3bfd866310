"""The synthetic generator of the paper's section 3.2."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from asp.game.synth import synthetic_dag

PAPER_SIZES = [(4, 10), (10, 4), (10, 10), (15, 10), (20, 10), (20, 20)]


@pytest.mark.parametrize(("layers", "max_nodes"), PAPER_SIZES)
def test_same_seed_same_graph(layers, max_nodes):
    a = synthetic_dag(layers, max_nodes, 4, seed=11)
    b = synthetic_dag(layers, max_nodes, 4, seed=11)
    assert a.indptr.tolist() == b.indptr.tolist()
    assert a.targets.tolist() == b.targets.tolist()


def test_different_seeds_differ():
    graphs = {synthetic_dag(15, 10, 4, seed=s).targets.tobytes() for s in range(5)}
    assert len(graphs) == 5


@settings(max_examples=40, deadline=None)
@given(
    layers=st.integers(1, 20),
    max_nodes=st.integers(1, 12),
    max_actions=st.integers(1, 5),
    seed=st.integers(0, 10_000),
)
def test_structure_invariants(layers, max_nodes, max_actions, seed):
    dag = synthetic_dag(layers, max_nodes, max_actions, seed=seed)
    n = dag.n_nodes
    layer = np.asarray(dag.metadata["layer_of"])
    assert dag.start == 0 and dag.end == n - 1
    assert layer[0] == 0 and layer[-1] == layers + 1
    out_degree = np.diff(dag.indptr)
    assert np.all(out_degree[:-1] >= 1) and np.all(out_degree <= max_actions)
    assert out_degree[-1] == 0
    in_degree = np.bincount(dag.targets, minlength=n)
    assert in_degree[0] == 0 and np.all(in_degree[1:] >= 1)
    assert np.all(layer[dag.targets] > layer[dag.sources])  # edges go to later layers
    assert np.all(np.diff(layer) >= 0)  # ids layer by layer
    assert np.all(np.bincount(layer)[1:-1] <= max_nodes)
    # Skips land on inner layers: the start never links straight to the end.
    assert dag.end not in dag.targets[dag.indptr[0] : dag.indptr[1]] or layers == 0


@pytest.mark.parametrize("bad", [{"layers": 0}, {"max_nodes": -1}, {"max_actions": 0}])
def test_bad_parameters(bad):
    params = {"layers": 3, "max_nodes": 3, "max_actions": 2} | bad
    with pytest.raises(ValueError, match=next(iter(bad))):
        synthetic_dag(**params)
