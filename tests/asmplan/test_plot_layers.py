"""The DAG picture scales: above the node limit it is drawn by layers, never skipped."""

from __future__ import annotations

import numpy as np

import asmplan.report.plot as plot
from asp.game.synth import synthetic_dag


def test_large_dag_is_drawn_by_layers(tmp_path, monkeypatch):
    dag = synthetic_dag(layers=15, max_nodes=10, max_actions=4, seed=3)
    nodes, edges = plot.layer_counts(dag)
    assert nodes.sum() == dag.n_nodes and edges.sum() == dag.n_edges
    assert nodes[0] == 1 and edges[-1] == 0
    monkeypatch.setattr(plot, "MAX_PLOT_NODES", 10)
    out = plot.plot_dag(dag, tmp_path / "dag.png", highlight=[0, 1], title="big")
    assert out.read_bytes()[:4] == b"\x89PNG"


def test_layers_are_longest_paths():
    dag = synthetic_dag(layers=6, max_nodes=5, max_actions=3, seed=1)
    layer = plot.node_layers(dag)
    assert layer[dag.start] == 0
    assert np.all(layer[dag.targets] >= layer[dag.sources] + 1)
