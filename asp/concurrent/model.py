"""The spec and state graph compiled for the concurrent game (:class:`ConcurrentModel`).

The workers, the durations each may take (a human's range on a grid), the state graph's
live transitions with their tool-change times and the tool conflicts; the semantics are in
:mod:`asp.concurrent`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from asp.errors import SpecError
from asp.game.dag import HUMAN, ROBOT
from asp.graph.state_graph import StateGraph
from asp.graph.together import OK, LiveSteps, first_failure
from asp.schedule.cpsat import integer_scale
from asp.schedule.replay import ReplayModel, Worker, spec_workers, tool_conflicts
from asp.spec import AssemblySpec

UNBOUNDED = -1
"""Budget of the fully adversarial human (no instructions, every reply allowed)."""


WAIT = -1
"""Operation index of a worker that waits (or has nothing to do)."""


@dataclass(frozen=True, eq=False)
class ConcurrentModel:
    """The spec and state graph compiled for the concurrent game.

    Attributes
    ----------
    graph : StateGraph
    workers : tuple of Worker
        Robots first, then humans.
    scale : int
        Times are integers in units of ``1 / scale`` (see :func:`asp.schedule.cpsat.integer_scale`).
    choices : list of list of tuple of int, [worker][op]
        The durations (scaled) worker ``w`` may take for operation ``op`` (empty: not
        allowed). A robot has one; a human with a range has the grid points.
    steps : asp.graph.together.LiveSteps
        Transitions of the state graph between co-reachable states, with the tool-change
        time (scaled) the operation adds there.
    succ : dict (state, op) -> (state, change)
        The same as a dictionary (the Python builder's lookups; made when first asked for:
        the compiled rules never do, and on millions of transitions it takes gigabytes).
    enabled : list of tuple of int
        Per state, the operations with a transition (made with ``succ``).
    conflict : (n_ops, n_ops) bool
        Tool conflicts: one changes a tool the other needs or changes.
    complete : (N,) bool
    """

    spec: AssemblySpec
    graph: StateGraph
    workers: tuple[Worker, ...]
    scale: int
    choices: list
    steps: LiveSteps
    conflict: np.ndarray
    complete: np.ndarray
    _memo: dict = field(default_factory=dict, repr=False)
    _lookups: dict = field(default_factory=dict, repr=False)
    _names: dict = field(default_factory=dict, repr=False)

    @property
    def succ(self) -> dict:
        if not self._lookups:
            self._make_lookups()
        return self._lookups["succ"]

    @property
    def enabled(self) -> list:
        if not self._lookups:
            self._make_lookups()
        return self._lookups["enabled"]

    def _make_lookups(self) -> None:
        steps = self.steps
        succ = {}
        enabled = [[] for _ in range(self.graph.n_states)]
        pairs = zip(
            steps.src.tolist(), steps.dst.tolist(), steps.op.tolist(), steps.change.tolist(),
            strict=True,
        )  # fmt: skip
        for s, d, o, c in pairs:
            succ[(s, o)] = (d, int(c))
            enabled[s].append(o)
        self._lookups["succ"] = succ
        self._lookups["enabled"] = [tuple(e) for e in enabled]

    @property
    def op_ids(self) -> tuple[str, ...]:
        """The spec's operation ids (made once: the plan file names every move by them)."""
        ids = self._names.get("ops")
        if ids is None:
            ids = self._names["ops"] = self.spec.op_ids
        return ids

    def state_names(self, state: int) -> tuple[tuple[str, ...], dict]:
        """The done operations (ids) and the tool values of a state of the graph, made once
        per state (a policy game has many nodes per state)."""
        names = self._names.setdefault("states", {})
        out = names.get(state)
        if out is None:
            key = self.graph.key(state)
            gm = self.graph.model
            out = names[state] = (tuple(gm.done_ops(key)), gm.tool_state(key))
        return out

    @property
    def n_ops(self) -> int:
        return len(self.spec.operations)

    @property
    def robots(self) -> list[int]:
        return [w for w, x in enumerate(self.workers) if x.side == ROBOT]

    @property
    def humans(self) -> list[int]:
        return [w for w, x in enumerate(self.workers) if x.side == HUMAN]

    def compatible(self, state: int, ops: tuple[int, ...]) -> bool:
        """Whether the operations ``ops`` may run together from ``state``
        (:func:`asp.graph.together.together`, the one place this rule is written)."""
        key = (state, ops)
        hit = self._memo.get(key)
        if hit is None:
            hit = first_failure(self.steps, self.conflict, state, ops)[0] == OK
            self._memo[key] = hit
        return hit

    def after(self, state: int, ops) -> int:
        """The state after the operations ``ops`` (compatible) are done on top of ``state``."""
        for o in ops:
            state = self.succ[(state, o)][0]
        return state

    def duration_choices(self, w: int, op: int, state: int) -> tuple[int, ...]:
        """Durations (scaled) worker ``w`` may take for ``op`` started in ``state``."""
        change = self.succ[(state, op)][1]
        return tuple(d + change for d in self.choices[w][op])

    def candidates(self, state: int, w: int, busy: tuple[int, ...]) -> list[int]:
        """Operations worker ``w`` may start in ``state`` next to the busy operations."""
        return [
            o
            for o in self.enabled[state]
            if self.choices[w][o]
            and o not in busy
            and self.compatible(state, tuple(sorted((*busy, o))))
        ]

    def time(self, scaled: float) -> float:
        """A scaled time in the spec's units."""
        return scaled / self.scale

    @property
    def succ_change_max(self) -> int:
        """The longest tool-change time (scaled) any transition adds."""
        return max((c for _, c in self.succ.values()), default=0)

    @property
    def replay(self) -> ReplayModel:
        """The same rules for a schedule replay (:func:`asp.schedule.replay.schedule_violation`):
        the graph's transitions as they are, without short cuts."""
        return ReplayModel(self.spec, self.workers, self.steps, self.conflict)

    def kernel_arrays(self) -> tuple:
        """The arrays :func:`asp.concurrent.kernel.build_kernel` takes (its docstring)."""
        n = self.n_ops
        nw = len(self.workers)
        width = max((len(c) for row in self.choices for c in row), default=1)
        dur = np.zeros((nw, n, max(1, width)), dtype=np.int64)
        ndur = np.zeros((nw, n), dtype=np.int64)
        for w, row in enumerate(self.choices):
            for o, c in enumerate(row):
                ndur[w, o] = len(c)
                dur[w, o, : len(c)] = c
        side = np.array([w.side for w in self.workers], dtype=np.int8)
        steps = self.steps
        return (
            steps.indptr,
            steps.dst.astype(np.int64),
            steps.op.astype(np.int64),
            steps.change,
            dur,
            ndur,
            self.conflict,
            self.complete,
            side,
        )


