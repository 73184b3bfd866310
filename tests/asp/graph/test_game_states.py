"""The names of the game DAG's states (:mod:`asp.graph.game_states`)."""

from __future__ import annotations

import numpy as np
import pytest


def test_state_names_kept_for_some_nodes_are_those_of_every_node():
    """``AlternateStates.only``: the plan's states keep their names (and no other's)."""
    from asmplan import pipeline
    from asp.graph.game_states import alternate_states
    from tests.conftest import REPO

    graph = pipeline.state_graph(pipeline.load(REPO / "examples" / "vacuum_pump"))
    dag = pipeline.game(graph)
    every = alternate_states(graph, dag)
    nodes = np.array([dag.end, 0, 3, 3])
    some = every.only(nodes)
    assert some.state_of.size == 3
    for v in nodes.tolist():
        assert some(v) == every(v)
    assert np.array_equal(some.done_matrix(nodes), every.done_matrix(nodes))
    with pytest.raises(KeyError, match="not among"):
        some(1)
