"""The concurrent game solved on the fly: ``W*(k)`` without building the game.

The game is walked from its start by the rules of :mod:`asp.concurrent.rules`; only the
positions the search needs are ever made. Two compiled kernels (numba, ``cache=True``) do
the work: a minimax search for values and a builder of the *policy game* (the states one
robot policy can reach against every human, with all their replies), whose exact solution
(:func:`asp.game.solve.solve`) is that policy's certified worst case state by state.

The search
----------
Depth-first minimax, alpha-beta with fail-soft bounds, over positions (the robot side on
turn); a human node (a position and one commitment) is the max over its replies, searched
inside its position's frame, and is not stored. A transposition table keyed on the positions'
canonical keys
(:meth:`asp.concurrent.rules.Rules.key`: alike operations and budgets that no longer bind
identified, both exact) keeps for each position a proven interval ``[lo, hi]`` of its value
and the commitment that proved ``hi``. Depth-first was chosen over best-first (AO*) for
memory: the only memory is the table (sized before the search, see *Limits*), and the
recursion is as deep as the number of events. Times are the rules' integers, so every
comparison is exact.

Every rule that cuts the search, with its proof:

1. *Alpha-beta with a transposition table.* A call with window ``(a, b)`` returns ``v``
   with ``W <= v`` if ``v <= a``, ``W >= v`` if ``v >= b``, else ``W = v`` (the standard
   fail-soft invariant, by induction over the calls). A stored interval narrows the window
   or answers at once; the commitment stored with ``hi`` achieves ``hi`` (its returned
   value is an upper bound of its true one).
2. *Admissible lower bounds.* ``lo`` starts at :meth:`~asp.concurrent.rules.Rules.lower_bound`
   (critical path and per-side load against a person who follows and is slow, one human
   strategy: the value is at least the robot's best against it). A commitment's human node
   is at least the bound of the position with the commitment's starts and instructions
   running (the follow reply, durations at their longest, is one reply): commitments are
   tried in increasing order of it, and the loop stops at the first whose bound reaches the
   best value found (or the window's top), which neither it nor any later one can beat.
3. *Budgets.* A human allowed ``b + 1`` deviations can play every strategy of ``b``, so
   ``W(s, b - 1) <= W(s, b) <= W(s, b + 1) <= W(s, R)`` (``R`` the cap): a new position takes
   ``lo`` from the same position one budget lower and ``hi`` from one budget higher or from
   the cap when the table has them (``W*(inf)`` is searched second, so the cap's entries are
   there for most positions the later budgets meet). At
   the root, the search for ``k`` runs in the window ``(W*(k - 1), W*(inf) + 1)`` (rule 7).
4. *Instructions that cannot bind.* With the budget at its cap (every deviation affordable,
   :mod:`asp.concurrent.rules`) the person may do anything at no cost, and the child's budget
   is its own cap whatever the instruction (a reply with ``d`` starting deviations has at
   most ``H * d`` in all, and starts at least ``d`` of the operations the cap counts). So
   the replies to two commitments with the same robot starts depend only on which free
   humans are told to wait (a told-to-wait person may idle, a told-to-work one only with
   nothing to start), and telling a set of them to wait gives the human side a superset
   of the replies of any subset. Per robot starts and set of waiting persons one
   commitment is kept (the one of least bound of rule 2: the instruction a person sees),
   and none whose set has a kept strict subset.
5. *Symmetry.* Positions are orbits under the alike-part symmetry (rules' docstring).
6. *A first move without bounds.* The table's move of the position, else the move of the
   same position one budget lower (then one higher: a position's commitments do not depend
   on its budget), else the CP-SAT schedule's commitment (:func:`_schedule_choice`) is
   searched first, before the other commitments' bounds of rule 2 are computed; when it
   cuts (its value at most the window's bottom) they never are. Any commitment is a legal
   move, so its value is an upper bound of the position's (rule 1 holds whichever move is
   tried first, kept by rule 4 or not); only the order changes, never the value.
7. *Proven floors.* A caller that has proved ``W >= f`` (the CP-SAT bound, a relaxation
   with the person following at the longest durations, for ``k = 0``; ``W*(k - 1)`` for
   ``k``, rule 3; ``W*(0)`` for ``k = inf``) searches in the window ``(f, U)``: a result
   ``v <= f`` proves ``W <= v`` (rule 1), so ``W = f``. Then a first line that reaches the
   floor ends the search at once (the schedule's line at ``k = 0`` when CP-SAT proved it
   optimal), instead of refuting every other commitment.

8. *Moves memoised.* A position's commitments (:func:`asp.concurrent.rules.commit_rows`)
   depend on its state and on which operation each worker runs, not on the remaining times
   nor on the budget (the kernel reads no other field), so one :class:`Search` keeps them
   (across its calls: every budget and the robust policy's game) per
   ``(state, running operations)`` (:func:`_commits_of`) and positions that differ only
   there share one list. Likewise the human side's joint choices after a commitment
   (:func:`asp.concurrent.rules.reply_choices`: every rule of a reply but the budget) per
   state, running operations and instructions (:func:`_choices_of`); the budget, the
   durations and the next event are applied to them per position
   (:func:`asp.concurrent.rules.replies_of`). The same lists, so the values and the order
   are unchanged; each memo holds at most one entry per position or human node expanded.
9. *Deviation-aware floors.* A new position at budget ``b`` takes as ``lo`` the largest of
   its static bound and the ``lo`` the table has proved for the same position at every
   budget ``b' < b`` (not only ``b - 1``). *Proof*: a human side allowed ``b`` deviations
   can play every strategy of ``b'``, so ``W(s, b') <= W(s, b)`` (rule 3, by induction over
   the budgets between), and each stored ``lo`` is a proven lower bound of its own value
   (rule 1). A human with deviations left is thus credited with what the table proved
   about the harm of the deviations it had before; the bound is exact wherever a lower
   budget's value is. The values are unchanged (rule 1 holds for any admissible ``lo``);
   only the windows close earlier.
10. *A higher budget's move.* Where the robust policy needs the move of a position
   ``(s, b)`` (its policy game, below) and the table proves ``W(s, b) >= v`` while the same
   position at a budget ``b' > b`` has a stored move ``m`` proving ``hi(s, b') <= v``, ``m``
   is optimal at ``(s, b)`` with value ``v``, without a search. *Proof*: ``m``'s human node
   at ``b`` has a subset of its replies at ``b'`` (a reply's deviations must fit the
   budget), each leading to the same position at a budget no larger, so by rule 3 its
   value at ``b`` is at most its value at ``b'``, at most ``hi(s, b') <= v <= W(s, b)``,
   and no move does better than ``W(s, b)``. (The commitments do not depend on the budget,
   rule 8, so ``m`` is the same commitment at both.) The policy is still optimal at every
   state it reaches; where two moves are optimal it may take the other one. By the same
   argument a ``hi`` taken from a higher budget (rule 3) is stored with that budget's move,
   which achieves it (rule 1's invariant), and a position met again is narrowed to what
   the other budgets' entries prove by then (rules 9 and 10) before it is expanded.

The values ``W*(k)`` for ``k = 0, 1, ...`` and ``W*(inf)`` (the budget at its cap) share one
table; a curve stops when ``W*(k) = W*(inf)`` (flat), at ``max_k``, or when a limit is hit.

The robust policy and certificates
----------------------------------
The plan's policy is built as a policy game: at each position it reaches, the search is
run to the exact value and its stored commitment taken (so the policy is optimal at every
state it reaches, after any human move, not only on the principal line); every human reply
is followed. Solving that small DAG gives each state's bound, and it is an ordinary
:class:`asp.concurrent.build.ConcurrentGame`: the plan file, the timelines and the runtime
advisor read it as they read the compiled game. A fixed policy is certified the same way
(an exact best response of the human side against it: the policy game of the CP-SAT
schedule run as a plan, of a greedy adaptive policy, or of the table's moves where the
search was cut short). One policy game holds every budget's start, and ``k = inf`` is the
budget at its cap in the same game, so a fixed policy's certified worst case never falls
as ``k`` grows.

Limits and the anytime answer
-----------------------------
The table is sized before the search from the memory allowed (only its key array is read
before a slot is written, so only the slots in use are resident) (``memory``: its bytes per
entry are known, :func:`table_entries`); it never grows. The search stops when the table is
full, at ``max_nodes`` positions expanded, or at ``time_limit``; the policy games stop at
their own node limit (from the same memory). ``time_limit`` is in search seconds, counted in
positions (:data:`POSITIONS_PER_SECOND`), so the search stops at the same position on every
run at any load and the plan is the same bytes; the wall clock stops it only as a safety
net (:func:`asp.schedule.cpsat.wall_safety`, the CP-SAT stage's rule), and then
:attr:`Search.wall_stop` says so (``timings.json``, never the plan). Stopped,
:func:`asp.concurrent.curve.solve_curve` still answers:
for each ``k`` a proven lower bound ``L(k)`` (the CP-SAT bound, the start's bound, what the
search proved, and ``L(k - 1)``: the curve never falls) and the least certified worst case
``U(k)`` of the policies above (and of larger budgets: ``U(k) <= U(k + 1)``), the policy
handed to the cell being the one certified at ``U``. ``W*(k)`` lies in ``[L(k), U(k)]``.
"""

