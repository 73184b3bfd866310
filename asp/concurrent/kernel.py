"""The concurrent game's construction, compiled with numba (:func:`asp.concurrent.build_game`).

The same rules as :mod:`asp.concurrent` (one game, two builders: this one for speed, the
Python one for states that do not fit the packed key), written over arrays:

- ``indptr``/``dst``/``op``/``change``: the live transitions in CSR form
  (:class:`asp.graph.together.LiveSteps`): the enabled operations of state ``s`` are
  ``op[indptr[s]:indptr[s + 1]]`` in the state graph's order, each with its target state and
  tool-change time;
- ``dur[w, o, :ndur[w, o]]``: the durations worker ``w`` may take for ``o`` (none: not allowed);
- ``conflict[a, b]``: a tool conflict; ``complete[s]``; ``side[w]`` (0 robot, 1 human).

Which operations may run together is :func:`asp.graph.together.together` (memoised here).

A node is an int32 row ``[kind, state, budget, op[0..W), rem[0..W), instr[0..W)]``
(``kind`` 0 robot, 1 human, 2 end; ``op`` -1 for a free worker; ``instr`` -2 where there is
none; edges are int32 with int16 operations), found again
through a hash map on a packed key of four words (:func:`fits` says when it fits). The
enumeration order of moves is the Python builder's, so both give the same game.
"""

from __future__ import annotations

import numba
import numpy as np
from numba import types
from numba.typed import Dict

from asp.graph.together import OK, edge, together

WAIT = -1
NONE = -2
MAX_WORKERS = 4
MAX_OPS = 250
MAX_REMAINING = 65_535
MAX_STATES = 2**31 - 1
KEY = types.UniTuple(types.int64, 4)
MEMO_KEY = types.UniTuple(types.int64, 2)
OVER_NODES, OVER_MEMORY = 1, 2
"""Why :func:`build_kernel` stopped: a node past ``max_nodes``, or its bytes past
``max_bytes``."""


def fits(n_workers: int, n_ops: int, longest: int, n_states: int, budget: int) -> bool:
    """Whether the packed key holds this game (else the Python builder runs)."""
    return (
        n_workers <= MAX_WORKERS
        and n_ops <= MAX_OPS
        and longest <= MAX_REMAINING
        and n_states <= MAX_STATES
        and budget < 1 << 20
    )


@numba.njit(cache=True)
def _key(row, nw):  # pragma: no cover - compiled
    w0 = np.int64(row[0]) | (np.int64(row[1]) << 2) | ((np.int64(row[2]) + 1) << 36)
    w1 = np.int64(0)
    w2 = np.int64(0)
    w3 = np.int64(0)
    for w in range(nw):
        w1 |= (np.int64(row[3 + w]) + 2) << (8 * w)
        w2 |= np.int64(row[3 + nw + w]) << (16 * w)
        w3 |= (np.int64(row[3 + 2 * nw + w]) + 2) << (8 * w)
    return (w0, w1, w2, w3)


@numba.njit(cache=True)
def _compatible(s, ops, m, indptr, dst, op, conflict, memo):  # pragma: no cover - compiled
    """``ops[:m]`` (sorted) may run together from state ``s``
    (:func:`asp.graph.together.together`)."""
    packed = 0
    for i in range(m):
        packed = packed * 256 + ops[i] + 1
    key = (s, packed)
    if key in memo:
        return memo[key]
    ok = together(s, ops, m, indptr, dst, op, conflict)[0] == OK
    memo[key] = ok
    return ok


@numba.njit(cache=True)
def _with(busy, nb, extra, ne, out):  # pragma: no cover - compiled
    """Sorted union of ``busy[:nb]`` and ``extra[:ne]`` (WAITs skipped) into ``out``; its size."""
    m = 0
    for i in range(nb):
        out[m] = busy[i]
        m += 1
    for i in range(ne):
        if extra[i] >= 0:
            out[m] = extra[i]
            m += 1
    out[:m].sort()
    return m


@numba.njit(cache=True)
def _has_candidate(  # pragma: no cover - compiled
    s, w, final, m, indptr, dst, op, ndur, conflict, memo, buf
):
    """Worker ``w`` has an operation it may start next to ``final[:m]``."""
    for k in range(indptr[s], indptr[s + 1]):
        o = op[k]
        if ndur[w, o] == 0:
            continue
        taken = False
        for i in range(m):
            if final[i] == o:
                taken = True
        if taken:
            continue
        for i in range(m):
            buf[i] = final[i]
        buf[m] = o
        buf[: m + 1].sort()
        if _compatible(s, buf, m + 1, indptr, dst, op, conflict, memo):
            return True
    return False


