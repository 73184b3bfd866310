"""The assembly state graph and the assembly sequence table (AST).

A state is the set of operations done plus the tool values, packed into one uint64 key
(:class:`asp.feasibility.OperationModel`). Starting from the empty assembly, the graph is
built breadth-first, one layer (states with ``k`` operations done) at a time: every state of
the layer x every operation is tested at once with bit operations, the successor keys are
computed the same way, and ``np.unique`` merges states reached in different orders.

States are numbered layer by layer (sorted by key within a layer), so every transition goes
from a lower to a higher index. The number of complete sequences is counted exactly by
dynamic programming over the layers, in modular arithmetic over a few 57-bit primes joined
by the Chinese remainder theorem (the count never exceeds ``n_ops!``, which fixes how many
primes are needed), so even astronomically large counts are exact Python ints.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass

import numpy as np

from asp.feasibility import OperationModel, operation_model
from asp.spec import AssemblySpec

DEFAULT_MAX_STATES = 20_000_000
"""Above this many states the build stops with a ``ValueError``."""


@dataclass(frozen=True, eq=False)
class StateGraph:
    """The assembly state graph.

    Attributes
    ----------
    model : OperationModel
        The compiled spec (key layout, enabled operations).
    keys : (N,) uint64
        State keys, layer by layer; state 0 is the start.
    parts : (N,) uint64
        Assembled-part bitset of each state.
    layer_ptr : (L + 2,) int64
        States of layer ``l`` (``l`` operations done) are ``layer_ptr[l]:layer_ptr[l + 1]``.
    src, dst : (E,) int32
        Transitions (state indices), sorted by ``src``.
    op : (E,) int16
        Operation index of each transition.
    """

    model: OperationModel
    keys: np.ndarray
    parts: np.ndarray
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
    def complete(self) -> np.ndarray:
        """(N,) bool: states with every operation done."""
        mask = np.uint64(self.model.done_mask)
        return (self.keys & mask) == mask

    @property
    def indptr(self) -> np.ndarray:
        """(N + 1,) int64 CSR row pointer of the transitions by source state."""
        return np.searchsorted(self.src, np.arange(self.n_states + 1), side="left").astype(np.int64)

    def coreachable(self) -> np.ndarray:
        """(N,) bool: states from which a complete state can be reached."""
        alive = self.complete.copy()
        if not alive.any():
            return alive
        # Transitions go to higher indices: one sweep from the last layer back suffices.
        bounds = np.searchsorted(self.src, self.layer_ptr)
        for layer in range(len(self.layer_ptr) - 2, -1, -1):
            lo, hi = bounds[layer], bounds[layer + 1]
            if lo == hi:
                continue
            s, d = self.src[lo:hi], self.dst[lo:hi]
            hit = np.zeros(self.n_states, dtype=bool)
            hit[s[alive[d]]] = True
            alive |= hit
        return alive

    def count_sequences(self) -> int:
        """Exact number of feasible complete operation sequences (a Python int)."""
        done = self.complete
        if not done.any():
            return 0
        primes = _primes_for(self.model.n_ops)
        mods = np.array(primes, dtype=np.uint64)
        counts = np.zeros((self.n_states, len(primes)), dtype=np.uint64)
        counts[0] = 1
        bounds = np.searchsorted(self.src, self.layer_ptr)
        for layer in range(len(self.layer_ptr) - 1):
            lo, hi = bounds[layer], bounds[layer + 1]
            if lo == hi:
                continue
            d = self.dst[lo:hi]
            order = np.argsort(d, kind="stable")
            d_sorted = d[order]
            vals = counts[self.src[lo:hi][order]]
            starts = np.flatnonzero(np.r_[True, d_sorted[1:] != d_sorted[:-1]])
            # Each term < 2**57 and at most 64 terms: the sum fits uint64.
            sums = np.add.reduceat(vals, starts, axis=0) % mods
            counts[d_sorted[starts]] = sums
        total = np.zeros(len(primes), dtype=object)
        for row in counts[done]:
            total += row.astype(object)
        residues = [int(r) % p for r, p in zip(total, primes, strict=True)]
        return _crt(residues, primes)

    def sequences(self, limit: int = 10) -> list[list[str]]:
        """Up to ``limit`` complete sequences (operation ids), in lexicographic operation order."""
        ids = self.spec.op_ids
        alive = self.coreachable()
        indptr = self.indptr
        out: list[list[str]] = []
        stack: list[tuple[int, list[int]]] = [(0, [])]
        while stack and len(out) < limit:
            v, seq = stack.pop()
            lo, hi = int(indptr[v]), int(indptr[v + 1])
            if lo == hi:
                if self.complete[v]:
                    out.append([ids[i] for i in seq])
                continue
            for e in range(hi - 1, lo - 1, -1):
                w = int(self.dst[e])
                if alive[w]:
                    stack.append((w, [*seq, int(self.op[e])]))
        return out

    def label(self, state: int) -> str:
        """A readable description of a state: the done operations and the tool values."""
        key = int(self.keys[state])
        done = self.model.done_ops(key)
        text = "{" + " ".join(done) + "}" if done else "start"
        tools = self.model.tool_state(key)
        if tools:
            text += " " + " ".join(f"{k}={v}" for k, v in tools.items())
        return text


def build_state_graph(
    spec: AssemblySpec,
    relations=None,
    *,
    model: OperationModel | None = None,
    max_states: int = DEFAULT_MAX_STATES,
    progress: bool = False,
    check: bool = True,
) -> StateGraph:
    """Build the state graph of ``spec`` breadth-first, vectorised over each layer.

    Parameters
    ----------
    relations : cad Relations, optional
        Part relations for the geometric checks (none: explicit precedence only).
    model : OperationModel, optional
        A precompiled model (overrides ``relations``).
    max_states : int
        Stop with a ``ValueError`` beyond this many states.
    progress : bool
        Print the layer sizes on stderr.
    check : bool
        Raise a ``ValueError`` naming the parts that can never be inserted when no complete
        sequence exists.
    """
    model = operation_model(spec, relations) if model is None else model
    keys = np.array([model.start_key], dtype=np.uint64)
    parts = np.array([model.initial_parts], dtype=np.uint64)
    key_layers, part_layers = [keys], [parts]
    src_l, dst_l, op_l = [], [], []
    offset, total = 0, 1
    for layer in range(model.n_ops):
        enabled = model.enabled(keys, parts)
        si, oi = np.nonzero(enabled)
        if si.size == 0:
            break
        new = model.successor_keys(keys[si], oi)
        uniq, inv = np.unique(new, return_inverse=True)
        inv = inv.reshape(-1)
        new_parts = np.empty(uniq.shape[0], dtype=np.uint64)
        new_parts[inv] = parts[si] | model.op_parts[oi]
        src_l.append((si + offset).astype(np.int32))
        dst_l.append((inv + offset + keys.shape[0]).astype(np.int32))
        op_l.append(oi.astype(np.int16))
        offset += keys.shape[0]
        keys, parts = uniq, new_parts
        key_layers.append(keys)
        part_layers.append(parts)
        total += keys.shape[0]
        if total > max_states:
            raise ValueError(
                f"{spec.source}: the state graph exceeds {max_states:,} states (layer {layer + 1})"
            )
        if progress:
            print(
                f"  layer {layer + 1}/{model.n_ops}: {keys.shape[0]:,} states, "
                f"{si.size:,} transitions",
                file=sys.stderr,
            )
    layer_ptr = np.zeros(len(key_layers) + 1, dtype=np.int64)
    np.cumsum([k.shape[0] for k in key_layers], out=layer_ptr[1:])
    empty32 = np.empty(0, dtype=np.int32)
    graph = StateGraph(
        model=model,
        keys=np.concatenate(key_layers),
        parts=np.concatenate(part_layers),
        layer_ptr=layer_ptr,
        src=np.concatenate(src_l) if src_l else empty32,
        dst=np.concatenate(dst_l) if dst_l else empty32,
        op=np.concatenate(op_l) if op_l else np.empty(0, dtype=np.int16),
    )
    if check and not graph.complete.any():
        raise ValueError(infeasibility_report(graph))
    return graph


def infeasibility_report(graph: StateGraph) -> str:
    """One line naming the operations (and parts) that can never be done, and why."""
    model = graph.model
    spec = model.spec
    ever = int(np.bitwise_or.reduce(graph.keys)) if graph.n_states else 0
    never = [i for i in range(model.n_ops) if not ever >> i & 1]
    problems = []
    zero = np.uint64(0)
    for i in never:
        op = spec.operations[i]
        keys = graph.keys
        ready = (keys & model.op_bits[i]) == zero
        ready &= (keys & model.pred_masks[i]) == model.pred_masks[i]
        ready &= (keys & model.requires_mask[i]) == model.requires_value[i]
        rows = np.flatnonzero(ready)
        if not op.parts:
            if rows.size == 0:
                problems.append(f"operation {op.id} never has its predecessors and tools ready")
            continue
        if rows.size == 0:
            # Only report operations blocked by geometry, not their waiting successors.
            continue
        common: set[str] | None = None
        for r in rows[:2000]:
            s = int(graph.parts[r])
            why = set()
            for p in model.part_lists[i]:
                for reason in model.oracle.reasons(p, s, held=op.held):
                    why.add(f"{model.oracle.parts[p]}: {reason}")
                s |= 1 << p
            common = why if common is None else common & why
        detail = "; ".join(sorted(common)) if common else "no single reason in every state"
        names = ", ".join(op.parts)
        problems.append(f"part {names} (operation {op.id}) can never be inserted ({detail})")
    if not problems:
        problems.append("operations " + ", ".join(spec.operations[i].id for i in never[:5]))
    return f"{spec.source}: infeasible assembly, no complete sequence: " + "; ".join(problems)


# --------------------------------------------------------------------------- exact counting

_PRIME_BITS = 57


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


_PRIMES: list[int] = []


def _primes_for(n_ops: int) -> list[int]:
    """Enough distinct primes below 2**57 that their product exceeds ``n_ops!``."""
    need = math.lgamma(n_ops + 1) / math.log(2) + 2
    k = max(1, math.ceil(need / (_PRIME_BITS - 1)))
    candidate = (1 << _PRIME_BITS) - 1 if not _PRIMES else _PRIMES[-1] - 2
    while len(_PRIMES) < k:
        if _is_prime(candidate):
            _PRIMES.append(candidate)
        candidate -= 2
    return _PRIMES[:k]


def _crt(residues: list[int], primes: list[int]) -> int:
    x, m = 0, 1
    for r, p in zip(residues, primes, strict=True):
        t = (r - x) * pow(m, -1, p) % p
        x, m = x + m * t, m * p
    return x