from __future__ import annotations

import functools
import sys
import threading
import time
from dataclasses import dataclass, field
from typing import NamedTuple

import numba
import numpy as np
from numba.typed import List

from asp.concurrent.build import ActionRows, ConcurrentGame, NodeRows, game_of
from asp.concurrent.kernel import grow, grow_rows
from asp.concurrent.model import UNBOUNDED
from asp.concurrent.rules import (
    NONE,
    Rules,
    budget_cap_of,
    commit_rows,
    committed_row,
    is_done,
    key_of,
    lower_bound_of,
    replies_of,
    reply_choices,
    reply_rows,
)
from asp.graph.together import edge
from asp.heap import memory_budget
from asp.schedule.cpsat import wall_safety

INF = 1 << 60
"""A value above every makespan (scaled)."""
ROBUST, SCHEDULE, GREEDY, HYBRID = 0, 1, 2, 3
"""Robot policies of a policy game: the search's (exact, per budget), the CP-SAT schedule run
as a plan (:func:`asp.concurrent.robustness.schedule_rule`'s rule), greedy (least bound of
rule 2), and the table's moves where it has them (of the state at the highest budget the
table holds), else greedy. The last three choose by the state alone, not the budget: fixed
policies, whose certified worst case never falls as ``k`` grows."""
DEFAULT_MEMORY = 1 << 30
"""Bytes for the search table and the policy games by default (1 GiB)."""
DEFAULT_MAX_NODES = 50_000_000
"""Positions the search expands at most by default."""
GENERATOR = "asmplan.concurrent.search/1"
"""The ``generator`` of a policy game's DAG."""
TICK = (1 << 15) - 1
"""The clock and the progress line are looked at every ``TICK + 1`` positions."""
POSITIONS_PER_SECOND = 20_000
"""Positions a search second stands for: the search's ``time_limit`` (and the certificates'
share of it, :func:`asp.concurrent.certify.best_response_values`) is counted in positions
expanded (valued), about a second of one core's search each (the real products' searches
ran 14,000 to 22,000 positions a CPU second), so the same input stops at the same position
whatever the load."""

# stats array
NODES, NODE_LIMIT, ABORT, ENTRIES, MAX_ENTRIES, DEADLINE, PROGRESS, NEXT_REPORT = range(8)
ROOT_BEST, BUDGET, T0 = 8, 9, 10
N_STATS = 11
STOP_NODES, STOP_MEMORY, STOP_TIME = 1, 2, 3
STOP_NAMES = {STOP_NODES: "node limit", STOP_MEMORY: "memory limit", STOP_TIME: "wall-clock limit"}
"""Why a search stopped; ``"time limit"`` is its budget of search seconds (a stop at
``NODE_LIMIT`` below ``max_nodes``, :attr:`Search.stopped`), ``STOP_TIME`` the wall clock's
safety net."""


class Table(NamedTuple):
    """An open-addressing hash table of positions (capacity a power of two).

    keys (C, K) int64 : canonical keys, zero rows free (a key's first word is never 0);
    lo, hi (C,) int64 : the proven interval of the value (search) or the node id (policy
    games, in ``lo``); move (C,) int64 : the commitment index that proved ``hi``, or -1.
    """

    keys: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    move: np.ndarray


ENTRY_BYTES = 3 * 8
"""Bytes of one table entry besides its key words (``lo``, ``hi``, ``move``)."""
LOAD = 0.7
"""Largest share of a table's slots in use."""
MIN_ENTRIES = 1024
"""The least search table worth starting."""
FIRST_ENTRIES = 1 << 16
"""Entries of a search table at first; it grows four-fold when full, up to the memory
allowed (a table sized for all the memory at once would be resident soon: its slots are
hashed, so a few entries touch every page)."""


