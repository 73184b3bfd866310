"""Drawing a game DAG: nodes laid out by layer, edges coloured by agent, a path highlighted.

Up to :data:`MAX_PLOT_NODES` nodes every node and edge is drawn; above, the graph is drawn
by layers (longest path from the start) with the number of nodes and edges of each layer,
and the highlighted path as the layers it crosses, so a large graph is never silently left
undrawn. What is drawn is a :class:`DagFigure`, small even for a game of millions of edges.
matplotlib is imported lazily and used without pyplot (no global backend is set, no figure
is left open); the PNG is written atomically.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numba
import numpy as np

from asmplan.report.png import write_png
from asp.game.dag import GameDAG, ids_topological
from asp.game.solve import node_order

AGENT_COLOURS = {"H": "#9e9e9e", "R1": "#2e9d4a", "R2": "#f28c28"}
"""The paper's Figure 9 colours: operator grey (white there), R1 green, R2 orange."""
OTHER_COLOURS = ("#3b6fb6", "#8e44ad", "#c0392b", "#16a085")
MAX_PLOT_NODES = 5_000


def node_layers(dag: GameDAG) -> np.ndarray:
    """(n,) int64: length of the longest path from the start to each node."""
    order = np.zeros(0, np.int64)  # node ids already topological: index order, no array
    if not ids_topological(dag):
        order = node_order(dag)
    return _layers_kernel(dag.indptr, dag.targets, order)


@numba.njit(cache=True)
def _layers_kernel(indptr, targets, order):  # pragma: no cover - compiled
    n = indptr.shape[0] - 1
    layer = np.zeros(n, np.int64)
    for k in range(n):
        v = order[k] if order.shape[0] else k
        for e in range(indptr[v], indptr[v + 1]):
            t = targets[e]
            if layer[t] < layer[v] + 1:
                layer[t] = layer[v] + 1
    return layer


@dataclass(frozen=True, eq=False)
class DagFigure:
    """What ``dag.png`` shows of a game DAG and a highlighted path (:func:`dag_figure`).

    A DAG of at most :data:`MAX_PLOT_NODES` nodes is kept whole and drawn node by node;
    a larger one only by its layers (longest path from the start), so the figure of a game
    of millions of edges holds a few small arrays and the game itself can be let go.

    Attributes
    ----------
    n_nodes, n_edges : int
    dag : GameDAG or None
        The DAG, when it is drawn whole.
    highlight : (k,) int64
        The highlighted edges (a DAG drawn whole).
    nodes, edges : (L,) int64 or None
        Nodes of each layer and edges leaving it (a DAG drawn by layers).
    path_layers : (k,) int64 or None
        The layers the highlighted edges join (a DAG drawn by layers).
    """

    n_nodes: int
    n_edges: int
    dag: GameDAG | None = None
    highlight: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    nodes: np.ndarray | None = None
    edges: np.ndarray | None = None
    path_layers: np.ndarray | None = None


def dag_figure(dag: GameDAG, highlight: list[int] | None = None) -> DagFigure:
    """The :class:`DagFigure` of ``dag`` with the edges ``highlight`` marked."""
    hl = np.asarray(highlight if highlight else [], dtype=np.int64)
    if dag.n_nodes <= MAX_PLOT_NODES:
        return DagFigure(dag.n_nodes, dag.n_edges, dag=dag, highlight=hl)
    layer = node_layers(dag)
    nodes, edges = _layer_counts(dag, layer)
    path_layers = np.unique(np.concatenate([layer[dag.edge_sources(hl)], layer[dag.targets[hl]]]))
    return DagFigure(dag.n_nodes, dag.n_edges, nodes=nodes, edges=edges, path_layers=path_layers)


def plot_dag(
    dag: GameDAG,
    path: str | os.PathLike[str],
    *,
    highlight: list[int] | None = None,
    title: str = "",
) -> Path:
    """Draw ``dag`` into the PNG ``path``; ``highlight`` is a list of edge indices.

    Above :data:`MAX_PLOT_NODES` nodes the drawing is by layers (:class:`DagFigure`).
    """
    return draw_dag(dag_figure(dag, highlight), path, title=title)


def draw_dag(figure: DagFigure, path: str | os.PathLike[str], *, title: str = "") -> Path:
    """Draw a :class:`DagFigure` into the PNG ``path``."""
    if figure.dag is None:
        return _draw_layers(figure, path, title)
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    dag = figure.dag
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
    if figure.highlight.size:
        ax.add_collection(
            LineCollection(
                segments[figure.highlight], colors="#d62728", linewidths=3.0, alpha=0.9, zorder=3
            )
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
    return _layer_counts(dag, node_layers(dag))


def _layer_counts(dag: GameDAG, layer: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return _counts_kernel(dag.indptr, layer, int(layer.max()) + 1)


@numba.njit(cache=True)
def _counts_kernel(indptr, layer, n_layers):  # pragma: no cover - compiled
    """Nodes of each layer and edges leaving it (the out-degrees of its nodes)."""
    nodes = np.zeros(n_layers, np.int64)
    edges = np.zeros(n_layers, np.int64)
    for v in range(layer.shape[0]):
        nodes[layer[v]] += 1
        edges[layer[v]] += indptr[v + 1] - indptr[v]
    return nodes, edges


def _draw_layers(figure: DagFigure, path: str | os.PathLike[str], title: str) -> Path:
    """Draw a large DAG by layers: node and edge counts per layer, the path's layers.

    Each layer (longest path from the start) is a bar as high as its node count (log
    scale), labelled with its node and out-edge counts; the highlighted edges mark the
    layers the path goes through.
    """
    from matplotlib.figure import Figure

    nodes, edges = figure.nodes, figure.edges
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
    layers = figure.path_layers
    if layers is not None and layers.size:
        ax.scatter(layers, nodes[layers], s=30, c="#d62728", zorder=4, label="robust plan")
    ax.set_xlabel("layer (longest path from the start)")
    ax.set_ylabel("count (log)")
    ax.set_title(
        (title + "\n" if title else "")
        + f"{figure.n_nodes:,} nodes, {figure.n_edges:,} edges, drawn by layers "
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
    return write_png(fig, path)
