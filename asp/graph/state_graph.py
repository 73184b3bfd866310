"""The assembly state graph and the assembly sequence table (AST).

A state is the set of operations done plus the tool values, packed into a key of
``W = ceil(bits / 64)`` uint64 words (:class:`asp.graph.state_keys.OperationModel`;
``W == 1``, up to 64 operations and tool bits, is the fast path). Starting from the empty
assembly, the graph is built breadth-first, one layer (states with ``k`` operations done) at
a time: every state of the layer x every operation is tested at once with bit operations,
the successor keys are computed the same way, and sorting the keys (``np.unique`` on one
word, ``np.lexsort`` on the words otherwise) merges states reached in different orders.

States are numbered layer by layer (sorted by key, as an integer, within a layer), so every
transition goes from a layer to the next, from a lower to a higher index. The number of
complete sequences is counted exactly by dynamic programming over the layers (two layers of
counts in memory at a time), in modular arithmetic over a few primes of at most 57 bits
joined by the Chinese remainder theorem (the count never exceeds ``n_ops!``, which fixes how
many primes are needed), so even astronomically large counts are exact Python ints.
"""

from __future__ import annotations

import functools
import math
import sys
import time
from dataclasses import dataclass

import numpy as np

from asp import heap
from asp.cad_keys import flex_hint
from asp.errors import InfeasibleAssembly, StateLimit
from asp.graph.feasibility import blocked_text, pack_words, unpack_words
from asp.graph.state_keys import OperationModel, operation_model
from asp.spec import DIRECTIONS, AssemblySpec

DEFAULT_MAX_STATES = 20_000_000
"""Above this many states the build stops with a ``ValueError``."""
_CHUNK_CELLS = 1 << 25
"""States x operations tested at once (bounds the enabled-table memory of a layer)."""
STATE_WORD_BYTES = 24
"""Peak bytes of a state per key word: its key, the key's copy when the layers are joined,
and its part set while its layer is the last (:func:`graph_bytes`)."""
LAYER_TRANSITION_BYTES = 40
"""Peak bytes of a transition of the layer being built, over what it keeps once built: the
chunks' moves and successor keys and their merge (measured: free operations, 18 to 24)."""
CHUNKS_IN_LIMIT = 8
"""A chunk's moves (at most its states x operations) take at most this fraction of the
memory limit, so that checking after each chunk overshoots the limit by little."""


def graph_bytes(
    n_states: int, n_transitions: int, in_flight: int = 0, *, n_words: int = 1, wide: bool = False
) -> int:
    """The estimated peak bytes of a state graph of ``n_states`` states (``n_words`` key
    words each) and ``n_transitions`` transitions, ``in_flight`` of them in the layer being
    built (:data:`LAYER_TRANSITION_BYTES` more each); ``wide``: int64 state indices.

    A kept transition costs its source, target and operation and the copy of one of them
    when the layers are joined (13 bytes, 25 when ``wide``); a state
    :data:`STATE_WORD_BYTES` per key word.
    """
    index = 8 if wide else 4
    return (
        int(n_states) * STATE_WORD_BYTES * int(n_words)
        + int(n_transitions) * (3 * index + 1)
        + int(in_flight) * LAYER_TRANSITION_BYTES
    )


def sorted_bounds(src: np.ndarray, states) -> np.ndarray:
    """(k,) int64: the first index of ``src`` (sorted, (E,)) at or after each of ``states``.

    The states are searched in ``src``'s own dtype: numpy would otherwise search an int64
    copy of all of ``src``.
    """
    states = np.asarray(states)
    if states.size and states.max() <= np.iinfo(src.dtype).max:
        states = states.astype(src.dtype, copy=False)
    return np.searchsorted(src, states, side="left").astype(np.int64)


