"""The game DAG: an array-backed directed acyclic graph the robot and the human play on.

Nodes are indexed ``0 .. n-1``; each keeps its original id (an int or a string) in
``node_ids``. Out-edges are stored in CSR form: the edges leaving node ``v`` are
``indptr[v]:indptr[v+1]``, with their heads in ``targets``, their costs in ``costs`` and the
side that may take them in ``sides``.

The edge arrays are as narrow as they can be without changing a value (a game of an
assembly has tens of millions of edges): ``targets`` are int32 while the node count is at
most :data:`INT32_NODES` (so that a game state ``2 * node + player`` still fits), and
``costs`` are float32 when every cost is exactly a float32 (1 per step, whole or binary
fraction seconds), else float64 (:func:`index_dtype`, :func:`compact_costs`). Arithmetic on
them in the solvers is done in float64 (a float32 widens exactly), so every result is the
same as with int64/float64 arrays; :func:`asp.game.rules.move_costs` gives the costs as float64.

The rules of play on it (who may take which edge, passes, the turn, the cost of a move) are
:mod:`asp.game.rules`; the side codes ``ROBOT``, ``HUMAN`` and ``ANY`` come from there. On a
synthetic DAG every edge is ``ANY``.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from functools import cached_property

import networkx as nx
import numba
import numpy as np

from asp.errors import GraphError
from asp.game import rules
from asp.game.rules import ANY, HUMAN, PLAYERS, ROBOT, SIDE_NAMES, side_from_name
from asp.game.turns import ALTERNATE

INT32_NODES = 2**30
"""Up to this many nodes, node indices (``targets``, ``sources``) are stored as int32."""

MAX_COST = 1e12
"""Largest cost of one move (seconds or steps): sums over any path stay exact enough in
float64 and within CP-SAT's integers; larger numbers are refused when a DAG is built."""

__all__ = [
    "ANY",
    "HUMAN",
    "INT32_NODES",
    "MAX_COST",
    "PLAYERS",
    "ROBOT",
    "SIDE_NAMES",
    "CodedCosts",
    "GameDAG",
    "compact_costs",
    "from_arrays",
    "from_edges",
    "from_networkx",
    "index_dtype",
    "ids_topological",
    "reachable",
    "side_from_name",
    "topological_order",
    "validate_dag",
]


class CodedLabels(Sequence):
    """Edge labels stored as an integer code per edge and a table of names.

    A game DAG of an assembly has tens of millions of edges and a few dozen operation ids
    and agents: a tuple of strings would take gigabytes. Reads like a tuple of str (index,
    slice, iterate, ``len``, compare with a tuple).

    Attributes
    ----------
    codes : (m,) int
        Index into ``names`` of each edge's label.
    names : tuple of str
    """

    __slots__ = ("codes", "names")

    def __init__(self, codes, names):
        self.codes = np.asarray(codes)
        self.names = tuple(str(x) for x in names)

    def __len__(self) -> int:
        return int(self.codes.shape[0])

    def __getitem__(self, i):
        if isinstance(i, slice):
            return tuple(self.names[c] for c in self.codes[i].tolist())
        return self.names[int(self.codes[i])]

    def __iter__(self):
        names, step = self.names, 1 << 16
        for lo in range(0, len(self), step):
            yield from (names[c] for c in self.codes[lo : lo + step].tolist())

    def __eq__(self, other) -> bool:
        if isinstance(other, CodedLabels | tuple | list):
            return len(self) == len(other) and all(a == b for a, b in zip(self, other, strict=True))
        return NotImplemented

    __hash__ = None

    def take(self, order: np.ndarray) -> CodedLabels:
        """The labels of the edges ``order`` (an index array), in that order."""
        return CodedLabels(self.codes[order], self.names)

    def __repr__(self) -> str:
        return f"CodedLabels({len(self)} edges, names={self.names!r})"


