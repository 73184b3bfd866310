"""The state graph's inner loops compiled with numba.

The enabled-operations test (:meth:`asp.graph.state_keys.OperationModel.enabled`), stuck states,
duplicate successor keys (:func:`asp.graph.state_graph.build_state_graph`) and the sequence count
(:meth:`asp.graph.state_graph.StateGraph.count_sequences`).

One pass over the states: for each state and operation, the key tests (not done, explicit
predecessors done, tools ready) and then the geometric test of the part it places (touches
the assembled parts, rests on them unless held, some allowed direction free; the base part
first) on the set it is tested against (the main assembly, without the members of units not
yet inserted, or its unit's workspace), word by word. The same rules as the numpy path, which
stays for operations placing several parts; the results are equal (tested).
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def _free(cur, blocked, p, directions):
    """Whether part ``p`` is free from the parts of the set ``cur`` along some allowed
    direction."""
    for d in range(6):
        if not directions[d]:
            continue
        clear = True
        for w in range(cur.shape[0]):
            if cur[w] & blocked[p, d, w]:
                clear = False
                break
        if clear:
            return True
    return False


@numba.njit(cache=True, nogil=True)
def _main_set(keys, parts, s, op_word, op_bit, unit_op, unit_masks, main):
    """Fill ``main`` (PW,) with state ``s``'s main assembly: its parts without the members
    of the units not yet inserted (those are in their own workspaces)."""
    for w in range(main.shape[0]):
        main[w] = parts[s, w]
    for u in range(unit_op.shape[0]):
        i = unit_op[u]
        if (keys[s, op_word[i]] & op_bit[i]) == np.uint64(0):
            for w in range(main.shape[0]):
                main[w] &= ~unit_masks[u, w]


@numba.njit(cache=True, nogil=True)
def _workspace_set(parts, s, workspace, unit_masks, out):
    """Fill ``out`` (PW,) with the members of unit ``workspace`` placed in state ``s``."""
    for w in range(out.shape[0]):
        out[w] = parts[s, w] & unit_masks[workspace, w]


@numba.njit(cache=True, nogil=True)
def enabled_single(
    keys,
    parts,
    op_word,
    op_bit,
    pred,
    req_mask,
    req_value,
    part_of,
    needs_base,
    held,
    contact,
    blocked,
    support,
    directions,
    base_word,
    base_bit,
    geometric,
    stability,
    workspace,
    unit_op,
    unit_masks,
    out,
):
    """Fill ``out`` (k, n_ops) bool: operation ``i`` may be done in state ``s``.

    Parameters
    ----------
    keys : (k, W) uint64
    parts : (k, PW) uint64
    op_word, op_bit : (n_ops,) int64, uint64
        Where operation ``i``'s own key bit is.
    pred, req_mask, req_value : (n_ops, W) uint64
    part_of : (n_ops,) int64
        The part (or unit) each operation places, -1 for none.
    needs_base : (n_ops,) bool
        The base part must be there (topological, the operation places another part into
        the main assembly).
    held : (n_ops,) bool
    contact, support : (n, PW) uint64
    blocked : (n, 6, PW) uint64
    directions : (6,) bool
    base_word, base_bit : int, uint64
    geometric, stability : bool
    workspace : (n_ops,) int64
        The unit whose workspace operation ``i`` builds in (-1: the main assembly).
    unit_op : (U,) int64
        Each unit's insertion operation.
    unit_masks : (U, PW) uint64
        Each unit's members.
    """
    k, n_words = keys.shape
    pw = parts.shape[1]
    n_ops = op_word.shape[0]
    zero = np.uint64(0)
    main = np.empty(pw, dtype=np.uint64)
    scratch = np.empty(pw, dtype=np.uint64)
    for s in range(k):
        _main_set(keys, parts, s, op_word, op_bit, unit_op, unit_masks, main)
        for i in range(n_ops):
            ok = (keys[s, op_word[i]] & op_bit[i]) == zero
            w = 0
            while ok and w < n_words:
                key = keys[s, w]
                if (key & pred[i, w]) != pred[i, w] or (key & req_mask[i, w]) != req_value[i, w]:
                    ok = False
                w += 1
            p = part_of[i]
            if ok and p >= 0:
                cur = main
                if workspace[i] >= 0:
                    _workspace_set(parts, s, workspace[i], unit_masks, scratch)
                    cur = scratch
                empty = True
                for w in range(pw):
                    if cur[w] != zero:
                        empty = False
                if needs_base[i] and (parts[s, base_word] & base_bit) == zero:
                    ok = False
                elif geometric and not empty:
                    touch = False
                    rest = not stability or held[i]
                    for w in range(pw):
                        if cur[w] & contact[p, w]:
                            touch = True
                        if cur[w] & support[p, w]:
                            rest = True
                    ok = touch and rest and _free(cur, blocked, p, directions)
            out[s, i] = ok


@numba.njit(cache=True, nogil=True)
def first_rows(keys):
    """Hash the (m, W) uint64 rows: the index of each distinct row's first occurrence, and
    for every row the number of its distinct row (in order of first occurrence).

    Returns
    -------
    firsts : (u,) int64
    inverse : (m,) int64
    """
    m, n_words = keys.shape
    size = 2
    while size < 2 * m:
        size *= 2
    mask = size - 1
    table = np.full(size, -1, dtype=np.int64)
    firsts = np.empty(m, dtype=np.int64)
    inverse = np.empty(m, dtype=np.int64)
    u = 0
    for r in range(m):
        h = np.uint64(0x9E3779B97F4A7C15)
        for w in range(n_words):
            h = (h ^ keys[r, w]) * np.uint64(0xBF58476D1CE4E5B9)
            h ^= h >> np.uint64(31)
        slot = np.int64(h & np.uint64(mask))
        while True:
            t = table[slot]
            if t == -1:
                table[slot] = u
                firsts[u] = r
                inverse[r] = u
                u += 1
                break
            f = firsts[t]
            same = True
            for w in range(n_words):
                if keys[f, w] != keys[r, w]:
                    same = False
                    break
            if same:
                inverse[r] = t
                break
            slot = (slot + 1) & mask
    return firsts[:u], inverse


@numba.njit(cache=True, nogil=True)
def stuck(
    keys,
    parts,
    parent_keys,
    parent_parts,
    after,
    op_word,
    op_bit,
    part_of,
    blocked,
    directions,
    workspace,
    unit_op,
    unit_masks,
):
    """(k,) bool: some operation not done places a part (or unit) that is blocked along
    every allowed direction by the parts already in the set it is tested against (it can
    never be done: parts are never removed, a workspace's members leave only with its
    finished unit).

    With ``after``, each state is reached by one operation from a state that is not stuck
    (row ``s`` of ``parent_keys`` (k, W) and ``parent_parts`` (k, PW)): only the operations
    whose part the parts new to its set (not in the parent's) block along some allowed
    direction are tested; for any other, the direction that was clear in the parent still
    is. Without it every operation is tested (the parent arrays are not read).

    Same arrays as :func:`enabled_single`.
    """
    k = keys.shape[0]
    pw = parts.shape[1]
    n_ops = op_word.shape[0]
    zero = np.uint64(0)
    reach = np.zeros((blocked.shape[0], pw), dtype=np.uint64)  # blocked along any direction
    for p in range(blocked.shape[0]):
        for d in range(6):
            if directions[d]:
                for w in range(pw):
                    reach[p, w] |= blocked[p, d, w]
    out = np.zeros(k, dtype=np.bool_)
    main = np.empty(pw, dtype=np.uint64)
    before = np.empty(pw, dtype=np.uint64)
    scratch = np.empty(pw, dtype=np.uint64)
    for s in range(k):
        _main_set(keys, parts, s, op_word, op_bit, unit_op, unit_masks, main)
        if after:
            _main_set(parent_keys, parent_parts, s, op_word, op_bit, unit_op, unit_masks, before)
        for i in range(n_ops):
            p = part_of[i]
            if p < 0 or (keys[s, op_word[i]] & op_bit[i]) != zero:
                continue
            cur = main
            new = not after
            if workspace[i] >= 0:
                _workspace_set(parts, s, workspace[i], unit_masks, scratch)
                cur = scratch
                for w in range(pw):
                    if after and scratch[w] & ~parent_parts[s, w] & reach[p, w]:
                        new = True
            elif after:
                for w in range(pw):
                    if main[w] & ~before[w] & reach[p, w]:
                        new = True
            if new and not _free(cur, blocked, p, directions):
                out[s] = True
                break
    return out


@numba.njit(cache=True, nogil=True)
def add_counts(src, dst, src_lo, dst_lo, counts, primes, out):
    """``out[dst - dst_lo] += counts[src - src_lo]`` modulo each prime, edge by edge.

    ``counts`` (a, P) and ``out`` (b, P) uint64 residues below ``primes`` (P,), each below
    ``2**63``; the sum of two residues fits uint64.
    """
    n_primes = primes.shape[0]
    for e in range(src.shape[0]):
        s = src[e] - src_lo
        d = dst[e] - dst_lo
        for k in range(n_primes):
            v = out[d, k] + counts[s, k]
            if v >= primes[k]:
                v -= primes[k]
            out[d, k] = v
