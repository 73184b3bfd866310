"""The concurrent game built as a game DAG (:func:`build_game`).

Compilation (the game the existing solver plays): every game state becomes a *robot node*
(the robot side on turn) and every robot commitment a *human node*; a robot edge (cost 0)
is a commitment, a human edge is the human side's reply followed by the wait for the next
event, and costs the time until that event. Robot and human nodes alternate strictly, each
node has moves only for its side, so the alternating turn rules of :mod:`asp.game.solve` (robot
first, the turn flips every move) play exactly this game, and the makespan is the sum of
the edge costs. One DAG holds every budget ``0..K`` (a state's budget is part of it), with
one start node per budget: ``W*(k)`` is the value at start ``k``. The unbounded adversary
is its own DAG (no instructions).
"""

from __future__ import annotations

import functools
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from asp.concurrent.model import UNBOUNDED, WAIT, ConcurrentModel
from asp.errors import GameError, GameLimit
from asp.game.dag import HUMAN, ROBOT, GameDAG, from_arrays
from asp.game.turns import CONCURRENT
from asp.heap import available_memory, memory_budget

DEFAULT_MAX_NODES = 3_000_000
"""Above this many game nodes the build stops with a ``ValueError``."""
NODE_BYTES, EDGE_BYTES = 200, 110
"""Peak bytes of the compiled build per game node and per edge, the DAG made from it
included (measured on ``examples/vacuum_pump_ranges``: 3.1 M edges and 180 k nodes peaked
at 0.32 GB over the interpreter, 103 bytes per edge, nodes included)."""
PY_NODE_BYTES, PY_EDGE_BYTES = 1000, 400
"""The same for the Python builder (tuples in a dict, one dataclass per edge)."""
DEFAULT_MEMORY = 2 << 30
"""The default memory limit of a build: :data:`DEFAULT_MEMORY` bytes (2 GiB), or less when
the memory available says so (:func:`default_memory`)."""


def default_memory() -> int:
    """The default memory limit of a build, in bytes (:func:`asp.heap.memory_budget` of
    :data:`DEFAULT_MEMORY`)."""
    return memory_budget(DEFAULT_MEMORY)


def game_bytes(n_nodes: int, n_edges: int, *, compiled: bool = True) -> int:
    """The estimated peak bytes of building a game of ``n_nodes`` nodes and ``n_edges``
    edges (:data:`NODE_BYTES`, :data:`EDGE_BYTES`; the Python builder's when not
    ``compiled``)."""
    if compiled:
        return int(n_nodes) * NODE_BYTES + int(n_edges) * EDGE_BYTES
    return int(n_nodes) * PY_NODE_BYTES + int(n_edges) * PY_EDGE_BYTES


BUILD_ADVICE = (
    "coarsen the human duration grid (--duration-step), bound the deviation budget "
    "(--max-k), or raise --max-memory"
)
"""What makes a compiled concurrent game smaller or its limit larger (:func:`build_game`)."""


def memory_limit_error(
    where: str,
    counts: tuple,
    limit: int,
    *,
    compiled: bool = True,
    what: str = "the concurrent game",
    advice: str = BUILD_ADVICE,
):
    """The :class:`asp.errors.GameLimit` of a build stopped at ``limit`` bytes: what it had
    built (``counts``: nodes expanded, nodes, edges) and its estimate (:func:`game_bytes`,
    a lower bound of the whole game's: the build was still growing), the limit and the
    memory available, and the flags that make the game smaller or the limit larger
    (``advice``; ``what``: the game built, e.g. a policy game,
    :func:`asp.concurrent.certify.certify`)."""
    _, nodes, edges = (int(x) for x in counts)
    now = game_bytes(nodes, edges, compiled=compiled)
    gb = 2**30
    free = available_memory() / gb
    return GameLimit(
        f"{where}: {what} needs more than {now / gb:.2f} GB (estimated from the "
        f"{nodes:,} nodes and {edges:,} edges built when it passed the limit), over the "
        f"--max-memory limit of {limit / gb:.2f} GB ({free:.1f} GB available); {advice}"
    )