class CodedCosts:
    """Edge costs stored as a small integer code per edge into a table of distinct costs.

    A game of an assembly has tens of millions of edges but few distinct costs (the
    durations of the operations by each agent): one int8 (or int16) code per edge instead
    of a float32 (a quarter of the memory). Reads like the float array it stands for:
    index it (an int gives one cost, an index array or a slice the costs), ``len``,
    ``shape``, ``size``, ``dtype`` (the table's), comparisons, ``np.asarray`` (the whole
    array, made on each call), ``tolist``, ``astype``, ``min``, ``max``. The compiled
    kernels read ``table[codes[e]]`` (:func:`asp.game.rules.kernel_tables`).

    Attributes
    ----------
    codes : (m,) int8 or int16
        Index into ``table`` of each edge's cost.
    table : (k,) float32 or float64
        The distinct costs (:func:`compact_costs`: float32 only when exact).
    """

    __slots__ = ("codes", "table")

    def __init__(self, codes: np.ndarray, table: np.ndarray) -> None:
        self.codes = np.asarray(codes)
        self.table = compact_costs(table)

    def __len__(self) -> int:
        return int(self.codes.shape[0])

    @property
    def shape(self) -> tuple[int]:
        return self.codes.shape

    @property
    def size(self) -> int:
        return int(self.codes.size)

    @property
    def ndim(self) -> int:
        return 1

    @property
    def dtype(self) -> np.dtype:
        return self.table.dtype

    def __getitem__(self, i):
        return self.table[self.codes[i]]

    def __array__(self, dtype=None, copy=None) -> np.ndarray:
        out = self.table[self.codes]
        return out if dtype is None else out.astype(dtype, copy=False)

    def __iter__(self):
        return iter(np.asarray(self))

    def tolist(self) -> list:
        return np.asarray(self).tolist()

    def astype(self, dtype, copy: bool = True) -> np.ndarray:
        return np.asarray(self, dtype=dtype)

    def min(self):
        return self.table[np.unique(self.codes)].min()

    def max(self):
        return self.table[np.unique(self.codes)].max()

    def __eq__(self, other):
        return np.asarray(self) == other

    def __ne__(self, other):
        return np.asarray(self) != other

    def __lt__(self, other):
        return np.asarray(self) < other

    def __le__(self, other):
        return np.asarray(self) <= other

    def __gt__(self, other):
        return np.asarray(self) > other

    def __ge__(self, other):
        return np.asarray(self) >= other

    __hash__ = None

    def __repr__(self) -> str:
        return f"CodedCosts({len(self)} edges, table={self.table!r})"