def table_entries(memory: int, key_words: int) -> int:
    """Positions a table of at most ``memory`` bytes holds (its slots a power of two, at most
    :data:`LOAD` of them used)."""
    per_slot = 8 * key_words + ENTRY_BYTES
    slots = 1 << max(4, int(memory // per_slot).bit_length() - 1)
    return int(slots * LOAD)


def new_table(entries: int, key_words: int) -> Table:
    """A free table for ``entries`` positions."""
    slots = 1 << max(4, (int(np.ceil(entries / LOAD)) - 1).bit_length())
    # Only the keys are read before a slot is written (a zero key: free), so the other
    # arrays are left as the allocator gives them: pages are only resident once used.
    return Table(
        keys=np.zeros((slots, key_words), dtype=np.int64),
        lo=np.empty(slots, dtype=np.int64),
        hi=np.empty(slots, dtype=np.int64),
        move=np.empty(slots, dtype=np.int64),
    )


# --------------------------------------------------------------------------- table kernels


@numba.njit(cache=True)
def _rehash(old, new):  # pragma: no cover - compiled
    """Every entry of the table ``old`` into the (larger, free) table ``new``."""
    for i in range(old.keys.shape[0]):
        if old.keys[i, 0] != 0:
            j = _slot(new, old.keys[i])
            new.keys[j] = old.keys[i]
            new.lo[j] = old.lo[i]
            new.hi[j] = old.hi[i]
            new.move[j] = old.move[i]


@numba.njit(cache=True)
def _slot(H, key):  # pragma: no cover - compiled
    """The slot of ``key``: where it is, or the free slot where it goes."""
    h = np.uint64(0x9E3779B97F4A7C15)
    for w in range(key.shape[0]):
        h ^= np.uint64(key[w])
        h *= np.uint64(0xBF58476D1CE4E5B9)
        h ^= h >> np.uint64(31)
    mask = np.uint64(H.keys.shape[0] - 1)
    i = np.int64(h & mask)
    kw = key.shape[0]
    while True:
        if H.keys[i, 0] == 0:
            return i
        same = True
        for w in range(kw):
            if H.keys[i, w] != key[w]:
                same = False
                break
        if same:
            return i
        i = (i + 1) & np.int64(mask)


@numba.njit(cache=True)
def _find(H, key):  # pragma: no cover - compiled
    """The slot holding ``key``, or -1."""
    i = _slot(H, key)
    return -1 if H.keys[i, 0] == 0 else i


@numba.njit(cache=True, inline="always")
def _at_budget(T, key, b, nb):  # pragma: no cover - compiled
    """The key ``key`` of a position at budget ``b`` with its budget set to ``nb`` (a copy;
    the budget is one packed field, :func:`asp.concurrent.rules.key_of`)."""
    out = key.copy()
    out[T.kword[1]] += (nb - b) << T.kshift[1]
    return out


@numba.njit(cache=True)
def _new_bounds(T, H, row, key, lb):  # pragma: no cover - compiled
    """The interval a new entry of the position ``row`` (its key ``key``) starts with:
    ``lo`` its lower bound (``lb`` when given, >= 0), raised to the best ``lo`` the table has
    proved for the same position at any lower budget (rule 9), and ``hi`` its one budget
    higher's or the cap's (rule 3), never below ``lo``; and the move stored with that ``hi``
    (-1 for none), which achieves it at ``row``'s budget too (rule 10)."""
    lo = lb if lb >= 0 else lower_bound_of(T, row)
    hi = INF
    mv = -1
    b = row[1]
    for nb in range(b - 1, -1, -1):  # fewer deviations left: W never rises (rule 9)
        j = _find(H, _at_budget(T, key, b, nb))
        if j >= 0 and H.lo[j] > lo:
            lo = H.lo[j]
    cap = budget_cap_of(T, row)
    for nb in (b + 1, cap):  # one budget higher, and the cap (k = inf): W never falls
        if nb > b:
            j = _find(H, _at_budget(T, key, b, nb))
            if j >= 0 and H.hi[j] < hi:
                hi = H.hi[j]
                mv = H.move[j]
    return lo, max(hi, lo), mv


@numba.njit(cache=True)
def _entry(T, H, row, st, lb):  # pragma: no cover - compiled
    """The slot of the position ``row``, made when new with the interval and move of
    :func:`_new_bounds`. -1 (and the stop flag) when the table is full."""
    key = key_of(T, row)
    i = _slot(H, key)
    if H.keys[i, 0] != 0:
        return i
    if st[ENTRIES] >= st[MAX_ENTRIES]:
        st[ABORT] = STOP_MEMORY
        return -1
    lo, hi, mv = _new_bounds(T, H, row, key, lb)
    i = _slot(H, key)  # (the probes above did not write)
    H.keys[i] = key
    H.lo[i] = lo
    H.hi[i] = hi
    H.move[i] = mv
    st[ENTRIES] += 1
    return i


@numba.njit(cache=True)
def _refresh(T, H, row, key, i):  # pragma: no cover - compiled
    """The entry ``i`` of ``row`` narrowed to what the table now proves at the other budgets
    (rules 9 and 10: ``lo`` from every lower budget, ``hi`` with its move from one higher or
    the cap), for a position met again after those entries improved."""
    lo, hi, mv = _new_bounds(T, H, row, key, H.lo[i])
    if lo > H.lo[i]:
        H.lo[i] = lo
    if mv >= 0 and hi < H.hi[i]:
        H.hi[i] = max(hi, H.lo[i])
        H.move[i] = mv


@numba.njit(cache=True)
def _move_above(T, H, row, key, v, m):  # pragma: no cover - compiled
    """A move of the same position at a higher budget that proved a value at most ``v``
    there, or -1 (rule 10: with ``v <= W`` at ``row``'s budget, it is optimal there)."""
    b = row[1]
    for nb in range(b + 1, budget_cap_of(T, row) + 1):
        j = _find(H, _at_budget(T, key, b, nb))
        if j >= 0 and 0 <= H.move[j] < m and H.hi[j] <= v:
            return H.move[j]
    return -1


# --------------------------------------------------------------------------- search kernels


@numba.njit(cache=True)
def _estimate(T, row, commit):  # pragma: no cover - compiled
    """Rule 2's bound of a commitment: the lower bound of the position with the robots'
    starts and the instructed persons' operations running (a person's at its longest)."""
    nw = T.side.shape[0]
    cur, told = committed_row(T, row, commit)
    s = row[0]
    for w in range(nw):
        o = told[w]
        if o >= 0:
            cur[2 + w] = o
            cur[2 + nw + w] = (
                T.dur[w, o, T.ndur[w, o] - 1] + T.change[edge(s, T.label[o], T.indptr, T.lab)]
            )
    return lower_bound_of(T, cur)


@numba.njit(cache=True)
def _dominant(T, row, commits, est):  # pragma: no cover - compiled
    """(M,) bool: the commitments rule 4 keeps (all when the budget is below its cap)."""
    m = commits.shape[0]
    keep = np.ones(m, np.bool_)
    if row[1] < budget_cap_of(T, row):
        return keep
    nw = T.side.shape[0]
    mask = np.zeros(m, np.int64)
    for i in range(m):
        bit = 0
        for w in range(nw):
            if T.side[w] == 1 and commits[i, w] != NONE:
                if commits[i, w] == -1:
                    mask[i] |= 1 << bit
                bit += 1
    lo = 0
    while lo < m:  # runs of equal robot starts (robots are the odometer's leading digits)
        hi = lo + 1
        while hi < m:
            same = True
            for w in range(nw):
                if T.side[w] == 0 and commits[hi, w] != commits[lo, w]:
                    same = False
                    break
            if not same:
                break
            hi += 1
        for i in range(lo, hi):  # one per set of waiting persons: the least bound
            for j in range(lo, hi):
                better = est[j] < est[i] or (est[j] == est[i] and j < i)
                if j != i and keep[j] and mask[j] == mask[i] and better:
                    keep[i] = False
                    break
        for i in range(lo, hi):  # none whose set has a strict subset kept
            if not keep[i]:
                continue
            for j in range(lo, hi):
                if keep[j] and mask[j] != mask[i] and (mask[j] & mask[i]) == mask[j]:
                    keep[i] = False
                    break
        lo = hi
    return keep


@numba.njit(cache=True)
def _ordered(T, row, commits, tried):  # pragma: no cover - compiled
    """Rule 2's bounds of the commitments at ``row`` and the order they are tried in: those
    rule 4 keeps by increasing bound; ``tried`` (already searched, or -1) and the others
    get the bound INF (never tried)."""
    m = commits.shape[0]
    est = np.empty(m, np.int64)
    for i in range(m):
        est[i] = _estimate(T, row, commits[i])
    keep = _dominant(T, row, commits, est)
    for i in range(m):
        if not keep[i] or i == tried:
            est[i] = INF
    return est, np.argsort(est, kind="mergesort")


@numba.njit(cache=True)
def _hint(T, H, row, commits, prefs, n_prefs):  # pragma: no cover - compiled
    """The commitment to try first at a position the table has no move for (rule 6): the
    move of the same position one budget lower, else one higher (the commitments of a
    position do not depend on its budget), else the CP-SAT schedule's; -1 for none."""
    m = commits.shape[0]
    other = row.copy()
    b = row[1]
    for nb in (b - 1, b + 1):
        if nb < 0 or nb > budget_cap_of(T, row):
            continue
        other[1] = nb
        j = _find(H, key_of(T, other))
        if j >= 0 and 0 <= H.move[j] < m:
            return H.move[j]
    if n_prefs.sum() > 0:
        return _schedule_choice(T, row, commits, prefs, n_prefs)
    return -1


@numba.njit(cache=True)
def _tick(st):  # pragma: no cover - compiled
    """Look at the clock (and print the progress line when it is due); True to stop."""
    with numba.objmode(now="float64"):
        now = time.perf_counter()
    ms = np.int64(now * 1000)
    if st[DEADLINE] > 0 and ms >= st[DEADLINE]:
        st[ABORT] = STOP_TIME
        return True
    if st[PROGRESS] and ms >= st[NEXT_REPORT]:
        st[NEXT_REPORT] = ms + 1000
        nodes, entries, best, budget = st[NODES], st[ENTRIES], st[ROOT_BEST], st[BUDGET]
        secs = (ms - st[T0]) / 1000.0
        with numba.objmode():
            _report(nodes, entries, best, budget, secs)
    return False


def _report(nodes: int, entries: int, best: int, budget: int, secs: float) -> None:
    found = "" if best >= INF else f", best commitment so far {best}"
    print(
        f"  concurrent search, budget {budget}: {nodes:,} positions expanded, {entries:,} "
        f"in the table{found} ({secs:.0f} s)",
        file=sys.stderr,
        flush=True,
    )


@numba.njit(cache=True)
def _new_moves(nw, slots, pool):  # pragma: no cover - compiled
    """A free memo of commitments (:func:`_commits_of`): keys ``(state + 1, running ops)``
    (``slots``, a power of two), each entry's first row and count in ``pool`` (rows of
    ``nw``), and ``[entries, pool rows used]``."""
    return (
        np.zeros((slots, 2), np.int64),
        np.empty(slots, np.int64),
        np.empty(slots, np.int64),
        np.empty((pool, nw), np.int64),
        np.zeros(2, np.int64),
    )


@numba.njit(cache=True)
def _moves_slot(keys, k0, k1):  # pragma: no cover - compiled
    """The slot of the memo key ``(k0, k1)``: where it is, or the free slot where it goes."""
    h = np.uint64(k0) * np.uint64(0x9E3779B97F4A7C15)
    h ^= np.uint64(k1) * np.uint64(0xBF58476D1CE4E5B9)
    h ^= h >> np.uint64(29)
    mask = keys.shape[0] - 1
    i = np.int64(h & np.uint64(mask))
    while keys[i, 0] != 0 and not (keys[i, 0] == k0 and keys[i, 1] == k1):
        i = (i + 1) & mask
    return i


@numba.njit(cache=True)
def _moves_grow(mv, more):  # pragma: no cover - compiled
    """The memo ``mv`` in arrays with room for one more entry of ``more`` rows."""
    keys, start, count, pool, meta = mv
    slots = keys.shape[0]
    while 2 * (meta[0] + 1) > slots:
        slots *= 2
    rows = pool.shape[0]
    while meta[1] + more > rows:
        rows *= 2
    new = _new_moves(pool.shape[1], slots, rows)
    nk, ns, nc, npool, nmeta = new
    npool[: meta[1]] = pool[: meta[1]]
    nmeta[:] = meta
    for i in range(keys.shape[0]):
        if keys[i, 0] != 0:
            j = _moves_slot(nk, keys[i, 0], keys[i, 1])
            nk[j] = keys[i]
            ns[j] = start[i]
            nc[j] = count[i]
    return new


@numba.njit(cache=True)
def _memo_put(mv, k0, k1, rows):  # pragma: no cover - compiled
    """``rows`` into the memo ``mv`` under the key ``(k0, k1)`` (absent); ``(slot, mv)``,
    the memo grown when it was full (the caller keeps the new one)."""
    keys, start, count, pool, meta = mv
    m = rows.shape[0]
    if 2 * (meta[0] + 1) > keys.shape[0] or meta[1] + m > pool.shape[0]:
        mv = _moves_grow(mv, m)
        keys, start, count, pool, meta = mv
    i = _moves_slot(keys, k0, k1)
    keys[i, 0] = k0
    keys[i, 1] = k1
    start[i] = meta[1]
    count[i] = m
    pool[meta[1] : meta[1] + m] = rows
    meta[1] += m
    meta[0] += 1
    return i, mv


@numba.njit(cache=True)
def _commits_of(T, mv, row):  # pragma: no cover - compiled
    """:func:`asp.concurrent.rules.commit_rows` of ``row``, memoised in ``mv`` per state and
    running operations (rule 8): ``(commitments, mv)``."""
    nw = T.side.shape[0]
    bits = T.kbits[2]
    if nw * bits > 62:  # the running operations do not pack in one word: no memo
        return commit_rows(T, row), mv
    k1 = 0
    for w in range(nw):
        k1 |= (row[2 + w] + 2) << (bits * w)
    k0 = row[0] + 1
    i = _moves_slot(mv[0], k0, k1)
    if mv[0][i, 0] == 0:
        i, mv = _memo_put(mv, k0, k1, commit_rows(T, row))
    return mv[3][mv[1][i] : mv[1][i] + mv[2][i]], mv


@numba.njit(cache=True)
def _choices_of(T, mv, cur, told):  # pragma: no cover - compiled
    """:func:`asp.concurrent.rules.reply_choices` at ``cur`` told ``told``, memoised in ``mv``
    per state, running operations and instructions (rule 8): ``(choices, mv)``."""
    nw = T.side.shape[0]
    bits = T.kbits[2]
    if 2 * nw * bits > 62:  # no memo
        return reply_choices(T, cur, told), mv
    k1 = 0
    for w in range(nw):
        k1 |= (cur[2 + w] + 2) << (bits * w)
        k1 |= (told[w] + 2) << (bits * (nw + w))
    k0 = cur[0] + 1
    i = _moves_slot(mv[0], k0, k1)
    if mv[0][i, 0] == 0:
        i, mv = _memo_put(mv, k0, k1, reply_choices(T, cur, told))
    return mv[3][mv[1][i] : mv[1][i] + mv[2][i]], mv


ENTER, NEXT_COMMIT, NEXT_REPLY, AFTER_CHILD = 0, 1, 2, 3
"""Phases of a frame of :func:`_search_memo`'s explicit stack."""


@numba.njit(cache=True)
def _search_memo(T, H, root, alpha, beta, st, prefs, n_prefs, moves, replies):  # pragma: no cover
    """The value of position ``root`` in the window ``(alpha, beta)`` (fail-soft, module
    docstring); 0 when stopped (``st[ABORT]``; nothing is stored then). ``moves`` and
    ``replies`` are the memos of rule 8 (:func:`_commits_of`, :func:`_choices_of`), kept by
    the caller from one call to the next (they depend on the rules alone): ``(value, moves,
    replies)``, the memos as grown.

    Depth-first with an explicit stack of positions (numba cannot cache a recursive
    function): a frame is a position, its commitments in the order tried and, for the one
    being tried, its human node's replies. A frame's depth is at most the operations + 2
    (each event completes one).

    One long function on purpose (it stays above the complexity limit): the phases of a
    frame are one nopython loop, and splitting it costs speed. Each phase as its own
    function would be a call between jitted functions taking the rules' arrays ``T``, the
    transposition table ``H`` and the stack's dozen per-frame arrays, and the loop state
    (the frame, its window and cursors, the value so far) would leave the locals numba
    keeps in registers. What touches none of that state is split out: :func:`_entry`,
    :func:`_find`, :func:`_estimate`, :func:`_dominant`, :func:`_tick`."""
    nw = T.side.shape[0]
    width = root.shape[0]
    D = T.label.shape[0] + 3
    rows = np.empty((D, width), np.int64)
    phase = np.zeros(D, np.int64)
    lbh = np.full(D, -1, np.int64)  # a lower bound the parent computed, or -1
    win_a = np.empty(D, np.int64)  # the call's window
    win_b = np.empty(D, np.int64)
    a_ = np.empty(D, np.int64)  # narrowed by the table
    b_ = np.empty(D, np.int64)
    slot = np.empty(D, np.int64)
    first = np.empty(D, np.int64)
    jc = np.empty(D, np.int64)  # next commitment (position in the order)
    best = np.empty(D, np.int64)
    best_i = np.empty(D, np.int64)
    pruned = np.empty(D, np.int64)
    ci = np.empty(D, np.int64)  # the commitment being tried
    beta_h = np.empty(D, np.int64)
    jr = np.empty(D, np.int64)  # next reply (position in the order)
    v = np.empty(D, np.int64)  # the human node's max so far
    cur_r = np.empty(D, np.int64)  # the reply whose child is being searched
    commits_l = List()
    est_l = List()
    order_l = List()
    rrows_l = List()
    rdelta_l = List()
    rlbs_l = List()
    rby_l = List()
    for _ in range(D):  # (made as the rules' kernels make them: the same array types)
        commits_l.append(np.empty((1, nw), np.int64)[:0])
        est_l.append(np.empty(0, np.int64))
        order_l.append(np.empty(0, np.int64))
        rrows_l.append(np.empty((1, width), np.int64)[:0])
        rdelta_l.append(np.empty((1, 2), np.int64)[:0, 1])
        rlbs_l.append(np.empty(0, np.int64))
        rby_l.append(np.empty(0, np.int64))
    if root[0] < 0:
        return 0, moves, replies
    d = 0
    rows[0] = root
    win_a[0], win_b[0], phase[0], lbh[0] = alpha, beta, ENTER, -1
    ret = 0
    while d >= 0:
        p = phase[d]
        if p == ENTER:
            row = rows[d]
            made = st[ENTRIES]
            s_ = _entry(T, H, row, st, lbh[d])
            if s_ < 0:
                return 0, moves, replies
            lo, hi = H.lo[s_], H.hi[s_]
            if lo < win_b[d] and lo < hi and hi > win_a[d] and st[ENTRIES] == made:
                # met again: the other budgets' entries may prove more by now (rules 9, 10)
                _refresh(T, H, row, key_of(T, row), s_)
                lo, hi = H.lo[s_], H.hi[s_]
            if lo >= win_b[d] or lo == hi:
                ret = lo
                d -= 1
                continue
            if hi <= win_a[d]:
                ret = hi
                d -= 1
                continue
            st[NODES] += 1
            if st[NODES] >= st[NODE_LIMIT]:
                st[ABORT] = STOP_NODES
                return 0, moves, replies
            if (st[NODES] & TICK) == 0 and _tick(st):
                return 0, moves, replies
            slot[d] = s_
            a_[d] = max(win_a[d], lo)
            b_[d] = min(win_b[d], hi)
            commits, moves = _commits_of(T, moves, row)
            m = commits.shape[0]
            f = H.move[s_]
            if not (0 <= f < m):
                f = _hint(T, H, row, commits, prefs, n_prefs)
            if f >= 0:  # the table's move, else a hint, alone first (rule 6)
                est = np.zeros(m, np.int64)
                order = np.full(1, f, np.int64)
            else:
                est, order = _ordered(T, row, commits, -1)
            commits_l[d] = commits
            est_l[d] = est
            order_l[d] = order
            first[d] = f
            jc[d] = 0
            best[d] = INF
            best_i[d] = -1
            pruned[d] = INF
            phase[d] = NEXT_COMMIT
            continue
        if p == NEXT_COMMIT:
            commits = commits_l[d]
            est = est_l[d]
            order = order_l[d]
            m = order.shape[0]
            chosen = -1
            if jc[d] == m and first[d] >= 0 and best[d] > a_[d]:
                # the first move did not cut: the others in order of their bounds
                est, order = _ordered(T, rows[d], commits, first[d])
                est_l[d] = est
                order_l[d] = order
                first[d] = -1
                jc[d] = 0
                m = order.shape[0]
            while jc[d] < m:
                i = order[jc[d]]
                if est[i] >= min(b_[d], best[d]):
                    if est[i] < pruned[d]:
                        pruned[d] = est[i]
                    jc[d] = m
                    break
                chosen = i
                jc[d] += 1
                break
            if chosen < 0 or best[d] <= a_[d]:
                # finished: store the result (module docstring, rule 1)
                bst = best[d]
                if bst >= b_[d] and pruned[d] < bst:
                    bst = pruned[d]
                s_ = slot[d]
                if bst <= a_[d]:
                    H.hi[s_] = bst
                    H.move[s_] = best_i[d]
                elif bst >= b_[d]:
                    if bst > H.lo[s_]:
                        H.lo[s_] = bst
                else:
                    H.lo[s_] = bst
                    H.hi[s_] = bst
                    H.move[s_] = best_i[d]
                ret = bst
                d -= 1
                continue
            # The human node of the chosen commitment: the max over its replies.
            ci[d] = chosen
            beta_h[d] = min(b_[d], best[d])
            cur_c, told_c = committed_row(T, rows[d], commits[chosen])
            choices, replies = _choices_of(T, replies, cur_c, told_c)
            ops, durs, dev, delta, rws = replies_of(T, rows[d], cur_c, choices)
            n = delta.shape[0]
            lbs = np.empty(n, np.int64)
            key_r = np.empty(n, np.int64)
            for r in range(n):
                if rws[r, 0] < 0:
                    lbs[r] = 0
                else:
                    jj = _find(H, key_of(T, rws[r]))
                    lbs[r] = H.lo[jj] if jj >= 0 else lower_bound_of(T, rws[r])
                key_r[r] = -(delta[r] + lbs[r])
            rrows_l[d] = rws
            rdelta_l[d] = delta
            rlbs_l[d] = lbs
            rby_l[d] = np.argsort(key_r, kind="mergesort")
            jr[d] = 0
            v[d] = -1 if n > 0 else INF  # (no reply: never taken)
            phase[d] = NEXT_REPLY
            continue
        if p == NEXT_REPLY:
            delta = rdelta_l[d]
            n = delta.shape[0]
            if jr[d] < n and v[d] < beta_h[d]:
                r = rby_l[d][jr[d]]
                dr = delta[r]
                rws = rrows_l[d]
                if rws[r, 0] < 0:  # the end: nothing more to do
                    if dr > v[d]:
                        v[d] = dr
                    jr[d] += 1
                    continue
                cur_r[d] = r
                phase[d] = AFTER_CHILD
                c = d + 1
                rows[c] = rws[r]
                win_a[c] = max(a_[d], v[d]) - dr
                win_b[c] = beta_h[d] - dr
                lbh[c] = rlbs_l[d][r]
                phase[c] = ENTER
                d = c
                continue
            # the human node is done: its value is v[d]
            if v[d] < best[d]:
                best[d] = v[d]
                best_i[d] = ci[d]
                if d == 0:
                    st[ROOT_BEST] = best[d]
            phase[d] = NEXT_COMMIT
            continue
        # AFTER_CHILD: the child's value came back in ret
        w = rdelta_l[d][cur_r[d]] + ret
        if w > v[d]:
            v[d] = w
        jr[d] += 1
        phase[d] = NEXT_REPLY
    return ret, moves, replies


# --------------------------------------------------------------------------- policy games


@numba.njit(cache=True)
def _choose(T, H, row, commits, kind, prefs, n_prefs, st):  # pragma: no cover - compiled
    """The commitment (index) a policy of ``kind`` takes at ``row``; -1 when stopped."""
    m = commits.shape[0]
    if kind == ROBUST:
        nw = T.side.shape[0]
        moves, replies = _new_moves(nw, 64, 256), _new_moves(nw + 1, 64, 256)
        return _robust_move(T, H, row, m, st, prefs, n_prefs, moves, replies)[0]
    if kind == HYBRID:  # the table's move of the same state at the highest budget it has
        other = row.copy()
        for b in range(budget_cap_of(T, row), -1, -1):
            other[1] = b
            i = _find(H, key_of(T, other))
            if i >= 0 and 0 <= H.move[i] < m:
                return H.move[i]
    if kind == SCHEDULE:
        return _schedule_choice(T, row, commits, prefs, n_prefs)
    best, best_i = INF, 0
    for i in range(m):
        e = _estimate(T, row, commits[i])
        if e < best:
            best, best_i = e, i
    return best_i


@numba.njit(cache=True)
def _robust_move(T, H, row, m, st, prefs, n_prefs, moves, replies):  # pragma: no cover
    """The robust policy's commitment (index, of ``m``) at ``row``, -1 when stopped: the
    table's move where it is exact, else a higher budget's that proves the floor (rule 10),
    else the search's, run to the exact value (:func:`_search_memo`, with the caller's memos
    of rule 8): ``(index, moves, replies)``."""
    key = key_of(T, row)
    i = _find(H, key)
    if i >= 0:
        _refresh(T, H, row, key, i)  # what the other budgets prove (rules 9, 10)
        if H.lo[i] == H.hi[i] and H.move[i] >= 0:
            return H.move[i], moves, replies  # exact with its move: what a search would return
        # a higher budget's move proving at most the proven floor (rule 10)
        f = _move_above(T, H, row, key, H.lo[i], m)
        if f >= 0:
            return f, moves, replies
    v, moves, replies = _search_memo(T, H, row, -1, INF, st, prefs, n_prefs, moves, replies)
    if st[ABORT]:
        return -1, moves, replies
    i = _find(H, key)
    if H.move[i] < 0:
        f = _move_above(T, H, row, key, v, m)
        if f >= 0:
            return f, moves, replies
        # exact by bounds alone (rule 3): search again for the move
        H.hi[i] = INF
        _, moves, replies = _search_memo(
            T, H, row, v - 1, v + 1, st, prefs, n_prefs, moves, replies
        )
        if st[ABORT]:
            return -1, moves, replies
    return H.move[i], moves, replies


@numba.njit(cache=True)
def _schedule_choice(T, row, commits, prefs, n_prefs):  # pragma: no cover - compiled
    """:func:`asp.concurrent.schedule_rule` on a position: each free worker wants the first
    operation of its list neither done nor running (alike ones by label); the commitment
    with every free worker as wanted, else the most, ties by order."""
    nw = T.side.shape[0]
    s = row[0]
    want = np.full(nw, NONE, np.int64)
    for w in range(nw):
        if row[2 + w] >= 0:
            continue
        want[w] = -1
        for j in range(n_prefs[w]):
            o = prefs[w, j]
            if T.chain_of[o] >= 0:
                # the list's j-th operation of its chain is done or running by count
                c = T.chain_of[o]
                rank = 0
                for p in range(T.chain_len[c]):
                    if T.chains[c, p] == o:
                        rank = p
                left = 0
                for p in range(T.chain_len[c]):
                    q = T.chains[c, p]
                    if is_done(T, s, q) or _running(row, nw, q):
                        left += 1
                if rank >= left:
                    want[w] = T.label[o]
                    break
            elif not is_done(T, s, o) and not _running(row, nw, o):
                want[w] = o
                break
    best, best_score = 0, -1
    for i in range(commits.shape[0]):
        score = 0
        exact = True
        for w in range(nw):
            if want[w] == NONE:
                continue
            got = commits[i, w]
            got = got if got < 0 else T.label[got]
            if got == want[w]:
                score += 1
            else:
                exact = False
        if exact:
            score += 1000
        if score > best_score:
            best, best_score = i, score
    return best


@numba.njit(cache=True)
def _running(row, nw, o):  # pragma: no cover - compiled
    for w in range(nw):  # noqa: SIM110 - numba has no generator expressions
        if row[2 + w] == o:
            return True
    return False


@numba.njit(cache=True)
def _node_row(row, kind, told, nw):  # pragma: no cover - compiled
    """A position as :class:`asp.concurrent.build.NodeRows` reads a node:
    ``[kind, state, budget, ops, remains, instructions]``."""
    out = np.full(3 + 3 * nw, NONE, np.int64)
    out[0] = kind
    out[1] = row[0]
    out[2] = row[1]
    for w in range(nw):
        out[3 + w] = row[2 + w]
        out[3 + nw + w] = row[2 + nw + w]
        out[3 + 2 * nw + w] = told[w]
    return out


@numba.njit(cache=True)
def _policy_game(T, H, P, starts, kind, prefs, n_prefs, st, max_nodes, memos):  # pragma: no cover
    """The policy game of ``kind`` from the rows ``starts`` (module docstring).

    Node 0 is the end; robot and human nodes alternate. Returns ``(ok, node rows, start
    nodes, edge src, dst, cost, side, ops, durations, deviations)``; ``ok`` False when
    stopped (``st[ABORT]``) or over ``max_nodes``. ``memos`` (a list of one ``(moves,
    replies)``, rule 8's memos of the caller's search) is read and left grown."""
    moves, replies = memos[0]
    nw = T.side.shape[0]
    width = 3 + 3 * nw
    nodes = np.zeros((1024, width), np.int64)
    nodes[0] = _node_row(np.full(2 + 2 * nw, -1, np.int64), 2, np.full(nw, NONE, np.int64), nw)
    n = 1
    cap_e = 1024
    e_src = np.empty(cap_e, np.int64)
    e_dst = np.empty(cap_e, np.int64)
    e_cost = np.empty(cap_e, np.int64)
    e_side = np.empty(cap_e, np.int64)
    e_dev = np.empty(cap_e, np.int64)
    e_ops = np.empty((cap_e, nw), np.int64)
    e_dur = np.empty((cap_e, nw), np.int64)
    m = 0
    stack = np.empty((64, 2 + 2 * nw), np.int64)
    top = 0
    start_ids = np.empty(starts.shape[0], np.int64)
    none = np.full(nw, NONE, np.int64)
    for b in range(starts.shape[0]):
        slot = _slot(P, key_of(T, starts[b]))
        if P.keys[slot, 0] != 0:
            start_ids[b] = P.lo[slot]
            continue
        P.keys[slot] = key_of(T, starts[b])
        P.lo[slot] = n
        if n >= nodes.shape[0]:
            nodes = grow_rows(nodes, 2 * nodes.shape[0])
        nodes[n] = _node_row(starts[b], 0, none, nw)
        start_ids[b] = n
        n += 1
        if top >= stack.shape[0]:
            stack = grow_rows(stack, 2 * stack.shape[0])
        stack[top] = starts[b]
        top += 1
    while top > 0:
        top -= 1
        row = stack[top].copy()
        v = P.lo[_slot(P, key_of(T, row))]
        commits, moves = _commits_of(T, moves, row)
        if kind == ROBUST:
            i, moves, replies = _robust_move(
                T, H, row, commits.shape[0], st, prefs, n_prefs, moves, replies
            )
        else:
            i = _choose(T, H, row, commits, kind, prefs, n_prefs, st)
        memos[0] = (moves, replies)
        if i < 0 or n + 1 >= max_nodes:
            return False, nodes[:n], start_ids, e_src[:m], e_dst[:m], e_cost[:m], e_side[:m], \
                e_ops[:m], e_dur[:m], e_dev[:m]  # fmt: skip
        commit = commits[i]
        cur, told = committed_row(T, row, commit)
        u = n
        if n >= nodes.shape[0]:
            nodes = grow_rows(nodes, 2 * nodes.shape[0])
        nodes[u] = _node_row(cur, 1, told, nw)
        n += 1
        ops, durs, dev, delta, rows = reply_rows(T, row, commit)
        need = m + 1 + delta.shape[0]
        if need > cap_e:
            while cap_e < need:
                cap_e *= 2
            e_src, e_dst, e_cost = grow(e_src, cap_e), grow(e_dst, cap_e), grow(e_cost, cap_e)
            e_side, e_dev = grow(e_side, cap_e), grow(e_dev, cap_e)
            e_ops, e_dur = grow_rows(e_ops, cap_e), grow_rows(e_dur, cap_e)
        e_src[m], e_dst[m], e_cost[m], e_side[m], e_dev[m] = v, u, 0, 0, 0
        e_ops[m] = commit
        e_dur[m] = NONE
        m += 1
        for r in range(delta.shape[0]):
            t = 0
            if rows[r, 0] >= 0:
                key = key_of(T, rows[r])
                slot = _slot(P, key)
                if P.keys[slot, 0] != 0:
                    t = P.lo[slot]
                else:
                    if n >= max_nodes:
                        return False, nodes[:n], start_ids, e_src[:m], e_dst[:m], \
                            e_cost[:m], e_side[:m], e_ops[:m], e_dur[:m], e_dev[:m]  # fmt: skip
                    P.keys[slot] = key
                    P.lo[slot] = n
                    t = n
                    if n >= nodes.shape[0]:
                        nodes = grow_rows(nodes, 2 * nodes.shape[0])
                    nodes[n] = _node_row(rows[r], 0, none, nw)
                    n += 1
                    if top >= stack.shape[0]:
                        stack = grow_rows(stack, 2 * stack.shape[0])
                    stack[top] = rows[r]
                    top += 1
            e_src[m], e_dst[m], e_cost[m], e_side[m], e_dev[m] = u, t, delta[r], 1, dev[r]
            e_ops[m] = ops[r]
            e_dur[m] = durs[r]
            m += 1
    return True, nodes[:n], start_ids, e_src[:m], e_dst[:m], e_cost[:m], e_side[:m], \
        e_ops[:m], e_dur[:m], e_dev[:m]  # fmt: skip


# --------------------------------------------------------------------------- Python side


COMPILE_NOTE_AFTER = 5.0
"""Seconds the kernels may take to load from numba's cache before :data:`COMPILE_NOTE` is
said (loading takes well under a second; compiling them, on the first run after an install
or an update of the code, minutes of CPU)."""
COMPILE_NOTE = (
    "  compiling the concurrent search's kernels (the first run after an install or an "
    "update: a few minutes of CPU, cached for the runs after it) ..."
)


def with_note(work, after: float, say) -> None:
    """Run ``work()``; if it is still running ``after`` seconds on, ``say(COMPILE_NOTE)``
    once (from a timer thread; the note never waits for ``work``)."""
    timer = threading.Timer(after, say, (COMPILE_NOTE,))
    timer.daemon = True
    timer.start()
    try:
        work()
    finally:
        timer.cancel()


def _say(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


def _compile_kernels(rules: Rules, prefs: np.ndarray, n_prefs: np.ndarray) -> None:
    """Compile (or load from numba's cache) the search and policy-game kernels for these
    argument types, so that a time limit counts search, not compilation (the first run on
    a machine compiles for minutes under load). Each kernel is called once on throwaway
    tables and counters that stop it at its first position; nothing of the search is
    touched."""
    kw = rules.key_words
    row = rules.start(0).row()
    for kernel in (_search_in, _policy_game):
        stats = np.zeros(N_STATS, dtype=np.int64)
        stats[MAX_ENTRIES], stats[NODE_LIMIT] = MIN_ENTRIES // 2, 1
        table = new_table(MIN_ENTRIES, kw)
        memos = new_memos(rules.n_workers)
        if kernel is _search_in:
            _search_in(rules.tables, table, row, -1, INF, stats, prefs, n_prefs, memos)
        else:
            starts = np.array([row], dtype=np.int64)
            other = new_table(MIN_ENTRIES, kw)
            _policy_game(
                rules.tables, table, other, starts, GREEDY, prefs, n_prefs, stats, 1, memos
            )


@numba.njit(cache=True)
def new_memos(n_workers):  # pragma: no cover - compiled
    """Free memos of rule 8 (the commitments, the human side's choices) as a list of one
    ``(moves, replies)``, which :func:`_search_in` and :func:`_policy_game` read and leave
    grown (made and read in compiled code only: a typed list's methods called from Python
    compile on every run)."""
    memos = List()
    memos.append((_new_moves(n_workers, 64, 256), _new_moves(n_workers + 1, 64, 256)))
    return memos


@numba.njit(cache=True)
def _search_in(T, H, root, alpha, beta, st, prefs, n_prefs, memos):  # pragma: no cover
    """:func:`_search_memo` with the memos of ``memos`` (:func:`new_memos`), left grown."""
    moves, replies = memos[0]
    v, moves, replies = _search_memo(T, H, root, alpha, beta, st, prefs, n_prefs, moves, replies)
    memos[0] = (moves, replies)
    return v


@dataclass
class Limits:
    """What the search may use: ``memory`` bytes (the table and the policy games; default
    :data:`DEFAULT_MEMORY`, or less when the memory available says so: the one rule,
    :func:`asp.heap.memory_budget`), ``max_nodes`` positions expanded, ``time_limit``
    search seconds (None: no limit): :data:`POSITIONS_PER_SECOND` positions each, the wall
    clock a safety net at :func:`asp.schedule.cpsat.wall_safety` of it."""

    memory: int = field(default_factory=lambda: memory_budget(DEFAULT_MEMORY))
    max_nodes: int = DEFAULT_MAX_NODES
    time_limit: float | None = None


class Search:
    """One search over a game's positions: the table, the counters, the limits.

    Its table is shared by every budget and by the policy games built from it (the robust
    policy's exact values, the hybrid policy's moves).
    """

    def __init__(
        self,
        rules: Rules,
        limits: Limits | None = None,
        *,
        progress: bool = False,
        schedule: list[dict] | None = None,
    ):
        self.rules = rules
        self.limits = limits or Limits()
        # The CP-SAT schedule's lists, the search's first guess where the table has none.
        self.prefs, self.n_prefs = schedule_lists(rules, schedule or [])
        kw = rules.key_words
        # Half the memory for the search table, the rest for the policy games' tables
        # and node arrays.
        self.entries = table_entries(self.limits.memory // 2, kw)
        if self.entries < MIN_ENTRIES:
            from asp.errors import GameError

            need = 2 * MIN_ENTRIES * (8 * kw + ENTRY_BYTES) / LOAD
            raise GameError(
                f"--max-memory: {self.limits.memory:,} bytes is too little for the concurrent "
                f"search (at least {need:,.0f} bytes)"
            )
        self.table = new_table(min(self.entries, FIRST_ENTRIES), kw)
        # rule 8's memos, kept from one search call to the next (they depend on the rules
        # alone; at most one entry per position or human node expanded)
        self.memos = new_memos(rules.n_workers)
        self.stats = np.zeros(N_STATS, dtype=np.int64)
        self.stats[MAX_ENTRIES] = min(self.entries, int(self.table.keys.shape[0] * LOAD))
        limit = self.limits.time_limit
        # positions expanded the search seconds allow in all (None: no time limit)
        self.budget = None if limit is None else work_positions(limit)
        self.valued = 0  # positions the certificates valued (best_response_values)
        self.net: float | None = None  # the wall-clock safety net of the phase, seconds
        self.wall_stop: float | None = None  # the net that stopped a phase, when one did
        self.stats[NODE_LIMIT] = self._cap(self.budget)
        self.stats[PROGRESS] = int(progress)
        # before the clock starts; a first run's compile is said when progress is shown
        compile_kernels = functools.partial(_compile_kernels, rules, self.prefs, self.n_prefs)
        if progress:
            with_note(compile_kernels, COMPILE_NOTE_AFTER, _say)
        else:
            compile_kernels()
        self.t0 = time.perf_counter()
        self.stats[T0] = int(self.t0 * 1000)
        if limit is not None:
            self.safety_net(limit)

    def _cap(self, nodes: int | None) -> int:
        return self.limits.max_nodes if nodes is None else min(self.limits.max_nodes, nodes)

    def safety_net(self, seconds: float) -> None:
        """The wall clock stops what follows at :func:`asp.schedule.cpsat.wall_safety` of
        ``seconds`` search seconds from now (a stop already made by it is lifted)."""
        self.net = wall_safety(seconds)
        self.stats[DEADLINE] = int((time.perf_counter() + self.net) * 1000)
        if self.stats[ABORT] == STOP_TIME:
            self.stats[ABORT] = 0

    def note_wall(self, net: float | None = None) -> None:
        """Record a stop by the wall clock's safety net (``net``: its seconds, default the
        search's), the first one."""
        if self.wall_stop is None:
            self.wall_stop = round(self.net if net is None else net, 3)

    @property
    def stopped(self) -> str | None:
        """Why the search stopped (``"node limit"``, ``"memory limit"``, ``"time limit"``:
        its search seconds, ``"wall-clock limit"``: the safety net), or None."""
        why = int(self.stats[ABORT])
        if why == STOP_NODES and self.nodes < self.limits.max_nodes:
            return "time limit"  # the budget of search seconds, or the share of a phase
        return STOP_NAMES.get(why)

    @property
    def nodes(self) -> int:
        return int(self.stats[NODES])

    @property
    def positions(self) -> int:
        return int(self.stats[ENTRIES])

    def _grow(self) -> bool:
        """When the table is full below the memory allowed: a table four times larger with
        every entry; False (the memory limit stands) otherwise."""
        st = self.stats
        if st[ABORT] != STOP_MEMORY or st[MAX_ENTRIES] >= self.entries:
            return False
        bigger = new_table(min(self.entries, 4 * int(st[MAX_ENTRIES])), self.rules.key_words)
        _rehash(self.table, bigger)
        self.table = bigger
        st[MAX_ENTRIES] = min(self.entries, int(bigger.keys.shape[0] * LOAD))
        st[ABORT] = 0
        return True

    def resume(self, nodes: int | None) -> None:
        """Search on after a stop at its budget of search seconds (or a phase's share of
        it), until ``nodes`` positions expanded in all (None: ``max_nodes`` alone). The
        table holds proven intervals only, so what the stopped search found stays valid. A
        stop by the wall clock's safety net stands (:meth:`safety_net` lifts it)."""
        if self.stats[ABORT] == STOP_NODES and self.nodes < self.limits.max_nodes:
            self.stats[ABORT] = 0
        self.stats[NODE_LIMIT] = self._cap(nodes)

    def _run(self, row, alpha: int, beta: int) -> int:
        """:func:`_search_memo` of ``row``, again with a larger table while it grows (the entries
        kept, so the search goes on where it stopped)."""
        t = self.rules.tables
        while True:
            v = _search_in(
                t, self.table, row, alpha, beta, self.stats, self.prefs, self.n_prefs, self.memos
            )
            if not self._grow():
                self._noted()
                return int(v)

    def _noted(self) -> None:
        if self.stats[ABORT] == STOP_TIME:
            self.note_wall()

    def value(self, budget: int | None, floor: int = 0, upper: int = INF) -> int | None:
        """``W*(budget)`` (scaled) where the caller has proved ``floor <= W* < upper``; None
        when a limit stopped it.

        Searched in the window ``(floor, upper)`` (rule 7): a result ``v <= floor`` proves
        ``W* <= v``, so ``W* = floor``; one inside the window is exact."""
        if self.stopped:
            return None
        row = self.rules.start(budget).row()
        self.stats[BUDGET] = row[1]
        self.stats[ROOT_BEST] = INF
        v = self._run(row, floor, upper)
        if self.stopped:
            return None
        if v <= floor:
            return int(floor)
        if v >= upper:  # the upper bound was wrong: search it again in full
            v = self._run(row, -1, INF)
            if self.stopped:
                return None
        return v

    def value_at(self, pos) -> int | None:
        """The exact value (scaled) of any position (:class:`asp.concurrent.rules.Position`),
        None when a limit stopped the search."""
        if self.rules.is_end(pos):
            return 0
        v = self._run(pos.row(), -1, INF)
        return None if self.stopped else v

    def proven(self, budget: int | None) -> tuple[int, int]:
        """The interval the table proves for the start of ``budget`` (scaled)."""
        row = self.rules.start(budget).row()
        i = _find(self.table, key_of(self.rules.tables, row))
        if i < 0:
            return int(lower_bound_of(self.rules.tables, row)), INF
        return int(self.table.lo[i]), int(self.table.hi[i])

    def interval(self, pos) -> tuple[int, int]:
        """The interval (scaled) the table proves for a position
        (:class:`asp.concurrent.rules.Position`), or, for one it does not hold, the interval
        a new entry would start with (rules 2, 3 and 9): ``lo <= W <= hi``."""
        if self.rules.is_end(pos):
            return 0, 0
        t = self.rules.tables
        row = pos.row()
        key = key_of(t, row)
        i = _find(self.table, key)
        if i >= 0:
            return int(self.table.lo[i]), int(self.table.hi[i])
        lo, hi, _ = _new_bounds(t, self.table, row, key, -1)
        return int(lo), int(hi)

    def policy_game(
        self, budgets: list[int | None], kind: int, schedule: list[dict] | None = None
    ) -> ConcurrentGame | None:
        """The policy game of ``kind`` with a start per budget (None: ``k = inf``), or None
        when a limit stopped it (module docstring)."""
        rules = self.rules
        t0 = time.perf_counter()
        starts = np.array([rules.start(b).row() for b in budgets], dtype=np.int64)
        prefs, n_prefs = (
            (self.prefs, self.n_prefs) if not schedule else schedule_lists(rules, schedule)
        )
        nw = rules.n_workers
        kw = rules.key_words
        # Bytes per policy-game node: its row, its table slot, and about two edges.
        per_node = 8 * (3 + 3 * nw) + (8 * kw + ENTRY_BYTES) / LOAD + 2 * 8 * (5 + 2 * nw)
        most = max(1024, int((self.limits.memory // 2) / per_node))
        room = min(most, max(FIRST_ENTRIES, self.positions))
        while True:  # a table for ``room`` nodes, four times larger while it is over
            table = new_table(room, kw)
            out = _policy_game(
                rules.tables, self.table, table, starts, kind, prefs, n_prefs, self.stats, room,
                self.memos,
            )  # fmt: skip
            if out[0]:
                break
            if self._grow():
                continue
            self._noted()
            if self.stats[ABORT] or room >= most:
                return None
            room = min(most, 4 * room)
        ok, rows, start_ids, src, dst, cost, side, e_ops, e_dur, e_dev = out
        edges = (src, dst, cost, side, e_ops, e_dur, e_dev)
        return _as_game(rules, budgets, rows, start_ids, edges, t0)


def work_positions(seconds: float) -> int:
    """Positions ``seconds`` search seconds stand for (:data:`POSITIONS_PER_SECOND`; at
    least one)."""
    return max(1, int(round(float(seconds) * POSITIONS_PER_SECOND)))


def schedule_lists(rules: Rules, rows: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    """Each worker's operations of a CP-SAT schedule in start order, alike operations named
    by the rank of their start within their chain (:func:`_schedule_choice`)."""
    model = rules.model
    ids = {oid: i for i, oid in enumerate(model.spec.op_ids)}
    names = {w.name: k for k, w in enumerate(model.workers)}
    by_agent = {}
    for k, w in enumerate(model.workers):
        by_agent.setdefault(w.agent, []).append(k)
    lists: list[list[int]] = [[] for _ in model.workers]
    started: dict[int, int] = {}
    t = rules.tables
    for row in sorted(rows, key=lambda r: (float(r["start"]), str(r["task"]))):
        o = ids[str(row["task"])]
        c = int(t.chain_of[o])
        if c >= 0:
            rank = started.get(c, 0)
            started[c] = rank + 1
            o = int(t.chains[c, rank])
        agent = str(row["agent"])
        k = names.get(agent)
        if k is None:  # an agent of side "any": the worker of the side that may do it
            k = next((j for j in by_agent.get(agent, []) if t.ndur[j, o]), 0)
        lists[k].append(o)
    width = max((len(x) for x in lists), default=1)
    prefs = np.zeros((len(lists), max(1, width)), dtype=np.int64)
    n_prefs = np.array([len(x) for x in lists], dtype=np.int64)
    for k, x in enumerate(lists):
        prefs[k, : len(x)] = x
    return prefs, n_prefs


def _as_game(rules, budgets, rows, start_ids, edges, t0):
    """A policy game's arrays as a :class:`asp.concurrent.build.ConcurrentGame`."""
    model = rules.model
    src, dst, cost, side, e_ops, e_dur, e_dev = edges
    order = np.argsort(src, kind="stable")
    src, dst, cost, side = src[order], dst[order], cost[order], side[order]
    nodes = NodeRows(rows.astype(np.int64), model.humans)
    actions = ActionRows(side.astype(np.int8), e_ops[order], e_dur[order], e_dev[order], cost)
    levels = [UNBOUNDED if b is None else int(b) for b in budgets]
    starts = {b: int(start_ids[i]) for i, b in enumerate(levels)}
    edges = (src, dst, cost, side)
    return game_of(model, levels, nodes, actions, starts, 0, edges, t0, GENERATOR)


# Public names for the certificate of any robot policy (asp.concurrent.certify).
node_row = _node_row
as_policy_game = _as_game
commit_bound = _estimate
policy_choice = _choose
table_find = _find
table_slot = _slot
table_rehash = _rehash