@dataclass(frozen=True)
class Commit:
    """A robot edge: the operation each worker starts (robots) or is told to do (humans).

    ``ops[w]`` is an operation index, :data:`WAIT`, or ``None`` (busy worker, or a human
    without instruction under the unbounded budget).
    """

    ops: tuple


@dataclass(frozen=True)
class Reply:
    """A human edge: the operation and duration (scaled) each free human starts, the
    deviations it costs, and the time until the next event (scaled)."""

    ops: tuple
    durations: tuple
    deviations: int
    delta: int


@dataclass(frozen=True, eq=False)
class ConcurrentGame:
    """The concurrent game compiled into a :class:`GameDAG` (module docstring).

    Attributes
    ----------
    model : ConcurrentModel
    dag : GameDAG
        Robot and human nodes alternate; costs are in the spec's time unit.
    budgets : tuple of int
        The deviation budgets with a start node (:data:`UNBOUNDED` alone for the unbounded
        game).
    starts : dict budget -> node index
    nodes : list of tuple
        Per node: ``(kind, state, running, budget, instructions)``; ``kind`` is ``"R"``,
        ``"H"`` or ``"E"`` (the end); ``running`` per worker ``(op, remaining)`` or
        ``(WAIT, 0)``.
    actions : list of Commit or Reply
        Per edge.
    seconds : float
        Build time.
    """

    model: ConcurrentModel
    dag: GameDAG
    budgets: tuple[int, ...]
    starts: dict
    nodes: list
    actions: list
    seconds: float

    @property
    def unbounded(self) -> bool:
        return self.budgets == (UNBOUNDED,)


LABEL_LIMIT = 200_000
"""Above this many edges the DAG's edge labels are left out (the actions hold the moves)."""


def build_game(
    model: ConcurrentModel,
    budgets: int | None | list,
    *,
    max_nodes: int = DEFAULT_MAX_NODES,
    progress: bool = False,
    compiled: bool | None = None,
    max_memory: int | None = None,
) -> ConcurrentGame:
    """Build the concurrent game for the budgets ``0..K`` (``budgets=K``) or unbounded (``None``).

    Parameters
    ----------
    max_memory : int, optional
        Bytes the build may use (:func:`game_bytes` of what it has built, checked at every
        node and edge); default :func:`default_memory` (2 GiB at most).
    compiled : bool, optional
        Use the numba builder (:mod:`asp.concurrent.kernel`); default whenever its packed
        state key fits. ``False``: the Python builder (the same game, slower).

    Raises
    ------
    ValueError
        A negative budget, or more than ``max_nodes`` nodes (the message names ``--max-k``).
    asp.errors.GameLimit
        Over ``max_nodes`` nodes, or over ``max_memory`` bytes (the message gives the
        estimate of the whole game, the limit and the memory available, and names the flags).
    """
    from asp.concurrent import kernel

    t0 = time.perf_counter()
    where = model.spec.source or model.spec.name
    if budgets is None:
        levels = [UNBOUNDED]
    else:
        k = int(budgets)
        if k < 0:
            raise GameError(f"k: expected a deviation budget >= 0, got {k}")
        levels = list(range(k + 1))
    too_big = GameLimit(
        f"{where}: the concurrent game exceeds {max_nodes:,} nodes (budgets "
        f"{'inf' if levels == [UNBOUNDED] else f'{levels[0]}..{levels[-1]}'}); bound the "
        "deviation budget with --max-k, coarsen the human duration grid (--duration-step), "
        "or add precedences"
    )
    longest = max(
        (d + int(model.succ_change_max) for row in model.choices for c in row for d in c),
        default=0,
    )
    limit = default_memory() if max_memory is None else int(max_memory)
    fits = kernel.fits(len(model.workers), model.n_ops, longest, model.graph.n_states, levels[-1])
    if compiled is None:
        compiled = fits
    if compiled:
        if not fits:
            raise GameError(f"{where}: the compiled builder's packed state key does not fit")
        arrays = model.kernel_arrays()
        out = kernel.build_kernel(
            *arrays,
            np.array(levels, dtype=np.int64),
            int(max_nodes),
            int(limit),
            NODE_BYTES,
            EDGE_BYTES,
        )
        overflow, counts, rows, starts_a, src, dst, cost, side, e_ops, e_dur, e_dev = out
        if overflow == kernel.OVER_MEMORY:
            raise memory_limit_error(where, tuple(counts), limit)
        if overflow:
            raise too_big
        order = np.argsort(src, kind="stable")
        src, dst, cost, side = src[order], dst[order], cost[order], side[order]
        nodes = NodeRows(rows, model.humans)
        actions = ActionRows(side, e_ops[order], e_dur[order], e_dev[order], cost)
        starts = {b: int(starts_a[i]) for i, b in enumerate(levels)}
        end = 0
    else:
        over_memory = functools.partial(memory_limit_error, where, limit=limit, compiled=False)
        nodes, actions, starts, end, src, dst, cost, side = _build_python(
            model, levels, max_nodes, too_big, progress, (limit, over_memory)
        )
    return game_of(model, levels, nodes, actions, starts, end, (src, dst, cost, side), t0)