@dataclass(frozen=True, eq=False)
class GameDAG:
    """A validated game DAG.

    Attributes
    ----------
    node_ids : tuple or range, length n
        The original id of each node (int or str); a ``range`` when the ids are the indices
        (a game of an assembly: no tuple of millions of ints).
    indptr : (n + 1,) int64
        CSR row pointer: the out-edges of node ``v`` are ``indptr[v]:indptr[v + 1]``.
    targets : (m,) int32 or int64
        Head node index of each edge (:func:`index_dtype`: int32 up to
        :data:`INT32_NODES` nodes).
    costs : (m,) float32 or float64, or CodedCosts
        Cost of each edge (``>= 0``; :func:`compact_costs`: float32 only when every cost is
        exactly a float32, so a cost read from it is the cost given). A game of an
        assembly stores them as :class:`CodedCosts` (a code per edge into a table).
    sides : (m,) int8
        Who may take each edge: ``ROBOT``, ``HUMAN`` or ``ANY``.
    start, end : int
        Start and end node indices.
    operations, agents : tuple of str, :class:`CodedLabels` or None, length m
        Optional edge labels (operation id, agent name).
    node_labels : tuple of str or None, length n
        Optional human-readable node descriptions.
    cost_model : str
        ``"steps"`` or ``"time"``.
    metadata : dict
        Free-form provenance (generator parameters, source file, ...).
    """

    node_ids: tuple
    indptr: np.ndarray
    targets: np.ndarray
    costs: np.ndarray
    sides: np.ndarray
    start: int
    end: int
    operations: tuple[str, ...] | None = None
    agents: tuple[str, ...] | None = None
    node_labels: tuple[str, ...] | None = None
    cost_model: str = "steps"
    turn_model: str = ALTERNATE.name
    metadata: dict = field(default_factory=dict)

    # ------------------------------------------------------------------ sizes
    @property
    def n_nodes(self) -> int:
        return len(self.node_ids)

    @property
    def n_edges(self) -> int:
        return int(self.targets.shape[0])

    @cached_property
    def sources(self) -> np.ndarray:
        """(m,) int, read-only: tail node index of each edge (computed once and kept: on a
        large game prefer :meth:`edge_sources` or a loop over ``indptr``). Same dtype as
        ``targets``."""
        index = np.arange(self.n_nodes, dtype=self.targets.dtype)
        src = np.repeat(index, np.diff(self.indptr))
        src.flags.writeable = False
        return src

    def edge_sources(self, edges) -> np.ndarray:
        """Tail node index (int64) of each edge in ``edges`` (an index array), without
        building :attr:`sources`."""
        edges = np.asarray(edges, dtype=np.int64)
        return np.searchsorted(self.indptr, edges, side="right").astype(np.int64) - 1

    def out_edges(self, v: int) -> range:
        """Edge indices leaving node ``v``."""
        return range(int(self.indptr[v]), int(self.indptr[v + 1]))

    def moves(self, v: int, player: int) -> list[int]:
        """Edge indices player ``player`` may take from node ``v``
        (:func:`asp.game.rules.moves`)."""
        return rules.moves(self, v, player)

    def index_of(self, node_id) -> int:
        """Index of the node whose original id is ``node_id`` (also accepts its str form)."""
        lookup = self._lookup
        if node_id in lookup:
            return lookup[node_id]
        key = str(node_id)
        if key in lookup:
            return lookup[key]
        raise GraphError(f"unknown node {node_id!r}")

    @cached_property
    def _lookup(self) -> dict:
        """Node id (and its str form) -> index, built on first use."""
        lookup: dict = {}
        for i, nid in enumerate(self.node_ids):
            lookup[nid] = i
            lookup.setdefault(str(nid), i)
        return lookup

    def edge_label(self, e: int) -> str:
        """A short description of edge ``e``: operation and agent where known."""
        parts = []
        if self.operations is not None and self.operations[e]:
            parts.append(self.operations[e])
        if self.agents is not None and self.agents[e]:
            parts.append(self.agents[e])
        return " ".join(parts)

    # ---------------------------------------------------------------- convert
    def to_networkx(self) -> nx.DiGraph:
        """A networkx DiGraph keyed by original node ids, edges carrying ``cost`` and labels.

        A graph with parallel edges (two moves between the same nodes) gives a
        ``MultiDiGraph``, so that no move is lost.
        """
        pairs = self.sources.astype(np.int64) * self.n_nodes + self.targets
        kind = nx.MultiDiGraph if np.unique(pairs).size < pairs.size else nx.DiGraph
        g = kind(start=self.node_ids[self.start], end=self.node_ids[self.end])
        g.graph["cost_model"] = self.cost_model
        for i, nid in enumerate(self.node_ids):
            attrs = {"label": self.node_labels[i]} if self.node_labels is not None else {}
            g.add_node(nid, **attrs)
        src = self.sources
        for e in range(self.n_edges):
            attrs = {"cost": float(self.costs[e]), "side": SIDE_NAMES[int(self.sides[e])]}
            if self.operations is not None:
                attrs["operation"] = self.operations[e]
            if self.agents is not None:
                attrs["agent"] = self.agents[e]
            g.add_edge(self.node_ids[src[e]], self.node_ids[int(self.targets[e])], **attrs)
        return g


def from_edges(
    node_ids: Sequence,
    edges: Iterable[tuple],
    *,
    start=None,
    end=None,
    costs: Sequence[float] | None = None,
    sides: Sequence[int] | None = None,
    operations: Sequence[str] | None = None,
    agents: Sequence[str] | None = None,
    node_labels: Sequence[str] | None = None,
    cost_model: str = "steps",
    metadata: dict | None = None,
) -> GameDAG:
    """Build and validate a :class:`GameDAG` from node ids and ``(u, v)`` edge pairs.

    ``start`` / ``end`` default to the one node without in-edges / out-edges. Edge order is
    kept within each node (it fixes move indices and so tie-breaks). Costs default to 1,
    sides to ``ANY``.

    Raises
    ------
    ValueError
        Empty graph, duplicate node, unknown node in an edge, negative or non-finite cost,
        a cycle (one is named), a node other than the end without out-edges, no path from
        start to end, or ambiguous start/end.
    """
    node_ids = tuple(node_ids)
    if not node_ids:
        raise GraphError("empty graph: expected at least one node")
    index: dict = {}
    for i, nid in enumerate(node_ids):
        if nid in index:
            raise GraphError(f"duplicate node {nid!r}")
        index[nid] = i
    edge_list = list(edges)
    m = len(edge_list)
    src = np.empty(m, dtype=np.int64)
    dst = np.empty(m, dtype=np.int64)
    for k, (u, v) in enumerate(edge_list):
        for x in (u, v):
            if x not in index:
                raise GraphError(f"edge ({u!r}, {v!r}) names unknown node {x!r}")
        src[k], dst[k] = index[u], index[v]
    cost_arr = np.ones(m) if costs is None else np.asarray(costs, dtype=np.float64)
    side_arr = np.full(m, ANY, np.int8) if sides is None else np.asarray(sides, dtype=np.int8)
    for name, arr in (("costs", cost_arr), ("sides", side_arr)):
        if arr.shape != (m,):
            raise GraphError(f"{name}: expected {m} values, got shape {arr.shape}")
    for name, labels in (("operations", operations), ("agents", agents)):
        if labels is not None and len(labels) != m:
            raise GraphError(f"{name}: expected {m} labels, got {len(labels)}")
    if node_labels is not None and len(node_labels) != len(node_ids):
        raise GraphError(f"node_labels: expected {len(node_ids)} labels, got {len(node_labels)}")
    return from_arrays(
        node_ids,
        src,
        dst,
        cost_arr,
        side_arr,
        start=None if start is None else _resolve(index, start, "start"),
        end=None if end is None else _resolve(index, end, "end"),
        operations=None if operations is None else tuple(str(x) for x in operations),
        agents=None if agents is None else tuple(str(x) for x in agents),
        node_labels=None if node_labels is None else tuple(str(x) for x in node_labels),
        cost_model=cost_model,
        metadata=metadata,
    )


