"""The certified worst case of any robot policy on the concurrent game (:func:`certify`).

A robot policy is a function ``choose(position, commits) -> index``: at a position of
:class:`asp.concurrent.rules.Rules` (the robot side on turn) it picks one of the
commitments :meth:`~asp.concurrent.rules.Rules.commits` lists. Fixing it leaves a one-player
game for the human side, much smaller than the concurrent game: from the start positions,
the robot's single commitment at each position and *every* reply of the human side to it.
That *policy game* is walked here from the rules, with the same node and edge layout as the
policy games of :mod:`asp.concurrent.search` (so it is an ordinary
:class:`asp.concurrent.build.ConcurrentGame`), and solved exactly by :func:`asp.game.solve.solve`:
the value at a start is the exact best response of the human side to the policy, the
policy's *certified worst case* for that budget.

Exactness: every human reply is a branch of the walk (the rules give each reply that leads
to a distinct position or cost), the robot side has one move per position, so the solved
value at a robot node is the maximum over the human side's strategies of the makespan
against the policy, i.e. the certified worst case. Positions are the rules' canonical
positions (budgets that no longer bind capped, alike operations identified), so a policy
is a function of the canonical position; a budget ``None`` (``k = inf``) is the start at
the budget cap. When ``choose`` does not look at :attr:`Position.budget`, a human allowed
``k + 1`` deviations can play every strategy of ``k`` against the same moves, so the
certified worst case never falls as ``k`` grows.

The walk is plain Python over the compiled move generators (:func:`commit_rows`,
:func:`reply_rows`): ``choose`` may be anything, a learned network included.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from dataclasses import dataclass

import numba
import numpy as np
from numba.typed import List

from asp.concurrent.build import Commit, ConcurrentGame
from asp.concurrent.model import UNBOUNDED
from asp.concurrent.rules import (
    NONE,
    Position,
    Rules,
    commit_rows,
    committed_row,
    key_of,
    reply_rows,
)
from asp.concurrent.search import (  # the search's compiled policies and table
    ABORT,
    as_policy_game,
    node_row,
    policy_choice,
    table_find,
    table_rehash,
    table_slot,
)

Choose = Callable[[Position, list[Commit]], int]
"""A robot policy: the index of the commitment it takes at a position."""

DEFAULT_MAX_NODES = 2_000_000
"""Nodes of a policy game above which :func:`certify` stops with a ``GameLimit``."""


@dataclass(frozen=True, eq=False)
class Certificate:
    """The certified worst case of a robot policy, per budget.

    Attributes
    ----------
    worst : dict
        Budget (``None``: ``k = inf``) -> the policy's exact worst-case makespan (spec units).
    game : asp.concurrent.build.ConcurrentGame
        The policy game (one start per budget); ``solution`` its exact solution: each
        robot node's value is the policy's worst case from there.
    solution : asp.game.solve.Solution
    seconds : float
    """

    worst: dict
    game: ConcurrentGame
    solution: object
    seconds: float

    @property
    def nodes(self) -> int:
        return self.game.dag.n_nodes

    def to_list(self) -> list[dict]:
        """``[{"k": 0, "bound": ...}, ..., {"k": None, "bound": ...}]`` (budgets in order,
        ``None`` last)."""
        ks = sorted(self.worst, key=lambda b: (b is None, b or 0))
        return [{"k": b, "bound": self.worst[b]} for b in ks]


def as_commits(rows: np.ndarray) -> list[Commit]:
    """The :class:`Commit` of each row of :func:`commit_rows` (None for a busy worker)."""
    return [Commit(ops=tuple(None if o == NONE else int(o) for o in row)) for row in rows]


def certify(
    rules: Rules,
    choose: Choose,
    budgets: list[int | None],
    *,
    max_nodes: int = DEFAULT_MAX_NODES,
    max_memory: int | None = None,
) -> Certificate:
    """The exact best response of the human side to the robot policy ``choose``.

    The policy game's memory is bounded like every compiled game's
    (:func:`asp.concurrent.build.game_bytes` of the Python builder, the nodes and edges
    walked so far), checked before each node is added: past ``max_memory`` the walk stops
    with one line naming ``--max-memory``, the estimate and the memory available.

    Parameters
    ----------
    rules : asp.concurrent.rules.Rules
    choose : callable ``(Position, list of Commit) -> int``
        The robot policy (module docstring).
    budgets : list of int or None
        The deviation budgets to certify (``None``: the fully adversarial human).
    max_nodes : int
        The policy game's largest size.
    max_memory : int, optional
        Bytes the policy game may use (default
        :func:`asp.concurrent.build.default_memory`: :func:`asp.heap.memory_budget`, the one
        rule).

    Raises
    ------
    asp.errors.GameError
        ``choose`` gave no valid index, or a negative budget.
    asp.errors.GameLimit
        The policy game has more than ``max_nodes`` nodes, or its estimate passes
        ``max_memory`` bytes.
    """
    from asp.concurrent.build import default_memory, game_bytes, memory_limit_error
    from asp.errors import GameError, GameLimit
    from asp.game.solve import solve

    limit = default_memory() if max_memory is None else int(max_memory)
    where = rules.model.spec.source or rules.model.spec.name
    t0 = time.perf_counter()
    T = rules.tables
    nw = rules.n_workers
    none = np.full(nw, NONE, dtype=np.int64)
    end = np.full(2 + 2 * nw, -1, dtype=np.int64)
    nodes = [node_row(end, 2, none, nw)]
    index: dict[bytes, int] = {}
    stack: list[np.ndarray] = []
    src, dst, cost, side, e_ops, e_dur, e_dev = [], [], [], [], [], [], []

    def node_of(row: np.ndarray) -> int:
        key = key_of(T, row).tobytes()
        v = index.get(key)
        if v is None:
            if len(nodes) >= max_nodes:
                raise GameLimit(f"{where}: the policy game exceeds {max_nodes:,} nodes")
            if game_bytes(len(nodes) + 2, len(src), compiled=False) > limit:
                raise memory_limit_error(
                    where,
                    (0, len(nodes), len(src)),
                    limit,
                    compiled=False,
                    what="the policy game of the robot policy (its exact best response)",
                    advice="raise --max-memory",
                )
            v = index[key] = len(nodes)
            nodes.append(node_row(row, 0, none, nw))
            stack.append(row)
        return v

    def add_edge(a, b, c, s, ops, durs, dev):
        src.append(a)
        dst.append(b)
        cost.append(c)
        side.append(s)
        e_ops.append(ops)
        e_dur.append(durs)
        e_dev.append(dev)

    start_ids = np.array([node_of(rules.start(b).row()) for b in budgets], dtype=np.int64)
    while stack:
        row = stack.pop()
        v = index[key_of(T, row).tobytes()]
        commits = commit_rows(T, row)
        i = choose(Position.of_row(row), as_commits(commits))
        if not 0 <= int(i) < commits.shape[0]:
            raise GameError(
                f"robot policy: expected a commitment index in 0..{commits.shape[0] - 1} at "
                f"{Position.of_row(row)}, got {i}"
            )
        commit = commits[int(i)]
        cur, told = committed_row(T, row, commit)
        u = len(nodes)
        nodes.append(node_row(cur, 1, told, nw))
        add_edge(v, u, 0, 0, commit, none, 0)
        ops, durs, dev, delta, rws = reply_rows(T, row, commit)
        for r in range(delta.shape[0]):
            t = 0 if rws[r, 0] < 0 else node_of(rws[r])
            add_edge(u, t, int(delta[r]), 1, ops[r], durs[r], int(dev[r]))
    edges = (
        np.array(src, dtype=np.int64),
        np.array(dst, dtype=np.int64),
        np.array(cost, dtype=np.int64),
        np.array(side, dtype=np.int64),
        np.array(e_ops, dtype=np.int64).reshape(-1, nw),
        np.array(e_dur, dtype=np.int64).reshape(-1, nw),
        np.array(e_dev, dtype=np.int64),
    )
    rows = np.array(nodes, dtype=np.int64)
    game = as_policy_game(rules, budgets, rows, start_ids, edges, t0)
    solution = solve(game.dag)
    worst = {
        (None if b == UNBOUNDED else b): float(solution.value[s, 0]) for b, s in game.starts.items()
    }
    return Certificate(worst=worst, game=game, solution=solution, seconds=time.perf_counter() - t0)


# --------------------------------------------------------------------------- values only

FIRST_POSITIONS = 1 << 16
"""Positions the memo of :func:`best_response_values` holds at first (it grows four-fold)."""
TICK_MASK = (1 << 15) - 1
"""The clock is looked at every ``TICK_MASK + 1`` positions valued."""
OK, FULL, STOPPED = 0, 1, 2
"""What :func:`_values` ended with: every start valued, the memo full, a limit reached."""
ENTRIES, CAPACITY, VALUED, DEADLINE_MS, PROGRESS_MS, T0_MS, MAX_VALUED, WALL = range(8)
"""The counters of :func:`_values` (an int64 array): positions in the memo, the most it
may hold, positions valued in all, the wall clock's safety net (ms of
``time.perf_counter``, 0: none), the next progress line (0: none), the start, the positions
the search seconds allow (0: no limit), and 1 once the safety net stopped it."""


@numba.njit(cache=True)
def _values(T, H, P, starts, kind, prefs, n_prefs, st, cnt, out):  # pragma: no cover
    """The exact best response of the human side to the fixed policy ``kind`` from each row
    of ``starts`` (scaled makespans into ``out``), values only (:func:`best_response_values`).

    Depth-first over positions with an explicit stack (as :mod:`asp.concurrent.search`'s search:
    numba caches no recursive function); a position's value, the max over the replies to
    the policy's one commitment of the reply's cost plus the value after it, is memoised in
    ``P`` (``P.lo``) once all its replies are valued, and nothing else is kept. The game is
    a DAG (every event completes an operation), so no position is met again below itself.
    Returns :data:`OK`, :data:`FULL` (``P`` holds ``cnt[CAPACITY]`` positions: what is
    memoised stays valid, call again with a larger ``P``) or :data:`STOPPED` (the deadline,
    or the policy stopped: ``st[ABORT]``)."""
    width = starts.shape[1]
    D = T.label.shape[0] + 3
    rows = np.empty((D, width), np.int64)
    jr = np.zeros(D, np.int64)
    v = np.zeros(D, np.int64)
    rrows_l = List()
    rdelta_l = List()
    for _ in range(D):  # (made as the rules' kernels make them: the same array types)
        rrows_l.append(np.empty((1, width), np.int64)[:0])
        rdelta_l.append(np.empty((1, 2), np.int64)[:0, 1])
    for b in range(starts.shape[0]):
        if starts[b, 0] < 0:
            out[b] = 0
            continue
        j = table_find(P, key_of(T, starts[b]))
        if j >= 0:
            out[b] = P.lo[j]
            continue
        d = 0
        rows[0] = starts[b]
        enter = True
        while d >= 0:
            if enter:  # the policy's commitment and every reply to it
                enter = False
                commits = commit_rows(T, rows[d])
                i = policy_choice(T, H, rows[d], commits, kind, prefs, n_prefs, st)
                if i < 0 or st[ABORT]:
                    return STOPPED
                _, _, _, delta, rws = reply_rows(T, rows[d], commits[i])
                rrows_l[d] = rws
                rdelta_l[d] = delta
                jr[d] = 0
                v[d] = 0 if delta.shape[0] == 0 else -1
                cnt[VALUED] += 1
                if cnt[MAX_VALUED] > 0 and cnt[VALUED] > cnt[MAX_VALUED]:
                    return STOPPED
                if (cnt[VALUED] & TICK_MASK) == 0 and (cnt[DEADLINE_MS] or cnt[PROGRESS_MS]):
                    with numba.objmode(now="float64"):
                        now = time.perf_counter()
                    ms = np.int64(now * 1000)
                    if cnt[DEADLINE_MS] > 0 and ms >= cnt[DEADLINE_MS]:
                        cnt[WALL] = 1
                        return STOPPED
                    if cnt[PROGRESS_MS] > 0 and ms >= cnt[PROGRESS_MS]:
                        cnt[PROGRESS_MS] = ms + 5000
                        valued, entries, secs = cnt[VALUED], cnt[ENTRIES], (ms - cnt[T0_MS]) / 1000
                        with numba.objmode():
                            _report(kind, valued, entries, secs)
            delta = rdelta_l[d]
            rws = rrows_l[d]
            pushed = False
            while jr[d] < delta.shape[0]:
                r = jr[d]
                if rws[r, 0] < 0:  # the end
                    val = delta[r]
                else:
                    j = table_find(P, key_of(T, rws[r]))
                    if j < 0:  # not valued yet: below it first, this reply again after
                        rows[d + 1] = rws[r]
                        d += 1
                        enter = True
                        pushed = True
                        break
                    val = delta[r] + P.lo[j]
                if val > v[d]:
                    v[d] = val
                jr[d] += 1
            if pushed:
                continue
            if cnt[ENTRIES] >= cnt[CAPACITY]:
                return FULL
            key = key_of(T, rows[d])
            s = table_slot(P, key)
            P.keys[s] = key
            P.lo[s] = v[d]
            cnt[ENTRIES] += 1
            d -= 1
        out[b] = P.lo[table_find(P, key_of(T, starts[b]))]
    return OK


def _report(kind: int, valued: int, entries: int, secs: float) -> None:
    from asp.concurrent.search import GREEDY, HYBRID, SCHEDULE

    name = {GREEDY: "greedy", HYBRID: "hybrid", SCHEDULE: "schedule"}.get(kind, str(kind))
    print(
        f"  certifying the {name} policy: {valued:,} positions valued, {entries:,} kept "
        f"({secs:.0f} s)",
        file=sys.stderr,
        flush=True,
    )


def best_response_values(
    search,
    kind: int,
    budgets: list[int | None],
    *,
    schedule: list[dict] | None = None,
    memory: int | None = None,
    time_limit: float | None = None,
    progress: bool = False,
) -> dict | None:
    """The certified worst case of a fixed robot policy per budget, without its policy game.

    The exact best response of the human side (module docstring), as :func:`certify` and
    the policy games of :class:`asp.concurrent.search.Search` give it, but only values are
    kept: each position the policy reaches is memoised with its value (its key and one
    integer; the policy game's nodes, edges and solution are never stored), so a policy
    whose game is over the memory allowed is still certified. Exactness: the value of a
    position is the max over the human side's replies to the policy's commitment of the
    reply's cost plus the value after it, which is what :func:`asp.game.solve.solve` computes
    on the policy game at its robot node; positions are the same canonical keys.

    Parameters
    ----------
    search : asp.concurrent.search.Search
        Its rules, its table (the hybrid policy's moves) and its CP-SAT lists.
    kind : int
        :data:`~asp.concurrent.search.GREEDY`, :data:`~asp.concurrent.search.SCHEDULE` or
        :data:`~asp.concurrent.search.HYBRID` (policies that choose by the state alone).
    budgets : list of int or None
        The budgets to certify (``None``: ``k = inf``), all in one memo.
    schedule : list of dict, optional
        The CP-SAT rows for ``SCHEDULE`` (default: the search's).
    memory : int, optional
        Bytes of the memo at most (default: half the search's memory limit).
    time_limit : float, optional
        Search seconds at most: positions valued, at
        :data:`asp.concurrent.search.POSITIONS_PER_SECOND` a second (the same answer at any
        load); the wall clock stops it only as a safety net
        (:func:`asp.schedule.cpsat.wall_safety`), recorded by ``search.note_wall``.
    progress : bool
        A line on stderr every 5 s (positions valued and kept).

    Returns
    -------
    dict or None
        Budget -> the policy's worst-case makespan (spec units); None when the memory or
        the time ran out first. The positions valued are added to ``search.valued``.
    """
    from asp.concurrent.search import LOAD, new_table, schedule_lists, work_positions
    from asp.schedule.cpsat import wall_safety

    t0 = time.perf_counter()
    rules = search.rules
    kw = rules.key_words
    starts = np.array([rules.start(b).row() for b in budgets], dtype=np.int64)
    prefs, n_prefs = (
        (search.prefs, search.n_prefs) if not schedule else schedule_lists(rules, schedule)
    )
    memory = search.limits.memory // 2 if memory is None else int(memory)
    most = int(memory // ((8 * kw + 8) / LOAD))  # only the keys and values are resident
    cnt = np.zeros(8, dtype=np.int64)
    if time_limit is not None:
        cnt[MAX_VALUED] = work_positions(time_limit)
        cnt[DEADLINE_MS] = int((t0 + wall_safety(time_limit)) * 1000)
    cnt[T0_MS] = int(t0 * 1000)
    if progress:
        cnt[PROGRESS_MS] = cnt[T0_MS] + 5000
    st = search.stats.copy()
    st[0:3] = 0  # NODES, NODE_LIMIT, ABORT of the search: the policies never search
    out = np.zeros(len(budgets), dtype=np.int64)
    size = min(most, FIRST_POSITIONS)
    if size < 16:
        return None
    memo = new_table(size, kw)
    while True:
        cnt[CAPACITY] = min(size, int(memo.keys.shape[0] * LOAD))
        status = _values(
            rules.tables, search.table, memo, starts, kind, prefs, n_prefs, st, cnt, out
        )
        if status != FULL or size >= most:
            search.valued += int(cnt[VALUED])
            if cnt[WALL]:
                search.note_wall(wall_safety(time_limit))
        if status == OK:
            break
        if status == STOPPED or size >= most:
            return None
        size = min(most, 4 * size)
        bigger = new_table(size, kw)
        table_rehash(memo, bigger)
        memo = bigger
    return {(None if b is None else b): float(out[i]) / rules.scale for i, b in enumerate(budgets)}