def game_of(
    model: ConcurrentModel,
    levels: list,
    nodes,
    actions,
    starts: dict,
    end: int,
    edges: tuple,
    t0: float,
    generator: str = "asmplan.concurrent/1",
) -> ConcurrentGame:
    """The :class:`ConcurrentGame` of built nodes and edges: its DAG (edges ``(src, dst,
    cost, side)`` sorted by source, costs scaled; edge labels when there are at most
    :data:`LABEL_LIMIT`), the start of ``levels[-1]`` its start. ``t0``: when the build
    began (``seconds``)."""
    src, dst, cost, side = edges
    ops_labels, agent_labels = (
        _edge_labels(model, actions) if len(actions) <= LABEL_LIMIT else (None, None)
    )
    dag = from_arrays(
        list(range(len(nodes))),
        src,
        dst,
        np.asarray(cost, dtype=np.float64) / model.scale,
        np.asarray(side, dtype=np.int8),
        start=starts[levels[-1]],
        end=end,
        operations=ops_labels,
        agents=agent_labels,
        cost_model="time",
        metadata={
            "generator": generator,
            "assembly": model.spec.name,
            "source": model.spec.source,
            "turn_model": CONCURRENT.name,
            "budgets": [None if b == UNBOUNDED else b for b in levels],
            "workers": {w.name: ("robot" if w.side == ROBOT else "human") for w in model.workers},
        },
    )
    return ConcurrentGame(
        model=model,
        dag=dag,
        budgets=tuple(levels),
        starts=starts,
        nodes=nodes,
        actions=actions,
        seconds=time.perf_counter() - t0,
    )


class NodeRows(Sequence):
    """The compiled builder's node rows read as the Python builder's node tuples."""

    def __init__(self, rows: np.ndarray, humans: list[int]):
        self.rows = rows
        self.humans = humans
        self.nw = (rows.shape[1] - 3) // 3

    def __len__(self) -> int:
        return int(self.rows.shape[0])

    def __getitem__(self, v):
        row = self.rows[int(v)].tolist()
        nw = self.nw
        kind, state, budget = row[0], row[1], row[2]
        if kind == 2:
            return ("E", -1, (), 0, ())
        ops, rem, instr = row[3 : 3 + nw], row[3 + nw : 3 + 2 * nw], row[3 + 2 * nw :]
        running = tuple((o, r) if o >= 0 else (WAIT, 0) for o, r in zip(ops, rem, strict=True))
        told = ()
        if kind == 1 and budget != UNBOUNDED:
            told = tuple(instr[w] for w in self.humans if ops[w] == WAIT)
        return ("R" if kind == 0 else "H", state, running, budget, told)


class ActionRows(Sequence):
    """The compiled builder's edge arrays read as :class:`Commit` and :class:`Reply`."""

    def __init__(self, side, ops, durations, deviations, cost):
        self.side, self.ops, self.durations = side, ops, durations
        self.deviations, self.cost = deviations, cost

    def __len__(self) -> int:
        return int(self.side.shape[0])

    def __getitem__(self, e):
        e = int(e)
        ops = tuple(None if o == -2 else o for o in self.ops[e].tolist())
        if self.side[e] == ROBOT:
            return Commit(ops=ops)
        durs = tuple(None if d == -2 else d for d in self.durations[e].tolist())
        return Reply(
            ops=ops, durations=durs, deviations=int(self.deviations[e]), delta=int(self.cost[e])
        )