def _resolve(index: dict, nid, what: str) -> int:
    if nid in index:
        return index[nid]
    for key, i in index.items():
        if str(key) == str(nid):
            return i
    raise GraphError(f"{what} node {nid!r} is not in the graph")


def index_dtype(n_nodes: int) -> type:
    """The dtype of node indices of a DAG with ``n_nodes`` nodes: int32 up to
    :data:`INT32_NODES` (``2 * node + 1`` then still fits), else int64."""
    return np.int32 if n_nodes <= INT32_NODES else np.int64


def compact_costs(costs: np.ndarray) -> np.ndarray:
    """``costs`` as float32 when every value is exactly a float32, else as float64.

    A float32 widens exactly to float64, so the solvers (which add in float64) give the
    same numbers either way.
    """
    costs = np.asarray(costs)
    if costs.dtype == np.float32:
        return np.ascontiguousarray(costs)
    costs = np.ascontiguousarray(costs, dtype=np.float64)
    if _fits_float32(costs):
        return costs.astype(np.float32)
    return costs


def _fits_float32(values: np.ndarray) -> bool:
    step = 1 << 20
    return all(
        np.array_equal(chunk.astype(np.float32), chunk)
        for chunk in (values[lo : lo + step] for lo in range(0, values.size, step))
    )


def ids_topological(dag: GameDAG) -> bool:
    """Whether every edge goes from a lower to a higher node index (without :attr:`sources`)."""
    return dag.n_edges == 0 or _ids_topological(dag.indptr, dag.targets)


@numba.njit(cache=True)
def _ids_topological(indptr, targets):  # pragma: no cover - compiled
    for v in range(indptr.shape[0] - 1):
        for e in range(indptr[v], indptr[v + 1]):
            if targets[e] <= v:
                return False
    return True


