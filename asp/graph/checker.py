"""An independent plan checker: replay a line of operations against the part relations.

It shares no code with the state graph (:mod:`asp.graph.feasibility` compiles the relations to
bitmasks; this reads the tables one pair at a time), so a plan both accept is right twice.
For each operation of the line, in order, with ``S`` the parts already there (the base part
from the start when no operation places it):

- the operation's explicit predecessors (``after``) are done and it is not done twice;
- each part ``p`` it places (several in turn, a unit's members together, see below), when
  ``S`` is not empty, is free along an insertion direction: some direction ``d`` the gripper
  approaches from with ``TT_d(p, j)`` for every ``j`` in ``S`` (it comes in along ``-d``);
- it touches ``S``: ``TC_d(p, j)`` for some ``d`` and ``j``, or it comes to rest on ``j``
  (``SP_g(p, j)``, gravity ``g``);
- it is supported: ``SP_g(p, j)`` for some ``j`` in ``S`` (``TC_g`` when the relations carry
  no support table), unless the operation is ``held``;
- at the end every operation is done.

A unit (a subassembly inserted as one rigid body: the spec's ``subassemblies``, whose
insertion operation has ``unit`` set, or ``units={op id: parts}``) is checked as one body:
free along ``d`` iff each member is free from each part of ``S``, touching iff some member
touches, supported iff some member is supported. The operations placing a spec unit's
members are checked against the members already in the unit's own workspace (the first
stands on the fixture), not against the main assembly. A unit built in another orientation
than it has in the product (``spec.unit_gravity``, or ``gravity={unit id: direction}``: a
die set's upper half built upside down, then turned over and inserted) has its members
tested for support along its own gravity there; its insertion is tested along the spec's.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np

DIRECTIONS = ("+x", "-x", "+y", "-y", "+z", "-z")


class PlanCheckError(ValueError):
    """A line of operations that the relations do not allow (one line, naming the step)."""


@dataclass(frozen=True)
class CheckedStep:
    """One checked insertion: the operation, the parts it placed and the way in."""

    operation: str
    parts: tuple[str, ...]
    direction: str
    """The direction ``d`` the body leaves along (inserted along ``-d``); ``""`` if first."""


def check_line(
    spec,
    relations,
    operations: Iterable[str],
    *,
    units: Mapping[str, Iterable[str]] = (),
    gravity: Mapping[str, str] = (),
) -> list[CheckedStep]:
    """Replay ``operations`` (ids, in order) and verify every insertion.

    Parameters
    ----------
    spec : asp.spec.AssemblySpec
    relations : cad Relations or None
        ``parts``, ``tc``, ``tt`` and optionally ``sp`` tables ``(n, n, 6)``; None checks
        only precedence and completeness.
    operations : iterable of str
        A complete line (every operation once).
    units : mapping, optional
        Operation id -> parts it inserts as one rigid unit.
    gravity : mapping, optional
        Unit id -> the gravity in its workspace (product frame; default: the spec's
        ``unit_gravity``, else ``spec.gravity``), as ``plan.json``'s ``workspaces`` give it.

    Returns
    -------
    list of CheckedStep

    Raises
    ------
    PlanCheckError
        The first step that is not allowed, and why.
    """
    units = {str(k): tuple(v) for k, v in dict(units).items()}
    members = dict(spec.subassemblies)
    units.update({op.id: members[op.unit] for op in spec.operations if op.unit})
    owner = {m: u for u, ms in members.items() for m in ms}
    down = {**dict(getattr(spec, "unit_gravity", ())), **dict(gravity)}
    workspaces: dict[str, list[str]] = {u: [] for u in members}
    ids = [str(o) for o in operations]
    c = spec.constraints
    placed_by_ops = {p for op in spec.operations for p in op.parts}
    assembled: list[str] = []
    if spec.base_part and spec.base_part not in placed_by_ops:
        assembled.append(spec.base_part)
    done: set[str] = set()
    out = []
    for k, op_id in enumerate(ids, start=1):
        where = f"{spec.source}: step {k} (operation {op_id})"
        op = spec.operation(op_id)
        if op_id in done:
            raise PlanCheckError(f"{where}: done twice")
        if c.topological:
            missing = [a for a in op.after if a not in done]
            if missing:
                raise PlanCheckError(f"{where}: its predecessor {missing[0]} is not done")
        bodies = [units[op_id]] if op_id in units else [(p,) for p in op.parts]
        for body in bodies:
            unit = owner.get(body[0], "") if op_id not in units else ""
            there = workspaces[unit] if unit else assembled
            direction = ""
            if relations is not None:
                g = down.get(unit, spec.gravity) if unit else spec.gravity
                direction = _check_body(spec, relations, body, there, op.held, where, unit, g)
            out.append(CheckedStep(op_id, body, direction))
            there.extend(body)
        done.add(op_id)
    left = [op.id for op in spec.operations if op.id not in done]
    if left:
        raise PlanCheckError(f"{spec.source}: the line ends with operation {left[0]} not done")
    return out


def _check_body(spec, relations, body, assembled, held, where, unit="", gravity="") -> str:
    """The direction a body leaves along, after checking it may go into ``assembled``."""
    rel_ids = [str(p) for p in relations.parts]
    idx = {p: k for k, p in enumerate(rel_ids)}
    c = spec.constraints
    names = ", ".join(body)
    base = spec.base_part
    if c.topological and base and not unit and base not in body and base not in assembled:
        raise PlanCheckError(f"{where}: {names} placed before the base part {spec.base_part}")
    if not assembled:
        return ""
    tc = np.asarray(relations.tc, dtype=bool)
    tt = np.asarray(relations.tt, dtype=bool)
    sp = getattr(relations, "sp", None)
    sp = tc if sp is None else np.asarray(sp, dtype=bool)
    g = DIRECTIONS.index(gravity or spec.gravity)
    members = [idx[p] for p in body]
    others = [idx[j] for j in assembled]
    touch = rest = False
    free = [True] * 6
    for i in members:
        for j in others:
            touch |= bool(tc[i, j].any() or sp[i, j, g])
            rest |= bool(sp[i, j, g])
            for d in range(6):
                free[d] &= bool(tt[i, j, d])
    ways = [d for d in range(6) if free[d]]
    if c.functional:
        ways = [d for d in ways if DIRECTIONS[d] in spec.gripper_approach]
    if not ways:
        raise PlanCheckError(f"{where}: {names} has no free way in past {', '.join(assembled)}")
    if not touch:
        raise PlanCheckError(f"{where}: {names} touches none of {', '.join(assembled)}")
    if c.stability and not held and not rest:
        fall = "" if g == DIRECTIONS.index(spec.gravity) else f" along {DIRECTIONS[g]}"
        raise PlanCheckError(f"{where}: {names} is not supported (it would fall{fall})")
    return DIRECTIONS[ways[0]]


def plan_operations(plan: Mapping) -> list[str]:
    """The operations of a ``plan.json`` object's principal line (``robust_plan``), in order."""
    return [str(s["operation"]) for s in plan["robust_plan"] if s.get("operation")]


def line_directions(
    spec, relations, operations: Iterable[str]
) -> tuple[dict[str, list[tuple[list[str], str | None]]], str | None]:
    """The bodies each operation of a line puts in, in order, with the direction each leaves
    along (None for the first body of a workspace), and None; or ``({}, error)`` when
    :func:`check_line` refuses the line (its message, without quotes)."""
    checked: dict[str, list[tuple[list[str], str | None]]] = {}
    try:
        for c in check_line(spec, relations, operations):
            checked.setdefault(c.operation, []).append((list(c.parts), c.direction or None))
    except (ValueError, KeyError) as exc:
        return {}, str(exc).strip("'\"")
    return checked, None