@dataclass(frozen=True, eq=False)
class StateGraph:
    """The assembly state graph.

    Attributes
    ----------
    model : OperationModel
        The compiled spec (key layout, enabled operations).
    keys : (N, W) uint64
        State keys (``W`` words each, see :class:`asp.graph.state_keys.OperationModel`), layer by
        layer; state 0 is the start.
    layer_ptr : (L + 2,) int64
        States of layer ``l`` (``l`` operations done) are ``layer_ptr[l]:layer_ptr[l + 1]``.
    src, dst : (E,) int32
        Transitions (state indices), sorted by ``src``.
    op : (E,) int8 or int16
        Operation index of each transition (int8 up to 127 operations).
    """

    model: OperationModel
    keys: np.ndarray
    layer_ptr: np.ndarray
    src: np.ndarray
    dst: np.ndarray
    op: np.ndarray

    @property
    def spec(self) -> AssemblySpec:
        return self.model.spec

    @property
    def n_states(self) -> int:
        return int(self.keys.shape[0])

    @property
    def n_transitions(self) -> int:
        return int(self.src.shape[0])

    @property
    def parts(self) -> np.ndarray:
        """(N, PW) uint64: assembled-part set of each state (``PW`` words, see
        :class:`asp.graph.feasibility.InsertionOracle`), computed from the keys on each call
        (:meth:`asp.graph.state_keys.OperationModel.parts_of`): not stored, a state's parts are
        those of its done operations."""
        return self.model.parts_of(self.keys)

    @property
    def complete(self) -> np.ndarray:
        """(N,) bool: states with every operation done."""
        return self.model.is_complete(self.keys)

    def key(self, state: int) -> int:
        """The key of a state as a Python int (bit ``i`` = operation ``i`` done, then tools)."""
        return self.model.unpack(self.keys[state])

    @property
    def indptr(self) -> np.ndarray:
        """(N + 1,) int64 CSR row pointer of the transitions by source state."""
        return self.src_bounds(np.arange(self.n_states + 1))

    def src_bounds(self, states: np.ndarray) -> np.ndarray:
        """(k,) int64: the first transition from each of ``states`` (or after them)."""
        return sorted_bounds(self.src, states)

    def coreachable(self) -> np.ndarray:
        """(N,) bool: states from which a complete state can be reached."""
        alive = self.complete.copy()
        if not alive.any():
            return alive
        # Transitions go to higher indices: one sweep from the last layer back suffices.
        bounds = self.src_bounds(self.layer_ptr)
        for layer in range(len(self.layer_ptr) - 2, -1, -1):
            lo, hi = bounds[layer], bounds[layer + 1]
            if lo == hi:
                continue
            s, d = self.src[lo:hi], self.dst[lo:hi]
            alive[s[alive[d]]] = True  # sources are in the layer before their targets
        return alive

    def count_sequences(self) -> int:
        """Exact number of feasible complete operation sequences (a Python int)."""
        from asp.graph.enabled_kernel import add_counts

        done = self.complete
        if not done.any():
            return 0
        n_ops = self.model.n_ops
        primes = _primes_for(n_ops)
        mods = np.array(primes, dtype=np.uint64)
        ptr = self.layer_ptr
        # Transitions only join consecutive layers: keep the counts of one layer at a time.
        counts = np.ones((1, len(primes)), dtype=np.uint64)
        bounds = self.src_bounds(ptr)
        for layer in range(len(ptr) - 2):
            lo, hi = bounds[layer], bounds[layer + 1]
            nxt = np.zeros((int(ptr[layer + 2] - ptr[layer + 1]), len(primes)), dtype=np.uint64)
            if lo < hi:  # compiled: residues added edge by edge
                add_counts(
                    self.src[lo:hi], self.dst[lo:hi], ptr[layer], ptr[layer + 1], counts, mods, nxt
                )
            counts = nxt
        rows = counts[done[ptr[-2] : ptr[-1]]]  # complete states are all in the last layer
        sums = rows.astype(object).sum(axis=0)
        residues = [int(x) % p for x, p in zip(sums, primes, strict=True)]
        return _crt(residues, primes)

    def sequences(self, limit: int = 10) -> list[list[str]]:
        """Up to ``limit`` complete sequences (operation ids), in lexicographic operation order."""
        ids = self.spec.op_ids
        alive = self.coreachable()
        complete = self.complete
        indptr = self.indptr
        out: list[list[str]] = []
        stack: list[tuple[int, list[int]]] = [(0, [])]
        while stack and len(out) < limit:
            v, seq = stack.pop()
            lo, hi = int(indptr[v]), int(indptr[v + 1])
            if lo == hi:
                if complete[v]:
                    out.append([ids[i] for i in seq])
                continue
            for e in range(hi - 1, lo - 1, -1):
                w = int(self.dst[e])
                if alive[w]:
                    stack.append((w, [*seq, int(self.op[e])]))
        return out

    def label(self, state: int) -> str:
        """A readable description of a state: the done operations and the tool values."""
        key = self.key(state)
        done = self.model.done_ops(key)
        text = "{" + " ".join(done) + "}" if done else "start"
        tools = self.model.tool_state(key)
        if tools:
            text += " " + " ".join(f"{k}={v}" for k, v in tools.items())
        return text

    def placed_label(self, state: int, limit: int = 8) -> str:
        """The parts a state has placed, as a person reads them (``placing a, b and 3
        more``; never bare operation ids); ``the start`` when none."""
        spec = self.model.spec
        parts = [p for op in self.model.done_ops(self.key(state)) for p in spec.operation(op).parts]
        if not parts:
            return "the start"
        more = f" and {len(parts) - limit} more" if len(parts) > limit else ""
        return f"placing {', '.join(parts[:limit])}{more}"