def from_arrays(
    node_ids: Sequence,
    src: np.ndarray,
    dst: np.ndarray,
    costs: np.ndarray | None = None,
    sides: np.ndarray | None = None,
    *,
    start: int | None = None,
    end: int | None = None,
    operations: tuple[str, ...] | None = None,
    agents: tuple[str, ...] | None = None,
    node_labels: tuple[str, ...] | None = None,
    cost_model: str = "steps",
    metadata: dict | None = None,
    validate: bool = True,
) -> GameDAG:
    """Build a :class:`GameDAG` from edge arrays of node indices (the fast path).

    Parameters
    ----------
    node_ids : sequence, length n
        A ``range`` is kept as it is; anything else becomes a tuple.
    src, dst : (m,) int
        Tail and head node index of each edge. Edges are stably sorted by tail.
    costs : (m,) float, optional (default 1)
    sides : (m,) int8, optional (default ``ANY``)

    The DAG's ``targets`` and ``costs`` are stored narrow when that loses nothing
    (:func:`index_dtype`, :func:`compact_costs`).
    """
    n = len(node_ids)
    if n == 0:
        raise GraphError("empty graph: expected at least one node")
    src = _indices(src)
    dst = _indices(dst)
    m = src.shape[0]
    if dst.shape != (m,):
        raise GraphError(f"src and dst: expected equal lengths, got {m} and {dst.shape[0]}")
    costs = np.ones(m, np.float32) if costs is None else compact_costs(costs)
    sides = np.full(m, ANY, np.int8) if sides is None else np.asarray(sides, dtype=np.int8)
    if m and (min(src.min(), dst.min()) < 0 or max(src.max(), dst.max()) >= n):
        raise GraphError(f"edge endpoints: expected node indices in [0, {n}), got out of range")
    if m and np.any(src[1:] < src[:-1]):
        order = np.argsort(src, kind="stable")
        src, dst, costs, sides = src[order], dst[order], costs[order], sides[order]
        operations, agents = (_reorder(x, order) for x in (operations, agents))
    indptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(src, minlength=n), out=indptr[1:])
    del src
    if start is None:
        start = _unique_node(
            np.flatnonzero(np.bincount(dst, minlength=n) == 0), node_ids, "start", "in-edges"
        )
    if end is None:
        end = _unique_node(np.flatnonzero(np.diff(indptr) == 0), node_ids, "end", "out-edges")
    dag = GameDAG(
        node_ids=node_ids if isinstance(node_ids, range) else tuple(node_ids),
        indptr=indptr,
        targets=np.ascontiguousarray(dst, dtype=index_dtype(n)),
        costs=costs,
        sides=sides,
        start=int(start),
        end=int(end),
        operations=operations,
        agents=agents,
        node_labels=node_labels,
        cost_model=cost_model,
        metadata=dict(metadata or {}),
    )
    if validate:
        validate_dag(dag)
    return dag


def _indices(x) -> np.ndarray:
    """An index array as given (any integer dtype), else as int64."""
    x = np.asarray(x)
    return x if x.dtype.kind in "iu" else x.astype(np.int64)


def _reorder(labels, order: np.ndarray):
    """Edge labels (a tuple or :class:`CodedLabels`, or None) in the order ``order``."""
    if labels is None:
        return None
    if isinstance(labels, CodedLabels):
        return labels.take(order)
    return tuple(labels[i] for i in order)


def _unique_node(candidates: np.ndarray, node_ids: Sequence, what: str, lacking: str) -> int:
    if candidates.size != 1:
        names = ", ".join(repr(node_ids[i]) for i in candidates[:5])
        raise GraphError(
            f"cannot infer the {what} node: expected exactly one node without {lacking}, "
            f"found {candidates.size}" + (f" ({names})" if candidates.size else "")
        )
    return int(candidates[0])


def topological_order(dag: GameDAG) -> np.ndarray:
    """(n,) int64 node indices in topological order (Kahn's algorithm, vectorised by level).

    Raises ``ValueError`` naming a node on a cycle if the graph is not acyclic.
    """
    n = dag.n_nodes
    indeg = np.bincount(dag.targets, minlength=n).astype(np.int64)
    frontier = np.flatnonzero(indeg == 0)
    out = [frontier]
    seen = frontier.size
    while frontier.size:
        # Edges leaving the frontier, then the heads whose last in-edge was just removed.
        lo, hi = dag.indptr[frontier], dag.indptr[frontier + 1]
        edge_idx = _ranges(lo, hi)
        heads = dag.targets[edge_idx]
        np.subtract.at(indeg, heads, 1)
        frontier = np.unique(heads[indeg[heads] == 0])
        seen += frontier.size
        out.append(frontier)
    if seen != n:
        raise GraphError(f"graph has a cycle: {_cycle_text(dag, dag.sources)}")
    return np.concatenate(out).astype(np.int64)