def game_spec(spec: AssemblySpec, graph: StateGraph) -> AssemblySpec:
    """The spec whose operations the graph's states are made of: ``spec`` when they are its
    own, the graph's spec when it adds operations to ``spec``'s (subassemblies' insertions).

    Raises
    ------
    ValueError
        The graph's operations are not ``spec``'s nor a superset of them.
    """
    own = graph.spec
    if own is spec or own.op_ids == spec.op_ids:
        return spec
    if set(spec.op_ids) < set(own.op_ids):
        return own
    missing = sorted(set(spec.op_ids) - set(own.op_ids))
    raise SpecError(
        f"{spec.source or spec.name}: the state graph is of other operations than the spec "
        f"({len(own.op_ids)} against {len(spec.op_ids)}"
        + (f"; it has no {', '.join(missing[:3])}" if missing else "")
        + ")"
    )


def concurrent_model(
    spec: AssemblySpec, graph: StateGraph, *, step: float | None = 1.0
) -> ConcurrentModel:
    """Compile ``spec`` and its state graph for the concurrent game.

    Parameters
    ----------
    step : float or None
        Grid of the human's durations within a range (module docstring); ``None``: the two
        end points.

    The game is played on the graph's operations: when the graph's spec holds ``spec``'s
    operations and more (the insertions of subassemblies found while it was built,
    :func:`asmplan.pipeline.state_graph`), the graph's spec is the game's.

    Raises
    ------
    ValueError
        One line naming the spec and the fault: a robot with a duration range, an agent
        with no operation it may do, an operation nobody may do, a bad duration or step,
        a graph of other operations.
    """
    spec = game_spec(spec, graph)
    where = spec.source or spec.name
    if step is not None and not (math.isfinite(step) and step > 0):
        raise SpecError(f"{where}: duration step: expected a positive number, got {step}")
    workers = spec_workers(spec)
    ops = spec.operations
    ranges = [[None] * len(ops) for _ in workers]
    for i, op in enumerate(ops):
        if not op.durations:
            raise SpecError(f"{where}: operations[{op.id}]: no agent may do this operation")
        for w, x in enumerate(workers):
            if x.agent in op.agents:
                lo, hi = op.duration_range(x.agent)
                if not (math.isfinite(lo) and math.isfinite(hi)) or lo < 0 or lo > hi:
                    raise SpecError(
                        f"{where}: operations[{op.id}].agents.{x.agent}: expected a duration "
                        f">= 0 or a range [min, max] with 0 <= min <= max, got [{lo}, {hi}]"
                    )
                if lo != hi and x.side == ROBOT:
                    raise SpecError(
                        f"{where}: operations[{op.id}].agents.{x.agent}: a duration range is "
                        "for a human; a robot's duration is one number"
                    )
                ranges[w][i] = (lo, hi)
    for a in spec.agents:
        if not any(a.name in op.agents for op in ops):
            raise SpecError(f"{where}: agents.{a.name}: this agent may do no operation")
    numbers = [v for row in ranges for r in row if r is not None for v in r]
    numbers += [t.change_time for t in spec.tools] + ([step] if step is not None else [])
    scale = integer_scale(numbers)
    choices = []
    for row in ranges:
        out = []
        for r in row:
            if r is None:
                out.append(())
                continue
            lo, hi = round(r[0] * scale), round(r[1] * scale)
            if lo == hi:
                out.append((lo,))
            elif step is None:
                out.append((lo, hi))
            else:
                s = max(1, round(step * scale))
                out.append(tuple(range(lo, hi, s)) + (hi,))
        choices.append(out)
    model = graph.model
    change = np.array([round(spec.tool(t).change_time * scale) for t in model.tool_names])

    def change_time(src, op):
        return model.tool_changes(graph.keys[src], op).astype(np.int64) @ change

    steps = LiveSteps(graph, change_time if model.tool_names else None)
    conflict = tool_conflicts(spec)
    return ConcurrentModel(
        spec=spec,
        graph=graph,
        workers=tuple(workers),
        scale=scale,
        choices=choices,
        steps=steps,
        conflict=conflict,
        complete=graph.complete,
    )
