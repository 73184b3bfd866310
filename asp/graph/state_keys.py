"""The state-key codec: a spec compiled to bit operations over the insertion oracle.

An assembly state packs the done operations (bit ``i`` = operation ``i``) and the tool
values (a small field per tool above the operation bits) into a key of ``W = ceil(bits / 64)``
uint64 words (one word, the fast path, up to 64 bits). :class:`OperationModel` packs and
unpacks keys and says which operations are enabled in which states (the geometric test of
:mod:`asp.graph.feasibility`, the precedences, tools and the symmetry orders; its numba
loops in :mod:`asp.graph.enabled_kernel`); :func:`operation_model` builds it from a spec.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from asp.errors import SpecError
from asp.graph.feasibility import (
    MAX_OPS,
    WORD_BITS,
    InsertionOracle,
    insertion_oracle,
    pack_words,
    split_words,
)
from asp.spec import AssemblySpec, tool_values


@dataclass(frozen=True, eq=False)
class OperationModel:
    """The spec compiled to bit operations: which operations are enabled in which states.

    State key layout: ``W = n_words`` uint64 words, ``ceil(n_bits / 64)``; key bit ``b`` is
    bit ``b % 64`` of word ``b // 64``. A set of ``k`` states is a ``(k, W)`` uint64 array (one
    row per state); :meth:`pack` and :meth:`unpack` convert to and from Python ints. Bit ``i``
    (``i < n_ops``) is operation ``i`` done; tool ``t`` keeps its value index (into
    ``tool_values[t]``) in ``tool_bits[t]`` bits at key bit ``tool_shift[t]`` (a tool field
    never straddles two words). With ``W == 1`` every method runs on the single word column.

    Attributes
    ----------
    op_bits : (n_ops, W) uint64
        Operation ``i``'s own bit.
    pred_masks : (n_ops, W) uint64
        Explicit predecessors of each operation (zero when topological is off).
    op_parts : (n_ops, PW) uint64
        Parts each operation places (part sets, see :class:`InsertionOracle`).
    requires_mask, requires_value : (n_ops, W) uint64
        Tool fields an operation reads and the values they must hold.
    sets_mask, sets_value : (n_ops, W) uint64
        Tool fields an operation writes and the values it writes.
    start_key : int
        Nothing done, every tool at its initial value.
    initial_parts : int
        The base part when no operation places it (it is on the fixture from the start).
    n_bits : int
        Key bits used (operations, tool fields and the padding that keeps fields in one word).
    op_workspace : tuple of int
        Per operation, the subassembly whose workspace it builds in (index into
        ``spec.subassemblies``), or -1 for the main assembly.
    unit_ops : tuple of int
        Per subassembly, the operation that inserts it.
    unit_masks : (U, PW) uint64
        Per subassembly, its member parts.
    symmetric : tuple of classes of blocks of operation indices
        Interchangeable blocks: of equal blocks only the first moves (:mod:`asp.graph.symmetry`).
    loose : tuple of (int, tuple of int)
        Classes of interchangeable operations, each with its slack ``m``: an operation of a
        class may be done only while at most ``m`` of the ones listed before it are not
        (:meth:`_loose_order`; ``m = 0`` is a fixed order).
    interchangeable : tuple of classes of blocks of operation ids
        Every class of interchangeable blocks the reduction of the spec used (chained in
        ``spec``, ``symmetric`` or ``loose``): each transposition of two blocks of a class
        (position by position) is a symmetry of the game. Recorded for the runtime
        (``plan.json``'s ``interchangeable``); the model's moves do not read it.
    fasteners_in_order : tuple of (part, joined part, joined part)
        The joining parts (screws, pins) the spec puts in one order, each after the two
        parts it joins (:mod:`asp.graph.fasteners`), in that order; recorded for the plan
        (``plan.json``'s ``fasteners_in_order``); the model's moves do not read it.
    fixed : tuple of classes of blocks of operation indices
        Interchangeable blocks the spec puts in a fixed order: at every position ``i``, the
        ``i``-th operations of the blocks are chained in block order by ``after``
        (:func:`asp.graph.symmetry.symmetry_reduction`). Only read by the schedule stage, which
        undoes that order (:mod:`asp.graph.fixed_order`).
    """

    spec: AssemblySpec
    oracle: InsertionOracle
    op_bits: np.ndarray
    pred_masks: np.ndarray
    op_parts: np.ndarray
    part_lists: tuple[tuple[int, ...], ...]
    requires_mask: np.ndarray
    requires_value: np.ndarray
    sets_mask: np.ndarray
    sets_value: np.ndarray
    tool_names: tuple[str, ...]
    tool_values: tuple[tuple[str, ...], ...]
    tool_shift: tuple[int, ...]
    tool_bits: tuple[int, ...]
    start_key: int
    initial_parts: int
    n_bits: int
    op_workspace: tuple[int, ...] = ()
    unit_ops: tuple[int, ...] = ()
    unit_masks: np.ndarray | None = None
    symmetric: tuple[tuple[tuple[int, ...], ...], ...] = ()
    loose: tuple[tuple[int, tuple[int, ...]], ...] = ()
    interchangeable: tuple[tuple[tuple[str, ...], ...], ...] = ()
    fixed: tuple[tuple[tuple[int, ...], ...], ...] = ()
    fasteners_in_order: tuple[tuple[str, str, str], ...] = ()

    @property
    def n_ops(self) -> int:
        return len(self.spec.operations)

    @property
    def n_words(self) -> int:
        """``W``: uint64 words per state key."""
        return int(self.op_bits.shape[1])

    @property
    def done_mask(self) -> int:
        return (1 << self.n_ops) - 1

    # ------------------------------------------------------------------ keys
    def pack(self, values) -> np.ndarray:
        """(k, W) uint64 keys of the Python ints ``values``."""
        rows = [split_words(int(v), self.n_words) for v in values]
        return np.array(rows, dtype=np.uint64).reshape(-1, self.n_words)

    def unpack(self, key) -> int:
        """The Python int of a key: a (W,) row of words, or already an int."""
        if isinstance(key, int | np.integer):
            return int(key)
        return sum(int(w) << (WORD_BITS * k) for k, w in enumerate(np.asarray(key).reshape(-1)))

    def _keys(self, keys) -> np.ndarray:
        keys = np.asarray(keys, dtype=np.uint64)
        if keys.ndim == 1:
            if self.n_words != 1:
                raise SpecError(f"expected (k, {self.n_words}) state keys, got {keys.shape}")
            keys = keys[:, None]
        if keys.ndim != 2 or keys.shape[1] != self.n_words:
            raise SpecError(f"expected (k, {self.n_words}) state keys, got {keys.shape}")
        return keys

    def has_op(self, keys: np.ndarray, i: int) -> np.ndarray:
        """(k,) bool: whether operation ``i`` is done in each state."""
        keys = self._keys(keys)
        word, bit = divmod(int(i), WORD_BITS)
        return (keys[:, word] & np.uint64(1 << bit)) != np.uint64(0)

    def done_matrix(self, keys: np.ndarray) -> np.ndarray:
        """(k, n_ops) bool: which operations are done in each state."""
        keys = self._keys(keys)
        as_bytes = np.ascontiguousarray(keys).astype("<u8", copy=False).view(np.uint8)
        bits = np.unpackbits(as_bytes, axis=1, bitorder="little")
        return bits[:, : self.n_ops].astype(bool)

    def is_complete(self, keys: np.ndarray) -> np.ndarray:
        """(k,) bool: states with every operation done."""
        keys = self._keys(keys)
        ok = np.ones(keys.shape[0], dtype=bool)
        for w, m in enumerate(split_words(self.done_mask, self.n_words)):
            if m:
                ok &= (keys[:, w] & np.uint64(m)) == np.uint64(m)
        return ok

    def ready(self, keys: np.ndarray, i: int) -> np.ndarray:
        """(k,) bool: operation ``i`` not done, its predecessors done and its tools ready."""
        keys = self._keys(keys)
        ok = ~self.has_op(keys, i)
        for w in range(self.n_words):
            pm, rm, rv = self.pred_masks[i, w], self.requires_mask[i, w], self.requires_value[i, w]
            if pm:
                ok &= (keys[:, w] & pm) == pm
            if rm:
                ok &= (keys[:, w] & rm) == rv
        return ok

    # ------------------------------------------------------------------ transitions
    def enabled(self, keys: np.ndarray, parts: np.ndarray) -> np.ndarray:
        """Which operations may be done next in each state.

        Parameters
        ----------
        keys : (k, W) uint64
            State keys (``(k,)`` is accepted when ``W == 1``).
        parts : (k, PW) uint64
            Assembled-part sets of those states (``(k,)`` when ``PW == 1``).

        Returns
        -------
        (k, n_ops) bool
        """
        keys = self._keys(keys)
        if self._kernel_args is not None:  # compiled: one pass over the states
            from asp.graph.enabled_kernel import enabled_single

            ok = np.empty((keys.shape[0], self.n_ops), dtype=bool)
            sets = np.ascontiguousarray(self.oracle.sets(parts))
            enabled_single(np.ascontiguousarray(keys), sets, *self._kernel_args, ok)
            self._symmetries(keys, ok)
            return ok
        zero = np.uint64(0)
        if self.n_words == 1:  # the fast path: one broadcast test per mask
            col = keys[:, :1]
            ok = (col & self.op_bits[:, 0]) == zero
            pred = self.pred_masks[:, 0]
            if pred.any():
                ok &= (col & pred) == pred
            if self.tool_names:
                ok &= (col & self.requires_mask[:, 0]) == self.requires_value[:, 0]
        else:
            ok = np.empty((keys.shape[0], self.n_ops), dtype=bool)
            for w in range(self.n_words):
                lo, hi = w * WORD_BITS, min(self.n_ops, (w + 1) * WORD_BITS)
                if lo < hi:
                    ok[:, lo:hi] = (keys[:, w : w + 1] & self.op_bits[lo:hi, w]) == zero
            checks = [(self.pred_masks, self.pred_masks)]
            if self.tool_names:
                checks.append((self.requires_mask, self.requires_value))
            for w in range(self.n_words):
                col = keys[:, w : w + 1]
                for masks, values in checks:
                    cols = np.flatnonzero(masks[:, w])
                    if cols.size == 0:
                        continue
                    if cols.size == self.n_ops:
                        ok &= (col & masks[:, w]) == values[:, w]
                    else:
                        ok[:, cols] &= (col & masks[cols, w]) == values[cols, w]
        parts = self.oracle.sets(parts)
        pending = self.pending_units(keys)
        for i, plist in enumerate(self.part_lists):
            if not plist:
                continue
            column = ok[:, i]
            rows = np.flatnonzero(column)
            if rows.size == 0:
                continue
            s, workspace = self.assembled_for(i, parts[rows], pending, rows)
            good = np.ones(rows.size, dtype=bool)
            held = self.spec.operations[i].held
            for p in plist:
                good &= self.oracle.feasible(p, s, held=held, workspace=workspace)
                s = s | self.oracle.bit(p)
            column[rows] = good
        self._symmetries(keys, ok)
        return ok

    def stuck(self, keys: np.ndarray, parts: np.ndarray, parents=None) -> np.ndarray:
        """(k,) bool: some operation not done places a part (or unit) that the parts already
        in the set it is tested against block along every allowed direction, so it can never
        be done (a dead end). Always False for specs off the compiled path (an operation
        placing several parts).

        ``parents`` (optional): the keys and parts of a state each of ``keys`` is reached
        from by one operation, none of them stuck; then only the operations whose part the
        parts new to its set could block are tested (:func:`asp.graph.enabled_kernel.stuck`,
        the same result).
        """
        keys = self._keys(keys)
        if self._kernel_args is None:
            return np.zeros(keys.shape[0], dtype=bool)
        from asp.graph.enabled_kernel import stuck

        a = self._kernel_args
        keys = np.ascontiguousarray(keys)
        sets = np.ascontiguousarray(self.oracle.sets(parts))
        before = (keys, sets)  # not read without parents
        if parents is not None:
            before = (
                np.ascontiguousarray(self._keys(parents[0])),
                np.ascontiguousarray(self.oracle.sets(parents[1])),
            )
        tables = (a[0], a[1], a[5], a[9], a[11], a[16], a[17], a[18])
        return stuck(keys, sets, *before, parents is not None, *tables)

    @functools.cached_property
    def _kernel_args(self) -> tuple | None:
        """The arrays of :func:`asp.graph.enabled_kernel.enabled_single`, or None when an
        operation places several parts (the numpy path)."""
        if any(len(p) > 1 for p in self.part_lists):
            return None
        o = self.oracle
        n_ops = self.n_ops
        part_of = np.array([p[0] if p else -1 for p in self.part_lists], dtype=np.int64)
        workspace = np.array(self.op_workspace or [-1] * n_ops, dtype=np.int64)
        needs_base = (part_of >= 0) & (part_of != o.base) & bool(o.topological and o.base >= 0)
        needs_base &= workspace < 0
        base = max(o.base, 0)
        return (
            np.arange(n_ops, dtype=np.int64) // WORD_BITS,
            np.array([1 << (i % WORD_BITS) for i in range(n_ops)], dtype=np.uint64),
            np.ascontiguousarray(self.pred_masks),
            np.ascontiguousarray(self.requires_mask),
            np.ascontiguousarray(self.requires_value),
            part_of,
            needs_base,
            np.array([op.held for op in self.spec.operations], dtype=bool),
            np.ascontiguousarray(o.contact),
            np.ascontiguousarray(o.blocked),
            np.ascontiguousarray(o.support),
            np.asarray(o.directions, dtype=bool),
            base // WORD_BITS,
            np.uint64(1 << (base % WORD_BITS)),
            bool(o.geometric),
            bool(o.stability),
            workspace,
            np.array(self.unit_ops, dtype=np.int64),
            np.ascontiguousarray(
                self.unit_masks
                if self.unit_masks is not None and len(self.unit_ops)
                else np.zeros((0, o.n_words), dtype=np.uint64)
            ),
        )

    def _symmetries(self, keys: np.ndarray, ok: np.ndarray) -> None:
        """Keep only the moves the reduction of interchangeable operations keeps."""
        if self.symmetric:
            self._first_of_equals(keys, ok)
        if self.loose:
            self._loose_order(keys, ok)

    def _loose_order(self, keys: np.ndarray, ok: np.ndarray) -> None:
        """Of each class of interchangeable operations ``(m, ops)`` (:mod:`asp.graph.symmetry`),
        keep ``ops[j]`` only where at most ``m`` of ``ops[:j]`` are not done.

        Any of them may be done next, so doing the first one not done is the same move up to
        a symmetry fixing the state: ``m = 0`` keeps that move alone (a fixed order). With
        ``m`` one less than the workers who may do them, ``m`` of them may still be running
        when another one starts, so the concurrent game keeps its moves too (the first not
        running), and since the count only falls as operations are done, an operation kept
        when it starts is kept whichever finishes first.
        """
        for slack, ops in self.loose:
            missing = np.zeros(keys.shape[0], dtype=np.int64)
            for j, i in enumerate(ops):
                if j > slack:
                    ok[:, i] &= missing <= slack
                missing += ~self.has_op(keys, i)

    def _first_of_equals(self, keys: np.ndarray, ok: np.ndarray) -> None:
        """Keep, of interchangeable blocks in the same state, only the first one's moves.

        ``symmetric`` holds classes of blocks (tuples of operation indices, position by
        position alike): every transposition of two blocks of a class is a symmetry of the
        game (:mod:`asp.graph.symmetry`). Two blocks with the same operations done (position by
        position) are swapped by a symmetry that fixes the state, so a move in the later one
        has the same cost and an isomorphic future as the same move in the earlier one: only
        the earlier one's is kept. TCT and W* do not change.
        """
        for blocks in self.symmetric:
            codes = np.zeros((keys.shape[0], len(blocks)), dtype=np.int64)
            for j, block in enumerate(blocks):
                for pos, i in enumerate(block):
                    codes[:, j] |= self.has_op(keys, i).astype(np.int64) << pos
            for j in range(1, len(blocks)):
                twin = (codes[:, :j] == codes[:, j : j + 1]).any(axis=1)
                ok[:, list(blocks[j])] &= ~twin[:, None]

    def parts_of(self, keys: np.ndarray) -> np.ndarray:
        """(k, PW) uint64: the parts placed in each state, every workspace (the base part
        when on the fixture from the start, and the parts of every done operation)."""
        keys = self._keys(keys)
        parts = np.empty((keys.shape[0], self.oracle.n_words), dtype=np.uint64)
        parts[:] = pack_words([self.initial_parts], self.oracle.n_words)
        for i in range(self.n_ops):
            if self.op_parts[i].any():
                parts[self.has_op(keys, i)] |= self.op_parts[i]
        return parts

    def pending_units(self, keys: np.ndarray) -> np.ndarray | None:
        """(k, PW) uint64: members of the subassemblies not yet inserted, per state."""
        if not self.unit_ops:
            return None
        keys = self._keys(keys)
        pending = np.zeros((keys.shape[0], self.oracle.n_words), dtype=np.uint64)
        for u, i in enumerate(self.unit_ops):
            pending[~self.has_op(keys, i)] |= self.unit_masks[u]
        return pending

    def assembled_for(self, i: int, parts: np.ndarray, pending, rows=None):
        """The parts operation ``i`` is tested against, and whether that is a unit's workspace.

        ``parts`` are the placed parts of the states (every workspace); a unit's member
        operation sees the members placed in its workspace, any other operation the main
        assembly (``pending``, from :meth:`pending_units`, removed; ``rows`` selects its rows).
        """
        parts = self.oracle.sets(parts)
        w = self.op_workspace[i] if self.op_workspace else -1
        if w >= 0:
            return parts & self.unit_masks[w], True
        if pending is None:
            return parts, False
        return parts & ~(pending if rows is None else pending[rows]), False

    def successor_keys(self, keys: np.ndarray, ops: np.ndarray) -> np.ndarray:
        """(k, W) uint64: the state after doing operation ``ops[k]`` in state ``keys[k]``."""
        keys = self._keys(keys)
        ops = np.asarray(ops)
        if self.n_words == 1:
            out = keys[:, 0] | self.op_bits[ops, 0]
            if self.tool_names:
                out &= ~self.sets_mask[ops, 0]
                out |= self.sets_value[ops, 0]
            return out[:, None]
        out = keys | self.op_bits[ops]
        if self.tool_names:
            out &= ~self.sets_mask[ops]
            out |= self.sets_value[ops]
        return out

    def tool_changes(self, keys: np.ndarray, ops: np.ndarray) -> np.ndarray:
        """(k, n_tools) bool: whether operation ``ops[k]`` changes each tool's value."""
        keys = self._keys(keys)
        ops = np.asarray(ops)
        out = np.zeros((keys.shape[0], len(self.tool_names)), dtype=bool)
        for t, (shift, bits) in enumerate(zip(self.tool_shift, self.tool_bits, strict=True)):
            w, local = divmod(shift, WORD_BITS)
            field = np.uint64(((1 << bits) - 1) << local)
            writes = (self.sets_mask[ops, w] & field) != np.uint64(0)
            out[:, t] = writes & ((keys[:, w] & field) != (self.sets_value[ops, w] & field))
        return out

    def tool_state(self, key) -> dict[str, str]:
        """Tool values of the state ``key`` (an int or a (W,) row)."""
        key = self.unpack(key)
        return {
            name: vals[(key >> shift) & ((1 << bits) - 1)]
            for name, vals, shift, bits in zip(
                self.tool_names, self.tool_values, self.tool_shift, self.tool_bits, strict=True
            )
        }

    def done_ops(self, key) -> list[str]:
        """Ids of the operations done in the state ``key`` (an int or a (W,) row), in order."""
        key = self.unpack(key)
        return [op.id for i, op in enumerate(self.spec.operations) if key >> i & 1]


def operation_model(
    spec: AssemblySpec,
    relations=None,
    *,
    _min_words: int = 1,
    symmetric=(),
    loose=(),
    interchangeable=(),
    fixed=(),
) -> OperationModel:
    """Compile ``spec`` (and the cad relations, if any) into an :class:`OperationModel`.

    The state key takes as many 64-bit words as the operations and tool fields need
    (``_min_words`` forces more, for tests of the multi-word path). ``symmetric``: classes of
    interchangeable blocks of operation ids (:func:`asp.graph.symmetry.interchangeable_blocks`),
    of which only the first of equal blocks moves (:meth:`OperationModel.enabled`);
    ``loose``: classes of interchangeable operation ids with their slack, ``(m, ids)``
    (:attr:`OperationModel.loose`); ``interchangeable``: the classes of blocks the
    reduction used (:attr:`OperationModel.interchangeable`); ``fixed``: classes of blocks
    of operation ids the spec puts in a fixed order (:attr:`OperationModel.fixed`).

    Raises
    ------
    ValueError
        More operations than the transition table's int16 operation index holds.
    """
    ops = spec.operations
    n_ops = len(ops)
    if n_ops > MAX_OPS:
        raise SpecError(
            f"{spec.source}: operations: {n_ops} operations, at most {MAX_OPS:,} are supported; "
            f"split the assembly into subassemblies"
        )
    values = tool_values(spec)
    names = tuple(values)
    bits = tuple(max(1, math.ceil(math.log2(len(values[t])))) for t in names)
    shifts, pos = [], n_ops
    for b in bits:
        if pos // WORD_BITS != (pos + b - 1) // WORD_BITS:  # keep each field in one word
            pos = (pos // WORD_BITS + 1) * WORD_BITS
        shifts.append(pos)
        pos += b
    n_words = max(1, math.ceil(pos / WORD_BITS), int(_min_words))
    oracle = insertion_oracle(spec, relations)
    index = {op.id: i for i, op in enumerate(ops)}
    pidx = {p: k for k, p in enumerate(oracle.parts)}
    topo = spec.constraints.topological
    pred = [sum(1 << index[a] for a in op.after) if topo else 0 for op in ops]
    part_lists = tuple(
        (pidx[op.unit],) if op.unit else tuple(pidx[p] for p in op.parts) for op in ops
    )
    units = [u for u, _ in spec.subassemblies]
    owner = {m: k for k, (_, ms) in enumerate(spec.subassemblies) for m in ms}
    op_workspace = tuple(
        owner[op.parts[0]] if op.parts and op.parts[0] in owner else -1 for op in ops
    )
    unit_masks = pack_words(
        [sum(1 << pidx[m] for m in ms) for _, ms in spec.subassemblies], oracle.n_words
    )
    req_m, req_v, set_m, set_v = [], [], [], []
    tindex = {t: k for k, t in enumerate(names)}
    for op in ops:
        for pairs, mlist, vlist in ((op.requires, req_m, req_v), (op.sets, set_m, set_v)):
            m = v = 0
            for t, val in pairs:
                k = tindex[t]
                m |= ((1 << bits[k]) - 1) << shifts[k]
                v |= values[t].index(val) << shifts[k]
            mlist.append(m)
            vlist.append(v)
    placed = set(spec.placed_parts)
    initial_parts = 0
    if oracle.base >= 0 and spec.base_part not in placed:
        initial_parts = 1 << oracle.base

    def table(ints: list[int]) -> np.ndarray:
        rows = [split_words(x, n_words) for x in ints]
        return np.array(rows, dtype=np.uint64).reshape(len(ints), n_words)

    return OperationModel(
        spec=spec,
        oracle=oracle,
        op_bits=table([1 << i for i in range(n_ops)]),
        pred_masks=table(pred),
        op_parts=pack_words([sum(1 << pidx[p] for p in op.parts) for op in ops], oracle.n_words),
        part_lists=part_lists,
        requires_mask=table(req_m),
        requires_value=table(req_v),
        sets_mask=table(set_m),
        sets_value=table(set_v),
        tool_names=names,
        tool_values=tuple(values[t] for t in names),
        tool_shift=tuple(shifts),
        tool_bits=bits,
        start_key=0,
        initial_parts=initial_parts,
        n_bits=pos,
        op_workspace=op_workspace,
        unit_ops=tuple(index[u] for u in units),
        unit_masks=unit_masks,
        symmetric=tuple(
            tuple(tuple(index[o] for o in block) for block in cls) for cls in symmetric
        ),
        loose=tuple((int(m), tuple(index[o] for o in ids)) for m, ids in loose),
        interchangeable=tuple(
            tuple(tuple(str(o) for o in block) for block in cls) for cls in interchangeable
        ),
        fixed=tuple(tuple(tuple(index[o] for o in block) for block in cls) for cls in fixed),
    )