PROGRESS_EVERY_S = 1.0
"""With ``progress``, a layer's line is printed at most this often (seconds)."""

PROJECTION_MARGIN = 2
"""A graph whose states are projected (:func:`_projected`) beyond this many times the limit
is stopped before its next layer is built."""


def build_state_graph(
    spec: AssemblySpec,
    relations=None,
    *,
    model: OperationModel | None = None,
    max_states: int | None = None,
    progress: bool = False,
    check: bool = True,
    drop_stuck: bool = False,
    max_memory: int | None = None,
    projection_margin: float = PROJECTION_MARGIN,
) -> StateGraph:
    """Build the state graph of ``spec`` breadth-first, vectorised over each layer.

    Parameters
    ----------
    relations : cad Relations, optional
        Part relations for the geometric checks (none: explicit precedence only).
    model : OperationModel, optional
        A precompiled model (overrides ``relations``).
    max_states : int, optional
        Stop with a one-line ``ValueError`` (states reached, the parts that multiply them,
        how to raise the limit) beyond this many states; a layer sure to go over is not
        built at all. Default: the spec's ``max_states``, else :data:`DEFAULT_MAX_STATES`.
    progress : bool
        Print the key width and, per layer, the states, transitions and seconds on stderr.
    check : bool
        Raise a ``ValueError`` naming the parts that can never be inserted when no complete
        sequence exists.
    drop_stuck : bool
        Leave out the states in which some part still to come is blocked along every
        direction (:meth:`asp.graph.state_keys.OperationModel.stuck`): dead ends, which the game
        drops anyway (TCT and W* do not change), but not the states an infeasibility report
        or the automatic subassemblies look at.
    max_memory : int, optional
        Bytes the build may use (default :func:`asp.heap.memory_budget`: 3/4 of the memory
        available). The estimate (:func:`graph_bytes`) of the graph built so far and of
        the layer being built is checked after every chunk of moves, and of the whole
        graph as projected (:func:`_projected`) after every layer; past the limit the
        build stops with a one-line :class:`asp.errors.StateLimit` naming the estimate,
        the limit, the memory available and ``--max-states``.
    projection_margin : float
        The build stops (:class:`asp.errors.StateLimit`) once the states projected after a
        layer (:func:`_projected`, cautious: it undercounts) exceed this many times
        ``max_states``. Default :data:`PROJECTION_MARGIN`; a caller with a sound answer
        past the limit (:mod:`asp.graph.fasteners`) passes 1, so that a graph sure to go
        over is given up layers earlier (the APLAN toy truck: after layer 12 of 61, 5.2 M
        states and 23 s, instead of layer 13, 11.9 M states, 2.2 GB and 54 s).
    """
    model = operation_model(spec, relations) if model is None else model
    if max_states is None:
        max_states = spec.max_states or DEFAULT_MAX_STATES
    n_ops, n_words = model.n_ops, model.n_words
    index_type = np.int32 if max_states < 2**31 else np.int64
    memory = _Memory(
        heap.memory_budget() if max_memory is None else int(max_memory),
        functools.partial(graph_bytes, n_words=n_words, wide=index_type is np.int64),
        max_states,
    )
    kept = 0  # transitions of the layers built
    keys = model.pack([model.start_key])
    parts = pack_words([model.initial_parts], model.oracle.n_words)
    key_layers = [keys]
    src_l, dst_l, op_l = [], [], []
    offset, total = 0, 1
    t0 = shown = time.perf_counter()
    line = None  # the latest layer's progress line not yet shown
    if progress:
        print(
            f"state graph: {n_ops} operations, {model.n_bits} key bits in {n_words} word(s)",
            file=sys.stderr,
        )
    # a chunk's moves are counted once found: at most an eighth of the memory limit each
    cells = min(_CHUNK_CELLS, memory.limit // (CHUNKS_IN_LIMIT * LAYER_TRANSITION_BYTES))
    chunk = max(1, cells // max(1, n_ops))
    for layer in range(n_ops):
        # chunk by chunk: the enabled moves, their successors (distinct within the chunk,
        # stuck ones dropped) and a lower bound on the layer being built, which stops a
        # layer sure to go over the limit before its transitions pile up in memory
        found = _Layer(index_type)
        for lo in range(0, keys.shape[0], chunk):
            hi = min(lo + chunk, keys.shape[0])
            si, oi = np.nonzero(model.enabled(keys[lo:hi], parts[lo:hi]))
            if si.size:
                si = si.astype(index_type) + index_type(lo)
                found.add(model, keys, parts, si, oi, drop_stuck, layer > 0)
            at_least = total + found.at_least(layer + 1, max_states - total)
            if at_least > max_states:
                raise _too_many(
                    model,
                    keys,
                    max_states,
                    _after(f"at least {at_least:,}", layer, n_ops),
                    relations,
                )
            sizes = (total + found.n_distinct, kept + found.n_transitions, found.n_transitions)
            if memory.over(*sizes):
                raise memory.error(model, keys, sizes, f"while building layer {layer + 1}")
        if found.n_transitions == 0:  # nothing enabled, or every successor is stuck
            break
        si, oi, inv, uniq, new_parts = found.join()
        if total + uniq.shape[0] > max_states:
            raise _too_many(
                model,
                uniq,
                max_states,
                _after(f"{total + uniq.shape[0]:,}", layer, n_ops),
                relations,
            )
        n_new = int(si.size)
        kept += n_new
        src_l.append(si + index_type(offset))
        dst_l.append(inv.astype(index_type) + index_type(offset + keys.shape[0]))
        op_l.append(oi)
        del si, oi, inv, found
        offset += keys.shape[0]
        keys, parts = uniq, new_parts
        key_layers.append(keys)
        total += keys.shape[0]
        line = (
            f"  layer {layer + 1}/{n_ops}: {keys.shape[0]:,} states, {n_new:,} "
            f"transitions ({total:,} states so far, {time.perf_counter() - t0:.1f} s)"
        )
        if progress and time.perf_counter() - shown >= PROGRESS_EVERY_S:
            print(line, file=sys.stderr)
            shown, line = time.perf_counter(), None
        sizes = [k.shape[0] for k in key_layers]
        projected = total + _projected(sizes, n_ops - layer - 1)
        if projected > projection_margin * max_states:
            growth = sizes[-1] / sizes[-2]
            reached = (
                f"{total:,} states after layer {layer + 1} of {n_ops}, the last layer {growth:.1f}"
                f" times the one before: about {projected:,} projected"
            )
            raise _too_many(model, keys, max_states, reached, relations)
        rest = projected - total  # and as many transitions a state as the layer just built
        sizes = (projected, kept + rest * n_new // max(1, keys.shape[0]), 0)
        if memory.over(*sizes):
            reached = f"projected from the {total:,} states after layer {layer + 1} of {n_ops}"
            raise memory.error(model, keys, sizes, reached)
    if progress and line:  # the last layer's line, unless just shown
        print(line, file=sys.stderr)
    layer_ptr = np.zeros(len(key_layers) + 1, dtype=np.int64)
    np.cumsum([k.shape[0] for k in key_layers], out=layer_ptr[1:])
    graph = StateGraph(
        model=model,
        keys=_join(key_layers, np.uint64),
        layer_ptr=layer_ptr,
        src=_join(src_l, index_type),
        dst=_join(dst_l, index_type),
        op=_join(op_l, op_type(n_ops)),
    )
    if check and not graph.complete.any():
        raise InfeasibleAssembly(infeasibility_report(graph))
    return graph


def infeasibility_report(graph: StateGraph) -> str:
    """One line naming the root cause of an assembly with no complete sequence.

    The root cause is the first part (by the layer in which its operation first became
    ready) that can never be inserted for a reason the parts still missing cannot remove
    (blocked along every free direction, or nothing it could touch or rest on even later),
    shown in the fullest state where it was tried: why it fails there, blocked along each
    direction by which parts, and the precedences that put those parts first. Operations
    that only wait for it (their predecessors or the parts they need never come) are
    knock-on failures and are counted, not listed. When every operation is done in some
    state but no order completes them all, the furthest dead end is named with the parts
    it leaves and why each cannot go in. Never an empty list.
    """
    model = graph.model
    spec = model.spec
    n_ops = model.n_ops
    ever = model.unpack(np.bitwise_or.reduce(graph.keys, axis=0)) if graph.n_states else 0
    never = [i for i in range(n_ops) if not ever >> i & 1]
    placed_ever = unpack_words(np.bitwise_or.reduce(graph.parts, axis=0))
    head = f"{spec.source}: infeasible assembly, no complete sequence: "
    head += flex_hint(_locking_pairs(model.oracle))  # the true cause, first
    if not never:
        return head + _dead_end(graph)
    layer_of = np.searchsorted(graph.layer_ptr, np.arange(graph.n_states), side="right") - 1
    found = []  # (root?, first layer, text)
    for i in never:
        op = spec.operations[i]
        rows = np.flatnonzero(model.ready(graph.keys, i))
        if rows.size == 0:
            if not op.parts:
                text = f"operation {op.id} never has its predecessors and tools ready"
                waits = any(not ever >> spec.op_index(a) & 1 for a in op.after)
                found.append((not waits, n_ops, text))
            continue
        if not op.parts:
            continue
        first = int(layer_of[rows].min())
        best = int(rows[np.argmax(layer_of[rows])])  # the fullest state it was tried in
        root, detail = _why_not(graph, i, best, placed_ever)
        names = ", ".join(op.parts)
        text = (
            f"part {names} (operation {op.id}) can never be inserted ({detail}), e.g. "
            f"after {graph.placed_label(best)}"
        )
        found.append((root, first, text))
    found.sort(key=lambda x: (not x[0], x[1]))
    if not found:
        return head + "operations " + ", ".join(spec.operations[i].id for i in never[:5])
    roots = [t for root, _, t in found if root][:2] or [found[0][2]]
    text = "; also ".join(roots)
    others = len(never) - len(roots)
    if others > 0:
        text += f"; {others} more operation(s) never done, knock-on failures of the above"
    return head + text


def never_done(graph: StateGraph) -> list[int]:
    """Operations that place parts, are ready in some state and are done in none."""
    model = graph.model
    ever = model.unpack(np.bitwise_or.reduce(graph.keys, axis=0)) if graph.n_states else 0
    return [
        i
        for i in range(model.n_ops)
        if not ever >> i & 1 and model.part_lists[i] and model.ready(graph.keys, i).any()
    ]


def _locking_pairs(oracle) -> list[tuple[str, str]]:
    """Pairs of parts that block each other along all six directions (no order places
    both), from the oracle's blocking masks."""
    if not oracle.geometric:
        return []
    every = np.bitwise_and.reduce(oracle.blocked, axis=1)  # (n, PW): blocks p everywhere
    masks = [unpack_words(row) for row in every]
    n = len(masks)
    return [
        (oracle.parts[p], oracle.parts[q])
        for p in range(n)
        for q in range(p + 1, n)
        if masks[p] >> q & 1 and masks[q] >> p & 1
    ]


def _why_not(graph: StateGraph, i: int, state: int, placed_ever: int) -> tuple[bool, str]:
    """Whether operation ``i``'s failure in ``state`` is a root cause, and why it fails."""
    model = graph.model
    spec, oracle = model.spec, model.oracle
    op = spec.operations[i]
    keys = graph.keys[state : state + 1]
    assembled, workspace = model.assembled_for(i, model.parts_of(keys), model.pending_units(keys))
    s = unpack_words(assembled[0])
    missing = ((1 << len(oracle.parts)) - 1) & ~placed_ever
    why, root = [], False
    for p in model.part_lists[i]:
        for reason in oracle.reasons(p, s, held=op.held, workspace=workspace):
            name = oracle.parts[p]
            if reason == "no free direction":
                by = oracle.blockers(p, s)
                allowed = {d: v for d, v in by.items() if oracle.directions[DIRECTIONS.index(d)]}
                reason += f" (blocked {blocked_text(allowed)}{_precedences(model, i, allowed)})"
                root = True
            elif reason.startswith("no contact"):
                root |= not missing & oracle.mask(oracle.contact[p])
            elif reason.startswith("nothing to rest on"):
                root |= not missing & oracle.mask(oracle.support[p])
                reason += " (it would fall: mark the operation held if an agent holds the part)"
            else:
                root = True
            why.append(f"{name}: {reason}")
        s |= 1 << p
    return root, "; ".join(why) or "no reason found"


def _precedences(model: OperationModel, i: int, by: dict[str, list[str]]) -> str:
    """``", which the precedence ... puts first"`` for blockers placed by predecessors of i."""
    spec = model.spec
    preds, stack = set(), list(spec.operations[i].after)
    while stack:
        a = stack.pop()
        if a not in preds:
            preds.add(a)
            stack.extend(spec.operation(a).after)
    blockers = {p for names in by.values() for p in names}
    forced = [
        f"{p} by operation {op.id}"
        for op in spec.operations
        if op.id in preds
        for p in op.parts
        if p in blockers
    ]
    return f"; placed first by precedence: {', '.join(forced)}" if forced else ""


def _dead_end(graph: StateGraph) -> str:
    """Every operation is done in some order, none completes: the furthest dead end."""
    model = graph.model
    spec = model.spec
    last = int(graph.layer_ptr[-2])
    key = graph.key(last)
    left = [i for i in range(model.n_ops) if not key >> i & 1]
    why = []
    for i in left[:3]:
        op = spec.operations[i]
        if not op.parts:
            why.append(f"operation {op.id} is not ready")
            continue
        _, detail = _why_not(
            graph, i, last, unpack_words(graph.model.parts_of(graph.keys[last : last + 1])[0])
        )
        why.append(f"part {', '.join(op.parts)} (operation {op.id}) cannot be inserted ({detail})")
    return (
        f"every order ends in a dead end; the furthest, after {graph.placed_label(last)} "
        f"({len(graph.layer_ptr) - 2} of {model.n_ops} operations done), leaves "
        + "; ".join(why)
        + (f" and {len(left) - 3} more" if len(left) > 3 else "")
        + ": another order or a subassembly is needed"
    )


class _Layer:
    """The moves out of one layer, gathered chunk by chunk (:func:`build_state_graph`).

    Each chunk's successors are made distinct within the chunk; across chunks they are
    merged only when the count so far could have crossed the limit (:meth:`at_least`), so
    a layer bound to go over stops as soon as that is certain, with a fraction of its
    moves in memory.
    """

    def __init__(self, index_type):
        self.index_type = index_type
        self.si: list[np.ndarray] = []
        self.oi: list[np.ndarray] = []
        self.inv: list[np.ndarray] = []
        self.keys: list[np.ndarray] = []
        self.parts: list[np.ndarray] = []
        self.n_transitions = 0
        self.n_distinct = 0  # summed over the chunks (an upper bound on the layer)
        self.merged = np.empty((0, 1), dtype=np.uint64)  # distinct keys of merged chunks
        self.n_merged = 0  # chunks merged into it
        self.unmerged = 0  # chunk-distinct keys added since

    def add(self, model, keys, parts, si, oi, drop_stuck: bool, checked: bool = False) -> None:
        """The moves ``si`` (states of the layer) x ``oi`` (operations) of one chunk.

        ``checked``: no state of the layer is stuck (each passed the test when it was
        found), so a successor is tested only for what its new part changes."""
        oi = oi.astype(op_type(model.n_ops))
        succ = model.successor_keys(keys[si], oi)
        firsts, inv = _distinct_rows(succ)
        succ = succ[firsts]
        succ_parts = parts[si[firsts]] | model.op_parts[oi[firsts]]
        if drop_stuck:
            parents = (keys[si[firsts]], parts[si[firsts]]) if checked else None
            keep = ~model.stuck(succ, succ_parts, parents)
            if not keep.all():
                live = keep[inv]
                si, oi, inv = si[live], oi[live], (np.cumsum(keep) - 1)[inv[live]]
                succ, succ_parts = succ[keep], succ_parts[keep]
        if si.size == 0:
            return
        self.si.append(si)
        self.oi.append(oi)
        self.inv.append((inv + self.n_distinct).astype(np.int64))
        self.keys.append(succ)
        self.parts.append(succ_parts)
        self.n_transitions += int(si.size)
        self.n_distinct += int(succ.shape[0])
        self.unmerged += int(succ.shape[0])

    def at_least(self, in_degree: int, room: int) -> int:
        """A lower bound on the states of the layer being built, exact enough to tell
        whether it exceeds ``room``: the moves found over the most moves a state can be
        reached by (``in_degree``), or the distinct successors of the chunks merged so far
        (merged again when the chunks since could have added more than ``room`` allows)."""
        if self.n_merged < len(self.keys) and self.merged.shape[0] + self.unmerged > room:
            fresh = np.concatenate(self.keys[self.n_merged :])
            both = fresh if not self.merged.size else np.concatenate([self.merged, fresh])
            self.merged = both[_distinct_rows(both)[0]]
            self.n_merged, self.unmerged = len(self.keys), 0
        return max(self.merged.shape[0], -(-self.n_transitions // in_degree))

    def join(self):
        """``(si, oi, inv, keys, parts)``: the moves, the index of each one's successor in
        the new layer, and the new layer's keys (sorted) and part sets."""
        cat = np.concatenate
        self.merged = None
        uniq, rank = _unique_rows(cat(self.keys))
        self.keys = []
        new_parts = np.empty((uniq.shape[0], self.parts[0].shape[1]), dtype=np.uint64)
        new_parts[rank] = cat(self.parts)
        self.parts = []
        inv = rank[cat(self.inv)].astype(self.index_type)
        out = (cat(self.si).astype(self.index_type), cat(self.oi), inv, uniq, new_parts)
        self.si = self.oi = self.inv = []
        return out


def op_type(n_ops: int) -> type:
    """The narrowest integer type of a transition's operation index (int8 or int16)."""
    return np.int8 if n_ops <= np.iinfo(np.int8).max else np.int16


def _distinct_rows(keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The index of each distinct row's first occurrence, and each row's distinct number."""
    from asp.graph.enabled_kernel import first_rows

    return first_rows(np.ascontiguousarray(keys))


def _join(layers: list[np.ndarray], dtype) -> np.ndarray:
    """Concatenate the per-layer arrays and empty the list (one array's copy at a time)."""
    out = np.concatenate(layers).astype(dtype, copy=False) if layers else np.empty(0, dtype)
    layers.clear()
    return out


def _unique_rows(keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distinct rows of the (m, W) keys in increasing integer order, and each row's index.

    The rows are first made distinct by hashing (:func:`asp.graph.enabled_kernel.first_rows`,
    linear), then only the distinct ones are sorted (a layer has several times more
    transitions than states).
    """
    from asp.graph.enabled_kernel import first_rows

    firsts, inv = first_rows(np.ascontiguousarray(keys))
    uniq = keys[firsts]
    order = np.lexsort(uniq.T)  # the last word (most significant) is the primary key
    rank = np.empty(order.size, dtype=np.int64)
    rank[order] = np.arange(order.size)
    return uniq[order], rank[inv]


def _projected(sizes: list[int], layers_left: int) -> int:
    """A cautious projection of the states of the layers still to come from the sizes of
    those built (0 while fewer than four layers or no growth).

    The growth ratio of the last layer is projected to fall each layer by the largest fall
    of the last two ratios, and by at least a quarter of its excess over 1 (so at most four
    more growing layers are counted); the layers are counted while they grow. Real graphs
    grow smoothly and fall off more slowly than that (binomial layers of independent parts,
    the reduced drive's 75 layers); a graph still growing several-fold a layer halfway up
    (two independent subsystems multiplied by units built in every interleaving) is
    hopeless long before its layers are built.
    """
    if len(sizes) < 4 or layers_left <= 0:
        return 0
    ratios = [sizes[k + 1] / sizes[k] for k in range(len(sizes) - 4, len(sizes) - 1)]
    ratio = ratios[-1]
    fall = max(ratios[0] - ratios[1], ratios[1] - ratios[2], (ratio - 1) / 4)
    size, out = float(sizes[-1]), 0.0
    for _ in range(layers_left):
        ratio -= fall
        if ratio <= 1:
            break
        size *= ratio
        out += size
    return int(out)


def _after(states: str, layer: int, n_ops: int) -> str:
    return f"{states} states after layer {layer + 1} of {n_ops}"


def _too_many(model: OperationModel, keys: np.ndarray, limit: int, reached: str, relations=None):
    """The one-line error of a state graph over ``max_states``.

    ``keys`` is the last layer built (or about to be): the operations done in some but not
    all of its states are the free choices that multiply the states; the parts they place
    are named, the most balanced choices (done in about half the states) first. ``reached``
    says how many states were reached (or projected) after which layer. When the derived
    precedences prove that the spec has no complete sequence at all
    (:func:`asp.graph.precedences.refutation`, with ``relations``; milliseconds), the error
    says that proof last: no limit would give a plan, and the proof names the cause (the
    two-cylinder engine with its lines: 46 M states projected, and a rocker's halves
    resting only on the pins through them).
    """
    per_state = 8 * model.n_words + 8 * model.oracle.n_words + 8
    return StateLimit(
        f"{model.spec.source}: the state graph exceeds the limit of {limit:,} states: "
        f"{reached}; {_free_choices(model, keys)}; raise max_states (the command line's "
        f"--max-states N or the spec key max_states: N) if memory allows (about {per_state} "
        f"bytes a state plus 10 a transition), or fix their order with precedences (after:) "
        f"or build some of them as subassemblies{_proved_infeasible(model.spec, relations)}"
    )


def _proved_infeasible(spec: AssemblySpec, relations) -> str:
    """``"; but no complete sequence exists: <proof>"`` when the derived precedences of
    ``spec`` prove it (:func:`asp.graph.precedences.refutation`), else ``""``."""
    if relations is None:
        return ""
    from asp.graph.precedences import refutation

    proof = refutation(spec, relations)
    if proof is None:
        return ""
    return (
        "; but no state limit gives a plan: no complete sequence exists, as the derived "
        f"precedences prove ({proof.why})"
    )


def _free_choices(model: OperationModel, keys: np.ndarray) -> str:
    """``the free order of N parts or operations multiplies them (a, b, ...)``: the
    operations done in some but not all of ``keys`` (a layer; 200,000 of them evenly
    spaced at most), the most balanced (done in about half the states) first, by the parts
    they place."""
    spec = model.spec
    done = model.done_matrix(keys[:: max(1, keys.shape[0] // 200_000)]).mean(axis=0)
    free = np.flatnonzero((done > 0) & (done < 1))
    order = free[np.argsort(np.abs(done[free] - 0.5), kind="stable")]
    names = []
    for i in order:
        op = spec.operations[int(i)]
        names.extend(op.parts or (f"operation {op.id}",))
    names = list(dict.fromkeys(names))
    shown = ", ".join(names[:8]) + (f" and {len(names) - 8} more" if len(names) > 8 else "")
    return f"the free order of {len(names)} parts or operations multiplies them ({shown or 'none'})"


@dataclass(frozen=True)
class _Memory:
    """The memory bound of a build (:func:`build_state_graph`): ``limit`` bytes, the
    estimate ``bytes_of(states, transitions, in_flight)`` and the state limit it is named
    with."""

    limit: int
    bytes_of: object
    max_states: int

    def over(self, states: int, transitions: int, in_flight: int) -> bool:
        return self.bytes_of(states, transitions, in_flight) > self.limit

    def error(self, model: OperationModel, keys: np.ndarray, sizes: tuple, when: str):
        """The one-line :class:`StateLimit` of a build over its memory: the estimate from
        ``sizes`` (states, transitions, in flight) ``when`` (which layer), the limit, the
        memory available, how many states fit at this many transitions a state, the state
        limit that allowed more, and the free choices that multiply the states."""
        states, transitions, _ = sizes
        gb = 2**30
        need = self.bytes_of(*sizes)
        each = self.bytes_of(1, transitions / max(1, states))
        fit = int(self.limit / max(1.0, each))
        return StateLimit(
            f"{model.spec.source}: the state graph needs more memory than it may use: "
            f"{need / gb:.2f} GB or more for {states:,} states and {transitions:,} transitions "
            f"({when}), over its limit of {self.limit / gb:.2f} GB "
            f"({heap.available_memory() / gb:.2f} GB available); about {fit:,} states fit, so "
            f"--max-states {self.max_states:,} (or the spec key max_states) cannot be "
            f"reached: {_free_choices(model, keys)}; fix their order with precedences "
            f"(after:) or build some of them as subassemblies"
        )


# --------------------------------------------------------------------------- exact counting

_MAX_PRIME_BITS = 57


def _is_prime(n: int) -> bool:
    if n < 2:
        return False
    small = (2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37)
    for p in small:
        if n % p == 0:
            return n == p
    d, r = n - 1, 0
    while d % 2 == 0:
        d, r = d // 2, r + 1
    for a in small:  # deterministic for n < 3.3e24
        x = pow(a, d, n)
        if x in (1, n - 1):
            continue
        for _ in range(r - 1):
            x = x * x % n
            if x == n - 1:
                break
        else:
            return False
    return True


_PRIMES: dict[int, list[int]] = {}


def _primes_for(n_ops: int) -> list[int]:
    """Enough distinct primes that their product exceeds ``n_ops!``.

    The primes are below ``2**bits`` with ``n_ops * 2**bits <= 2**64``, so summing the counts
    of a state's at most ``n_ops`` predecessors never overflows uint64.
    """
    bits = min(_MAX_PRIME_BITS, 64 - max(1, n_ops).bit_length())
    need = math.lgamma(n_ops + 1) / math.log(2) + 2
    k = max(1, math.ceil(need / (bits - 1)))
    found = _PRIMES.setdefault(bits, [])
    candidate = (1 << bits) - 1 if not found else found[-1] - 2
    while len(found) < k:
        if _is_prime(candidate):
            found.append(candidate)
        candidate -= 2
    return found[:k]


def _crt(residues: list[int], primes: list[int]) -> int:
    x, m = 0, 1
    for r, p in zip(residues, primes, strict=True):
        t = (r - x) * pow(m, -1, p) % p
        x, m = x + m * t, m * p
    return x
