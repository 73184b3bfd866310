"""Drawing a game DAG: nodes laid out by layer, edges coloured by agent, a path highlighted.

Up to :data:`MAX_PLOT_NODES` nodes every node and edge is drawn; above, the graph is drawn
by layers (longest path from the start) with the number of nodes and edges of each layer,
and the highlighted path as the layers it crosses, so a large graph is never silently left
undrawn. matplotlib is imported lazily and used without pyplot (no global backend is set, no figure
is left open); the PNG is written atomically.
"""

from __future__ import annotations

import io
import os
from pathlib import Path

import numba
import numpy as np

from asp.atomic import write_bytes
from asp.dag import GameDAG
from asp.solve import node_order

AGENT_COLOURS = {"H": "#9e9e9e", "R1": "#2e9d4a", "R2": "#f28c28"}
"""The paper's Figure 9 colours: operator grey (white there), R1 green, R2 orange."""
OTHER_COLOURS = ("#3b6fb6", "#8e44ad", "#c0392b", "#16a085")
MAX_PLOT_NODES = 5_000


def node_layers(dag: GameDAG) -> np.ndarray:
    """(n,) int64: length of the longest path from the start to each node."""
    return _layers_kernel(dag.indptr, dag.targets, node_order(dag))


@numba.njit(cache=True)
def _layers_kernel(indptr, targets, order):  # pragma: no cover - compiled
    layer = np.zeros(indptr.shape[0] - 1, np.int64)
    for v in order:
        for e in range(indptr[v], indptr[v + 1]):
            t = targets[e]
            if layer[t] < layer[v] + 1:
                layer[t] = layer[v] + 1
    return layer


def plot_dag(
    dag: GameDAG,
    path: str | os.PathLike[str],
    *,
    highlight: list[int] | None = None,
    title: str = "",
) -> Path:
    """Draw ``dag`` into the PNG ``path``; ``highlight`` is a list of edge indices.

    Above :data:`MAX_PLOT_NODES` nodes the drawing is by layers (:func:`plot_layers`).
    """
    if dag.n_nodes > MAX_PLOT_NODES:
        return plot_layers(dag, path, highlight=highlight, title=title)
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
    return _save(fig, path)


def layer_counts(dag: GameDAG) -> tuple[np.ndarray, np.ndarray]:
    """Nodes per layer and edges leaving each layer: two ``(L,)`` int64 arrays."""
    layer = node_layers(dag)
    n_layers = int(layer.max()) + 1
    nodes = np.bincount(layer, minlength=n_layers)
    # Edges leaving a layer: the out-degrees of its nodes (no per-edge array).
    degree = np.diff(dag.indptr)
    edges = np.bincount(layer, weights=degree, minlength=n_layers).round().astype(np.int64)
    return nodes.astype(np.int64), edges.astype(np.int64)


def plot_layers(
    dag: GameDAG,
    path: str | os.PathLike[str],
    *,
    highlight: list[int] | None = None,
    title: str = "",
) -> Path:
    """Draw a large ``dag`` by layers: node and edge counts per layer, the path's layers.

    Each layer (longest path from the start) is a bar as high as its node count (log
    scale), labelled with its node and out-edge counts; the highlighted edges mark the
    layers the path goes through.
    """
    from matplotlib.figure import Figure

    layer = node_layers(dag)
    nodes, edges = layer_counts(dag)
    x = np.arange(nodes.size)
    fig = Figure(figsize=(min(max(8.0, 0.4 * nodes.size), 40), 5), dpi=110)
    ax = fig.subplots()
    ax.bar(x, nodes, color="#9ecae1", edgecolor="#3b6fb6", label="nodes per layer")
    ax.plot(x, np.maximum(edges, 1), "o-", color="#f28c28", ms=3, lw=1, label="edges leaving")
    ax.set_yscale("log")
    for k in x:
        ax.annotate(
            f"{nodes[k]:,}\n{edges[k]:,}e",
            (k, nodes[k]),
            ha="center",
            va="bottom",
            fontsize=6,
            xytext=(0, 2),
            textcoords="offset points",
        )
    if highlight:
        hl = np.asarray(highlight, dtype=np.int64)
        layers = np.unique(np.concatenate([layer[dag.edge_sources(hl)], layer[dag.targets[hl]]]))
        ax.scatter(layers, nodes[layers], s=30, c="#d62728", zorder=4, label="robust plan")
    ax.set_xlabel("layer (longest path from the start)")
    ax.set_ylabel("count (log)")
    ax.set_title(
        (title + "\n" if title else "")
        + f"{dag.n_nodes:,} nodes, {dag.n_edges:,} edges, drawn by layers "
        f"(more than {MAX_PLOT_NODES:,} nodes)",
        fontsize=10,
    )
    ax.legend(loc="upper left", fontsize=8, frameon=False)
    for side in ("top", "right"):
        ax.spines[side].set_visible(False)
    return _save(fig, path)


def _save(fig, path: str | os.PathLike[str]) -> Path:
    """Write the matplotlib Figure ``fig`` as a PNG atomically."""
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png")
    return write_bytes(path, buffer.getvalue())
