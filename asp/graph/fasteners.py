"""Fasteners in one order after the parts they join: far fewer states, every plan sound.

A product held together by screws (the APLAN toy truck: 61 parts, 39 of them screws) has
states for every subset of screws driven so far, and the state graph exceeds any limit
(71.5 M projected), although a screw matters to nothing but the two parts it joins. Scene
files of purchased or visual assets have the same class with one host or several: a cover
touching only the block it sits on, a sensor module on a back plate, a bolt through three
plates (the two-cylinder engine: 4 such parts on its head and block, 16 times fewer states).

**Joining part.** Part ``f``, placed alone by an operation of the main assembly (no unit,
no tools, no explicit predecessors, no operation waiting for it, not the base part), is a
*joining part* of the parts it touches (its *joined parts*, one or more) when, in the
insertion tests (:mod:`asp.graph.feasibility`, DESIGN.md "Support" and "precedence"):

1. every part ``f`` touches (or rests on) is the base part or placed alone in the main
   assembly, and none of them is a joining part itself (so no part but its joined parts
   touches or rests on ``f``, and a joined part needs no joining part to touch: links
   of a chain, each touching the next, are none);
2. ``f`` goes in whatever else is there: some direction the gripper may approach from is
   free of every other part, and ``f`` rests on a joined part (or is ``held``).

**The reduction** (:func:`fastener_order`): each joining part waits for the parts it joins
and for the joining part before it (one chain, ordered by when their joined parts can be
there: the latest of them in the spec's order); a joined part resting on nothing but its
own joining parts, which now come after it, is ``held`` while they go in (DESIGN.md: held
until a later operation fixes it). These are only precedences and ``held`` marks on the
spec, so the state graph still tests every move with the same insertion oracle: every
sequence it holds is feasible by the DESIGN's rules with those marks, and every plan is
sound (the independent checker replays it with the plan's held flags).

**What it keeps.** With the marks, the reduced graph has a complete sequence iff the full
graph has one in which every joining part follows every part it joins. Proof: take such a
sequence, keep its other parts in their order and put the joining parts last, in chain
order. A part ``q`` that is no joining part now sees a subset of what it saw: its free
directions stay free (a part that blocks no move when there blocks none when not);
what it touched or rested on was no joining part (a joining part touches only its joined
parts, and came after them); its predecessors are the same. A joining part at the end
goes in along its free direction (2), touching and resting on its
joined parts, which are there (and its predecessors, the chain's, are done). How many
parts it joins plays no part in this. Conversely
every sequence of the reduced graph is one of the full graph (with the marks). When the
reduced graph has no complete sequence, the full graph's answer stands
(:func:`asp.subassemblies.build_with_units` keeps the state-limit error).

**Where it applies.** Only where the full graph exceeds its state limit (or, in a round of
automatic units guessed for a proved failure, first: :func:`asp.subassemblies.build_with_units`):
screws, pins, covers and modules that touch nothing but their joined parts and go in along a
way nothing else closes. A screw
whose head a later cover would stop (blocked by it along its only way) is not one: it stays
free. The joining parts are found before the full graph is built. When they alone multiply
its states past the limit (:func:`joining_states`, a lower bound where no joined part is
held, a projection where one is), the full graph is not tried at all
(:func:`asp.subassemblies.fastener_projection`; the toy truck: 34 joining
parts, at least 725 M states; the plan 23 s CPU and 0.72 GB, from 48 s and 1.2 GB, the same
plan); it is built only when the ordered graph fails. Otherwise the full graph is built
first, with a projection margin of 1 (:func:`asp.graph.state_graph.build_state_graph`): a
graph sure to go over is given up as soon as its cautious projection passes the limit.

**What it changes.** The game is played over the sequences with the joining parts in that
order, each after the parts it joins: TCT and W* are those of that game (TCT no lower than the
full graph's; the order is a rule of the cell, "fasten in this order once the parts are
there", said on stderr and kept in the plan's spec as precedences).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from asp.graph.precedences import with_waits
from asp.spec import DIRECTIONS, AssemblySpec


@dataclass(frozen=True)
class Joining:
    """A joining part and the two parts it joins (module docstring).

    Attributes
    ----------
    part : str
    joins : tuple of str
        The parts it touches (one or more), in the relations' order.
    operation : str
        The operation placing it.
    """

    part: str
    joins: tuple[str, ...]
    operation: str


def _support(relations) -> np.ndarray:
    """``relations.sp``, or contact where it is absent (as the insertion oracle reads it)."""
    sp = getattr(relations, "sp", None)
    return np.asarray(relations.tc if sp is None else sp, dtype=bool)


def _single_placements(spec: AssemblySpec) -> dict[str, int]:
    """Part -> index of the one main-assembly operation placing it alone (no tools)."""
    in_units = {m for _, members in spec.subassemblies for m in members}
    count: dict[str, int] = {}
    out: dict[str, int] = {}
    for i, op in enumerate(spec.operations):
        for p in op.parts:
            count[p] = count.get(p, 0) + 1
        if len(op.parts) == 1 and not op.unit and not op.requires and not op.sets:
            out[op.parts[0]] = i
    return {p: i for p, i in out.items() if count[p] == 1 and p not in in_units}


def joining_parts(spec: AssemblySpec, relations) -> list[Joining]:
    """The joining parts of ``spec`` under ``relations`` (module docstring), in spec order.

    Parameters
    ----------
    spec : AssemblySpec
    relations : cad Relations
        As the state graph reads them (the spec's ``flex`` and the nearest parts applied).
    """
    if relations is None:
        return []
    ids = [str(p) for p in relations.parts]
    where = {p: k for k, p in enumerate(ids)}
    tc = np.asarray(relations.tc, dtype=bool)
    tt = np.asarray(relations.tt, dtype=bool)
    sp = _support(relations)
    g = DIRECTIONS.index(spec.gravity)
    touch = tc.any(axis=2) | sp[:, :, g]
    touch = touch | touch.T
    np.fill_diagonal(touch, False)
    allowed = np.array(
        [not spec.constraints.functional or d in spec.gripper_approach for d in DIRECTIONS]
    )
    single = _single_placements(spec)
    base = spec.base_part
    waited_for = {a for op in spec.operations for a in op.after}
    candidates: dict[str, tuple[str, ...]] = {}
    for p, i in single.items():
        op = spec.operations[i]
        if p == spec.base_part or p not in where or op.after or op.id in waited_for:
            continue
        f = where[p]
        near = np.flatnonzero(touch[f])
        if not len(near) or not all(ids[j] in single or ids[j] == base for j in near):
            continue
        rest = np.ones(len(ids), dtype=bool)
        rest[f] = False
        free = tt[f, rest].all(axis=0) & allowed  # (2): free of every other part
        rests = op.held or not spec.constraints.stability or sp[f, near, g].any()
        if free.any() and rests:
            candidates[p] = tuple(ids[j] for j in near)
    return [
        Joining(p, joins, spec.operations[single[p]].id)
        for p, joins in candidates.items()
        if not set(joins) & set(candidates)
    ]


def _held_on_joining(spec: AssemblySpec, relations, found: list[Joining]) -> set[str]:
    """The joined parts that rest on nothing but joining parts of their own (a drum
    support standing on the two screws that fix it): with the screws after it, an agent
    holds it while they go in (``held``, DESIGN.md "Support")."""
    ids = [str(p) for p in relations.parts]
    where = {p: k for k, p in enumerate(ids)}
    sp = _support(relations)[:, :, DIRECTIONS.index(spec.gravity)]
    own: dict[str, set[int]] = {}
    for j in found:
        for p in j.joins:
            own.setdefault(p, set()).add(where[j.part])
    out = set()
    for p, joining in own.items():
        rests = set(np.flatnonzero(sp[where[p]]).tolist())
        if rests and rests <= joining and p != spec.base_part:
            out.add(p)
    return out


def fastener_order(spec: AssemblySpec, relations) -> tuple[AssemblySpec, list[Joining]]:
    """``spec`` with its joining parts in one chain, each after the two parts it joins
    (module docstring), and those parts; ``spec`` itself when it has fewer than two.

    A joined part resting on nothing but its own joining parts is ``held`` as well: they
    now come after it, and an agent holds it while they go in (DESIGN.md "Support": held
    until a later operation fixes it; the caller says which)."""
    found = joining_parts(spec, relations)
    if len(found) < 2:
        return spec, []
    hold = _held_on_joining(spec, relations, found)
    single = _single_placements(spec)
    position = {op.id: i for i, op in enumerate(spec.operations)}
    found.sort(key=lambda j: (max(single.get(p, -1) for p in j.joins), position[j.operation]))
    wait: dict[str, tuple[str, ...]] = {}
    before = None
    for j in found:
        joined = tuple(spec.operations[single[p]].id for p in j.joins if p in single)
        wait[j.operation] = (*joined, *((before,) if before else ()))
        before = j.operation
    held = tuple(
        replace(op, held=True) if len(op.parts) == 1 and op.parts[0] in hold else op
        for op in spec.operations
    )
    return with_waits(replace(spec, operations=held), wait), found


def joining_states(found: list[Joining], classes) -> int:
    """How many states the free order of the joining parts ``found`` gives the full graph:
    2 for each (in or not), and ``m + 1`` for a class of interchangeable blocks of which
    ``m`` hold joining parts (the symmetry reduction puts them in one order: a prefix of
    them in; ``classes`` as :func:`asp.graph.symmetry.symmetry_reduction` returns them,
    each a list of blocks of operation ids).

    **A lower bound** when some complete sequence places every joining part after the two
    parts it joins, none of them held (the module docstring's reordered sequence): its
    state with every other part in and no joining part is a state of the full graph; from
    it each joining part goes in (2), and none is ever stuck (each has its free direction),
    so every set of them the symmetry reduction's order allows is a state (a prefix of each
    chain; a loose order allows more). Where a joined part rests on its joining parts only
    (``held`` by :func:`fastener_order`) that state may not be reached, and the count is a
    projection: skipping the full graph on it costs at most the free order of the joining
    parts, never soundness, and when the ordered graph fails the full graph is built.
    """
    ops = {j.operation for j in found}
    count, seen = 1, set()
    for cls in classes:
        blocks = [b for b in cls if ops & set(b)]
        seen.update(o for b in blocks for o in b)
        count *= len(blocks) + 1
    return count * 2 ** len(ops - seen)


__all__ = ["Joining", "fastener_order", "joining_parts", "joining_states"]