def _build_python(model: ConcurrentModel, levels, max_nodes, too_big, progress, memory):
    """The Python builder: a depth-first search over the game's nodes (dict of tuples).
    ``memory``: the limit in bytes and the error for ``(expanded, nodes, edges)`` past it."""
    limit, over_memory = memory
    expanded = 0
    nw = len(model.workers)
    idle = tuple((WAIT, 0) for _ in range(nw))
    index: dict = {}
    nodes: list = []
    src, dst, cost, side, actions = [], [], [], [], []
    end_key = ("E", -1, (), 0, ())

    def node(key) -> int:
        v = index.get(key)
        if v is None:
            v = len(nodes)
            if v >= max_nodes:
                raise too_big
            index[key] = v
            nodes.append(key)
            todo.append(v)
        return v

    todo: list[int] = []
    starts = {b: node(("R", 0, idle, b, ())) for b in levels}
    node(end_key)
    while todo:
        v = todo.pop()
        expanded += 1
        if game_bytes(len(nodes), len(src), compiled=False) > limit:
            raise over_memory((expanded, len(nodes), len(src)))
        key = nodes[v]
        if key[0] == "R":
            for commit, target in _robot_moves(model, key):
                src.append(v)
                dst.append(node(target))
                cost.append(0)
                side.append(ROBOT)
                actions.append(commit)
        elif key[0] == "H":
            seen = set()
            for reply, target in _human_moves(model, key):
                t = node(target) if target != end_key else index[end_key]
                if (t, reply.delta) in seen:
                    continue
                seen.add((t, reply.delta))
                src.append(v)
                dst.append(t)
                cost.append(reply.delta)
                side.append(HUMAN)
                actions.append(reply)
        if progress and len(nodes) % 200_000 == 0:
            print(f"  concurrent game: {len(nodes):,} nodes ...", file=sys.stderr)
    src_a = np.array(src, dtype=np.int64)
    order = np.argsort(src_a, kind="stable")
    acts = [actions[i] for i in order]
    return (
        nodes,
        acts,
        starts,
        index[end_key],
        src_a[order],
        np.array(dst, dtype=np.int64)[order],
        np.array(cost, dtype=np.int64)[order],
        np.array(side, dtype=np.int8)[order],
    )


def _edge_labels(model: ConcurrentModel, actions) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """Each edge's operations (``"a,b"``, ``"wait"`` for none) and agents (``"R1,H"``): the
    ids of the operations started, in worker order, and their workers' names. Computed once
    per distinct row of started operations (few) when ``actions`` is :class:`ActionRows`."""
    ids = model.spec.op_ids
    names = [w.name for w in model.workers]

    def labels(ops) -> tuple[str, str]:
        started = [(w, o) for w, o in enumerate(ops) if o is not None and o >= 0]
        return (
            ",".join(ids[o] for _, o in started) or "wait",
            ",".join(names[w] for w, _ in started),
        )

    if isinstance(actions, ActionRows):
        if len(actions) == 0:
            return (), ()
        uniq, inverse = np.unique(actions.ops, axis=0, return_inverse=True)
        texts = [labels(row) for row in uniq.tolist()]
        ops_of = np.array([t[0] for t in texts], dtype=object)[inverse.ravel()]
        agents_of = np.array([t[1] for t in texts], dtype=object)[inverse.ravel()]
        return tuple(ops_of.tolist()), tuple(agents_of.tolist())
    pairs = [labels(a.ops) for a in actions]
    return tuple(p[0] for p in pairs), tuple(p[1] for p in pairs)


def _assignments(model: ConcurrentModel, state: int, deciders: list[int], busy: tuple[int, ...]):
    """Every joint choice of an operation or :data:`WAIT` for the workers ``deciders`` in
    ``state``: operations they may do, distinct, and compatible with ``busy`` and each other."""
    out: list[tuple[int, ...]] = []

    def extend(i: int, chosen: list[int], ops: tuple[int, ...]) -> None:
        if i == len(deciders):
            out.append(tuple(chosen))
            return
        w = deciders[i]
        chosen.append(WAIT)
        extend(i + 1, chosen, ops)
        chosen.pop()
        for o in model.enabled[state]:
            if model.choices[w][o] and o not in ops:
                new = tuple(sorted((*ops, o)))
                if model.compatible(state, new):
                    chosen.append(o)
                    extend(i + 1, chosen, new)
                    chosen.pop()

    extend(0, [], busy)
    return out