@numba.njit(cache=True)
def build_kernel(
    indptr,
    dst,
    op,
    change,
    dur,
    ndur,
    conflict,
    complete,
    side,
    budgets,
    max_nodes,
    max_bytes,
    node_bytes,
    edge_bytes,
):  # pragma: no cover - compiled
    """The game from the starts of ``budgets`` (module docstring). It stops (``overflow``
    :data:`OVER_NODES`) before a node past ``max_nodes``, and (:data:`OVER_MEMORY`) once
    its nodes and edges, at ``node_bytes`` and ``edge_bytes`` each, pass ``max_bytes``.
    Returns ``(overflow, [nodes expanded, nodes, edges], node rows, start nodes, edge
    arrays...)``, the arrays empty when it stopped.

    One long function on purpose (it stays above the complexity limit): it is the nopython
    loop over every node, and splitting it costs speed. Each piece would be a call between
    jitted functions taking a dozen arrays (the transitions, durations, the growing node and
    edge buffers, the hash map and the memo), and the loop state (the node expanded, its
    busy and free workers, the odometer over their choices, the buffer sizes) would leave
    the locals numba keeps in registers for arrays or tuples passed back and forth. What
    touches none of that state is split out: :func:`_key`, :func:`_compatible`,
    :func:`_with`, :func:`_has_candidate`, :func:`_append_edge`, :func:`_intern`."""
    nw = side.shape[0]
    width = 3 + 3 * nw
    cap = 1024
    rows = np.empty((cap, width), np.int32)
    index = Dict.empty(key_type=KEY, value_type=types.int64)
    memo = Dict.empty(key_type=MEMO_KEY, value_type=types.boolean)
    n = 0
    stack = np.empty(cap, np.int64)
    top = 0
    # Edges: source, target, cost, side, deviations, operation and duration per worker.
    edges = (
        np.empty(cap, np.int32),
        np.empty(cap, np.int32),
        np.empty(cap, np.int32),
        np.empty(cap, np.int8),
        np.empty(cap, np.int8),
        np.empty((cap, nw), np.int16),
        np.empty((cap, nw), np.int32),
    )
    m_edges = 0
    row = np.empty(width, np.int64)
    # The end node first (index 0), then one start per budget.
    row[:] = 0
    row[0] = 2
    row[2] = -1
    for w in range(nw):
        row[3 + w] = -2
        row[3 + 2 * nw + w] = -2
    index[_key(row, nw)] = 0
    rows[0] = row
    n = 1
    starts = np.empty(budgets.shape[0], np.int64)
    for b in range(budgets.shape[0]):
        row[:] = 0
        row[0] = 0
        row[2] = budgets[b]
        for w in range(nw):
            row[3 + w] = WAIT
            row[3 + 2 * nw + w] = NONE
        k = _key(row, nw)
        if k in index:
            starts[b] = index[k]
            continue
        index[k] = n
        rows[n] = row
        stack[top] = n
        top += 1
        starts[b] = n
        n += 1
    busy = np.empty(nw, np.int64)
    final = np.empty(nw + 1, np.int64)
    buf = np.empty(nw + 2, np.int64)
    deciders = np.empty(nw, np.int64)
    n_opts = np.empty(nw, np.int64)
    opts = np.empty((nw, op.shape[0] + 1 if op.shape[0] > 0 else 1), np.int64)
    digit = np.empty(nw, np.int64)
    chosen = np.empty(nw, np.int64)
    new = np.empty(width, np.int64)
    seen_t = np.empty(4096, np.int64)
    seen_c = np.empty(4096, np.int64)
    overflow = False
    over = OVER_NODES
    expanded = 0
    while top > 0:
        top -= 1
        expanded += 1
        v = stack[top]
        cur = rows[v].copy()
        kind, s, budget = cur[0], cur[1], cur[2]
        nb = 0
        for w in range(nw):
            if cur[3 + w] >= 0:
                busy[nb] = cur[3 + w]
                nb += 1
        busy[:nb].sort()
        instruct = budget >= 0
        nd = 0
        if kind == 0:
            for w in range(nw):
                if cur[3 + w] == WAIT and (side[w] == 0 or instruct):
                    deciders[nd] = w
                    nd += 1
        elif kind == 1:
            for w in range(nw):
                if cur[3 + w] == WAIT and side[w] == 1:
                    deciders[nd] = w
                    nd += 1
        else:
            continue
        # Options per decider: WAIT, then the enabled operations it may do (state order).
        for d in range(nd):
            w = deciders[d]
            opts[d, 0] = WAIT
            c = 1
            for k in range(indptr[s], indptr[s + 1]):
                o = op[k]
                if ndur[w, o] == 0:
                    continue
                taken = False
                for i in range(nb):
                    if busy[i] == o:
                        taken = True
                if not taken:
                    opts[d, c] = o
                    c += 1
            n_opts[d] = c
            digit[d] = 0
        n_seen = 0
        while True:
            # The joint choice of this odometer position (first decider most significant).
            for d in range(nd):
                chosen[d] = opts[d, digit[d]]
            distinct = True
            for a in range(nd):
                for b2 in range(a + 1, nd):
                    if chosen[a] >= 0 and chosen[a] == chosen[b2]:
                        distinct = False
            m = _with(busy, nb, chosen, nd, final) if distinct else 0
            ok = distinct and _compatible(s, final, m, indptr, dst, op, conflict, memo)
            if ok and kind == 0:
                something = nb > 0
                for d in range(nd):
                    w = deciders[d]
                    if chosen[d] >= 0 and (side[w] == 0 or instruct):
                        something = True
                if not something and not instruct:
                    # Robots' ops only in final (humans are not deciders here).
                    for w in range(nw):
                        if (
                            side[w] == 1
                            and cur[3 + w] == WAIT
                            and _has_candidate(
                                s, w, final, m, indptr, dst, op, ndur, conflict, memo, buf
                            )
                        ):
                            something = True
                            break
                if something:
                    new[:] = cur
                    for d in range(nd):
                        w = deciders[d]
                        if side[w] == 0:
                            if chosen[d] >= 0:
                                o = chosen[d]
                                new[3 + w] = o
                                new[3 + nw + w] = dur[w, o, 0] + change[edge(s, o, indptr, op)]
                        else:
                            new[3 + 2 * nw + w] = chosen[d]
                    new[0] = 1
                    t, rows, stack, n, top = _intern(new, nw, index, rows, stack, n, top, max_nodes)
                    if t < 0:
                        overflow = True
                        break
                    edges = _append_edge(edges, m_edges, v, t, 0, 0, 0, deciders, chosen, nd)
                    m_edges += 1
                    if m_edges * edge_bytes + n * node_bytes > max_bytes:
                        overflow, over = True, OVER_MEMORY
                        break
            elif ok and kind == 1 and m > 0:
                dev = 0
                if instruct:
                    for d in range(nd):
                        if cur[3 + 2 * nw + deciders[d]] != chosen[d]:
                            dev += 1
                valid = not (instruct and dev > budget)
                if valid:
                    for d in range(nd):
                        w = deciders[d]
                        if chosen[d] == WAIT:
                            following = instruct and cur[3 + 2 * nw + w] == WAIT
                            if not following and _has_candidate(
                                s, w, final, m, indptr, dst, op, ndur, conflict, memo, buf
                            ):
                                valid = False
                                break
                if valid:
                    # Durations of the started humans: an odometer of their grids.
                    ns = 0
                    for d in range(nd):
                        if chosen[d] >= 0:
                            ns += 1
                    started = np.empty(ns, np.int64)
                    sd = np.zeros(ns, np.int64)
                    j = 0
                    for d in range(nd):
                        if chosen[d] >= 0:
                            started[j] = d
                            j += 1
                    while True:
                        new[:] = cur
                        for j in range(ns):
                            d = started[j]
                            w = deciders[d]
                            o = chosen[d]
                            new[3 + w] = o
                            new[3 + nw + w] = dur[w, o, sd[j]] + change[edge(s, o, indptr, op)]
                        delta = -1
                        for w in range(nw):
                            if new[3 + w] >= 0 and (delta < 0 or new[3 + nw + w] < delta):
                                delta = new[3 + nw + w]
                        s2 = s
                        for w in range(nw):
                            if new[3 + w] >= 0:
                                if new[3 + nw + w] == delta:
                                    buf[0] = new[3 + w]
                                    new[3 + w] = WAIT
                                    new[3 + nw + w] = 0
                                    s2 = dst[edge(s2, buf[0], indptr, op)]
                                else:
                                    new[3 + nw + w] -= delta
                        running = False
                        for w in range(nw):
                            new[3 + 2 * nw + w] = NONE
                            if new[3 + w] >= 0:
                                running = True
                        new[0] = 0
                        new[1] = s2
                        new[2] = budget - dev if instruct else budget
                        if complete[s2] and not running:
                            t = 0
                        else:
                            t, rows, stack, n, top = _intern(
                                new, nw, index, rows, stack, n, top, max_nodes
                            )
                            if t < 0:
                                overflow = True
                                break
                        dup = False
                        for i in range(n_seen):
                            if seen_t[i] == t and seen_c[i] == delta:
                                dup = True
                        if not dup and n_seen < seen_t.shape[0]:
                            seen_t[n_seen] = t
                            seen_c[n_seen] = delta
                            n_seen += 1
                        if not dup:
                            edges = _append_edge(
                                edges, m_edges, v, t, delta, 1, dev, deciders, chosen, nd
                            )
                            e_dur = edges[6]
                            for j in range(ns):
                                d = started[j]
                                w = deciders[d]
                                e_dur[m_edges, w] = dur[w, chosen[d], sd[j]]
                                e_dur[m_edges, w] += change[edge(s, chosen[d], indptr, op)]
                            m_edges += 1
                            if m_edges * edge_bytes + n * node_bytes > max_bytes:
                                overflow, over = True, OVER_MEMORY
                                break
                        # Next durations.
                        j = ns - 1
                        while j >= 0:
                            sd[j] += 1
                            if sd[j] < ndur[deciders[started[j]], chosen[started[j]]]:
                                break
                            sd[j] = 0
                            j -= 1
                        if j < 0:
                            break
                    if overflow:
                        break
            if overflow:
                break
            # Next joint choice.
            d = nd - 1
            while d >= 0:
                digit[d] += 1
                if digit[d] < n_opts[d]:
                    break
                digit[d] = 0
                d -= 1
            if d < 0:
                break
        if overflow:
            break
    e_src, e_dst, e_cost, e_side, e_dev, e_ops, e_dur = edges
    counts = np.array([expanded, n, m_edges], np.int64)
    if overflow:  # what was built is dropped: only the counts are returned
        n = m_edges = 0
    return (
        over if overflow else 0,
        counts,
        rows[:n].copy(),
        starts,
        e_src[:m_edges].copy(),
        e_dst[:m_edges].copy(),
        e_cost[:m_edges].copy(),
        e_side[:m_edges].copy(),
        e_ops[:m_edges].copy(),
        e_dur[:m_edges].copy(),
        e_dev[:m_edges].copy(),
    )


