"""Drawing a game DAG: nodes laid out by layer, edges coloured by agent, a path highlighted.

matplotlib is imported lazily and used without pyplot (no global backend is set, no figure
is left open); the PNG is written atomically.
"""

from __future__ import annotations

import io
import os
from pathlib import Path

import numpy as np

from asp.atomic import write_bytes
from asp.dag import GameDAG
from asp.errors import GraphError
from asp.solve import node_order

AGENT_COLOURS = {"H": "#9e9e9e", "R1": "#2e9d4a", "R2": "#f28c28"}
"""The paper's Figure 9 colours: operator grey (white there), R1 green, R2 orange."""
OTHER_COLOURS = ("#3b6fb6", "#8e44ad", "#c0392b", "#16a085")
MAX_PLOT_NODES = 5_000


def node_layers(dag: GameDAG) -> np.ndarray:
    """(n,) int64: length of the longest path from the start to each node."""
    layer = np.zeros(dag.n_nodes, dtype=np.int64)
    for v in node_order(dag):
        lo, hi = dag.indptr[v], dag.indptr[v + 1]
        if hi > lo:
            t = dag.targets[lo:hi]
            layer[t] = np.maximum(layer[t], layer[v] + 1)
    return layer


def plot_dag(
    dag: GameDAG,
    path: str | os.PathLike[str],
    *,
    highlight: list[int] | None = None,
    title: str = "",
) -> Path:
    """Draw ``dag`` into the PNG ``path``; ``highlight`` is a list of edge indices.

    Raises
    ------
    ValueError
        More than :data:`MAX_PLOT_NODES` nodes (the drawing would be unreadable).
    """
    if dag.n_nodes > MAX_PLOT_NODES:
        raise GraphError(f"plot: {dag.n_nodes} nodes, at most {MAX_PLOT_NODES} can be drawn")
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    layer = node_layers(dag)
    y = np.zeros(dag.n_nodes)
    for k in np.unique(layer):
        members = np.flatnonzero(layer == k)
        y[members] = np.arange(members.size) - (members.size - 1) / 2
    x = layer.astype(float)
    src = dag.sources
    agents = dag.agents or tuple("" for _ in range(dag.n_edges))
    palette = dict(AGENT_COLOURS)
    for a in sorted(set(agents) - set(palette)):
        palette[a] = OTHER_COLOURS[len(palette) % len(OTHER_COLOURS)]

    width = max(8.0, 0.45 * (layer.max() + 1))
    height = max(4.0, 0.35 * (np.bincount(layer).max() + 1))
    fig = Figure(figsize=(min(width, 40), min(height, 30)), dpi=110)
    ax = fig.subplots()
    segments = np.stack(
        [np.column_stack([x[src], y[src]]), np.column_stack([x[dag.targets], y[dag.targets]])],
        axis=1,
    )
    colours = [palette[a] for a in agents]
    ax.add_collection(LineCollection(segments, colors=colours, linewidths=0.8, alpha=0.6))
    if highlight:
        hl = np.asarray(highlight, dtype=np.int64)
        ax.add_collection(
            LineCollection(segments[hl], colors="#d62728", linewidths=3.0, alpha=0.9, zorder=3)
        )
    ax.scatter(x, y, s=14, c="white", edgecolors="black", linewidths=0.6, zorder=4)
    ax.scatter(x[[dag.start, dag.end]], y[[dag.start, dag.end]], s=50, c="black", zorder=5)
    handles = [Line2D([], [], color=c, lw=2, label=a) for a, c in palette.items() if a in agents]
    handles.append(Line2D([], [], color="#d62728", lw=3, label="robust plan"))
    ax.legend(handles=handles, loc="upper left", fontsize=8, frameon=False)
    ax.set_xlabel("operations done")
    ax.set_yticks([])
    ax.set_title(title or f"game DAG: {dag.n_nodes} nodes, {dag.n_edges} edges", fontsize=10)
    ax.autoscale()
    ax.margins(0.05)
    for side in ("top", "right", "left"):
        ax.spines[side].set_visible(False)
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png")
    return write_bytes(path, buffer.getvalue())