def _robot_moves(model: ConcurrentModel, key):
    """Every commitment of the robot side at robot node ``key`` and the human node it makes."""
    _, state, running, budget, _ = key
    busy = tuple(o for o, _ in running if o != WAIT)
    free_r = [w for w in model.robots if running[w][0] == WAIT]
    free_h = [w for w in model.humans if running[w][0] == WAIT]
    instruct = budget != UNBOUNDED
    deciders = free_r + (free_h if instruct else [])
    out = [dict(zip(deciders, c, strict=True)) for c in _assignments(model, state, deciders, busy)]
    moves = []
    for chosen in out:
        started = [w for w in free_r if chosen[w] != WAIT]
        something = bool(busy) or bool(started)
        if instruct:
            something = something or any(chosen[w] != WAIT for w in free_h)
        else:
            now = tuple(sorted((*busy, *(chosen[w] for w in started))))
            something = something or any(model.candidates(state, w, now) for w in free_h)
        if not something:
            continue
        new_running = list(running)
        for w in started:
            (d,) = model.duration_choices(w, chosen[w], state)
            new_running[w] = (chosen[w], d)
        instr = tuple(chosen[w] for w in free_h) if instruct else ()
        ops = tuple(chosen.get(w) if w in chosen else None for w in range(len(model.workers)))
        moves.append((Commit(ops=ops), ("H", state, tuple(new_running), budget, instr)))
    return moves


def _human_moves(model: ConcurrentModel, key):
    """Every reply of the human side at human node ``key`` and the robot node after it."""
    _, state, running, budget, instr = key
    free_h = [w for w in model.humans if running[w][0] == WAIT]
    told = dict(zip(free_h, instr, strict=False)) if budget != UNBOUNDED else {}
    busy = tuple(o for o, _ in running if o != WAIT)
    picks = _assignments(model, state, free_h, busy)
    moves = []
    for chosen in picks:
        deviations = sum(
            1 for w, o in zip(free_h, chosen, strict=True) if w in told and told[w] != o
        )
        if budget != UNBOUNDED and deviations > budget:
            continue
        final = tuple(sorted((*busy, *(o for o in chosen if o != WAIT))))
        idle_ok = True
        for w, o in zip(free_h, chosen, strict=True):
            following = w in told and told[w] == WAIT
            if o == WAIT and not following and model.candidates(state, w, final):
                idle_ok = False
                break
        if not idle_ok or not final:
            continue
        started = [(w, o) for w, o in zip(free_h, chosen, strict=True) if o != WAIT]
        grids = [model.duration_choices(w, o, state) for w, o in started]
        for durs in _product(grids):
            new_running = list(running)
            for (w, o), d in zip(started, durs, strict=True):
                new_running[w] = (o, d)
            delta = min(r for o, r in new_running if o != WAIT)
            done = []
            for w, (o, r) in enumerate(new_running):
                if o != WAIT:
                    if r == delta:
                        done.append(o)
                        new_running[w] = (WAIT, 0)
                    else:
                        new_running[w] = (o, r - delta)
            new_state = model.after(state, sorted(done))
            left = budget if budget == UNBOUNDED else budget - deviations
            if model.complete[new_state] and all(o == WAIT for o, _ in new_running):
                target = ("E", -1, (), 0, ())
            else:
                target = ("R", new_state, tuple(new_running), left, ())
            ops = [None] * len(model.workers)
            dd = [None] * len(model.workers)
            for w, o in zip(free_h, chosen, strict=True):
                ops[w] = o
            for (w, _), d in zip(started, durs, strict=True):
                dd[w] = d
            reply = Reply(ops=tuple(ops), durations=tuple(dd), deviations=deviations, delta=delta)
            moves.append((reply, target))
    return moves


def _product(grids):
    if not grids:
        yield ()
        return
    first, rest = grids[0], grids[1:]
    for d in first:
        for tail in _product(rest):
            yield (d, *tail)