@numba.njit(cache=True)
def _append_edge(edges, m, v, t, cost, side, dev, deciders, chosen, nd):  # pragma: no cover
    """Write edge ``m`` (``v -> t``, its cost, side and deviations; the deciders' choices as
    its operations, every other worker and every duration NONE) into ``edges``, grown first
    when full. Returns the edge arrays (new ones when grown)."""
    e_src, e_dst, e_cost, e_side, e_dev, e_ops, e_dur = edges
    if m >= e_src.shape[0]:
        size = 2 * e_src.shape[0]
        e_src = grow(e_src, size)
        e_dst = grow(e_dst, size)
        e_cost = grow(e_cost, size)
        e_side = grow(e_side, size)
        e_dev = grow(e_dev, size)
        e_ops = grow_rows(e_ops, size)
        e_dur = grow_rows(e_dur, size)
    e_src[m] = v
    e_dst[m] = t
    e_cost[m] = cost
    e_side[m] = side
    e_dev[m] = dev
    e_ops[m, :] = NONE
    e_dur[m, :] = NONE
    for d in range(nd):
        e_ops[m, deciders[d]] = chosen[d]
    return (e_src, e_dst, e_cost, e_side, e_dev, e_ops, e_dur)


@numba.njit(cache=True)
def _intern(new, nw, index, rows, stack, n, top, max_nodes):  # pragma: no cover - compiled
    """The node of state row ``new``: found in ``index``, or appended (to ``rows`` and the
    work ``stack``, grown as needed). Returns ``(t, rows, stack, n, top)``; ``t`` is -1 when a
    new node would pass ``max_nodes``."""
    key = _key(new, nw)
    if key in index:
        return index[key], rows, stack, n, top
    if n >= max_nodes:
        return -1, rows, stack, n, top
    if n >= rows.shape[0]:
        grown = np.empty((2 * rows.shape[0], rows.shape[1]), np.int32)
        grown[:n] = rows[:n]
        rows = grown
        gs = np.empty(2 * stack.shape[0], np.int64)
        gs[:top] = stack[:top]
        stack = gs
    index[key] = n
    rows[n] = new
    stack[top] = n
    return n, rows, stack, n + 1, top + 1


@numba.njit(cache=True)
def grow(a, size):  # pragma: no cover - compiled
    """``a`` (1-d) in a new array of ``size`` entries (the first ones copied)."""
    out = np.empty(size, a.dtype)
    out[: a.shape[0]] = a
    return out


@numba.njit(cache=True)
def grow_rows(a, size):  # pragma: no cover - compiled
    """``a`` (2-d) in a new array of ``size`` rows (the first ones copied)."""
    out = np.empty((size, a.shape[1]), a.dtype)
    out[: a.shape[0]] = a
    return out