def _ranges(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Concatenate ``arange(lo[i], hi[i])`` for all i, vectorised."""
    lengths = hi - lo
    total = int(lengths.sum())
    if total == 0:
        return np.empty(0, dtype=np.int64)
    offsets = np.repeat(lo - np.cumsum(lengths) + lengths, lengths)
    return offsets + np.arange(total, dtype=np.int64)


def _cycle_text(dag: GameDAG, src: np.ndarray) -> str:
    g = nx.DiGraph()
    g.add_edges_from(zip(src.tolist(), dag.targets.tolist(), strict=True))
    cycle = nx.find_cycle(g)
    nodes = [dag.node_ids[u] for u, _ in cycle] + [dag.node_ids[cycle[0][0]]]
    return " -> ".join(str(x) for x in nodes)


def validate_dag(dag: GameDAG) -> None:
    """Check the invariants the solvers rely on; raise ``ValueError`` naming the fault."""
    if dag.n_nodes == 0:
        raise GraphError("empty graph: expected at least one node")
    rules.check_cost_model(dag.cost_model)
    if dag.turn_model != ALTERNATE.name:  # a DAG's form: the concurrent game is compiled to it
        raise GraphError(f"turn_model: expected 'alternate', got {dag.turn_model!r}")
    if dag.n_edges:
        bad = np.flatnonzero(~np.isfinite(dag.costs) | (dag.costs < 0) | (dag.costs > MAX_COST))
        if bad.size:
            e = int(bad[0])
            u, v = dag.node_ids[int(dag.sources[e])], dag.node_ids[int(dag.targets[e])]
            raise GraphError(
                f"edge ({u!r}, {v!r}) has negative, non-finite or too large cost "
                f"{dag.costs[e]}: expected 0 to {MAX_COST:g}"
            )
        if np.any((dag.sides < 0) | (dag.sides > ANY)):
            raise GraphError("sides: expected values 0 (robot), 1 (human) or 2 (any)")
        loops = np.flatnonzero(dag.sources == dag.targets)
        if loops.size:
            nid = dag.node_ids[int(dag.targets[loops[0]])]
            raise GraphError(f"graph has a cycle: self-loop at node {nid!r}")
    topological_order(dag)  # raises on a cycle, naming one
    if dag.indptr[dag.end + 1] != dag.indptr[dag.end]:
        raise GraphError(f"end node {dag.node_ids[dag.end]!r} has out-edges")
    if not reachable(dag)[dag.end]:
        raise GraphError(
            f"no path from start {dag.node_ids[dag.start]!r} to end {dag.node_ids[dag.end]!r}"
        )
    dead = np.flatnonzero(np.diff(dag.indptr) == 0)
    dead = dead[dead != dag.end]
    if dead.size:
        raise GraphError(
            f"node {dag.node_ids[int(dead[0])]!r} has no out-edge but is not the end node "
            f"{dag.node_ids[dag.end]!r}"
        )


def reachable(dag: GameDAG, source: int | None = None) -> np.ndarray:
    """(n,) bool: nodes reachable from ``source`` (default: the start), by frontier sweeps."""
    seen = np.zeros(dag.n_nodes, dtype=bool)
    frontier = np.array([dag.start if source is None else source], dtype=np.int64)
    seen[frontier] = True
    while frontier.size:
        heads = dag.targets[_ranges(dag.indptr[frontier], dag.indptr[frontier + 1])]
        heads = np.unique(heads[~seen[heads]])
        seen[heads] = True
        frontier = heads
    return seen


def from_networkx(g: nx.DiGraph, *, start=None, end=None, cost_model: str | None = None) -> GameDAG:
    """Build a :class:`GameDAG` from a networkx DiGraph (or MultiDiGraph).

    Start and end come from the arguments, else the graph attributes ``start`` / ``end``,
    else the one node without in-edges / out-edges. Edge attributes used: ``cost``
    (default 1), ``side`` (``robot``/``human``/``any``, default any), ``operation``, ``agent``.
    Parallel edges of a ``MultiDiGraph`` are distinct moves, as in ``asmplan-dag/1``.
    """
    if not isinstance(g, nx.DiGraph):
        raise GraphError(f"expected a networkx DiGraph, got {type(g).__name__}")
    nodes = list(g.nodes)
    start = g.graph.get("start") if start is None else start
    end = g.graph.get("end") if end is None else end
    edges = list(g.edges(data=True))
    has_ops = any("operation" in d for _, _, d in edges)
    has_agents = any("agent" in d for _, _, d in edges)
    labels = [g.nodes[v].get("label") for v in nodes]
    try:
        costs = [float(d.get("cost", 1.0)) for _, _, d in edges]
    except (TypeError, ValueError) as exc:
        raise GraphError(f"edge cost: expected a number ({exc})") from None
    return from_edges(
        nodes,
        [(u, v) for u, v, _ in edges],
        start=start,
        end=end,
        costs=costs,
        sides=[side_from_name(d.get("side", "any")) for _, _, d in edges],
        operations=[str(d.get("operation", "")) for _, _, d in edges] if has_ops else None,
        agents=[str(d.get("agent", "")) for _, _, d in edges] if has_agents else None,
        node_labels=[str(x) for x in labels] if all(x is not None for x in labels) else None,
        cost_model=cost_model or g.graph.get("cost_model", "steps"),
    )
