"""Which way up a unit is built: the gravity of a subassembly's workspace.

DESIGN.md ("Parts and subassemblies from CAD"): a subassembly is built on its own and then
inserted as one rigid unit, so it may be built in another orientation than the one it has
in the product, then turned over and inserted. A toolmaker builds the upper half of a die
set upside down: its top plate on the bench, the punch holder and the punch on it, the
stripper plate hanging on its bolts, then turns the half over and lowers it onto the
guide pins. In the product's frame, the workspace's gravity is then the opposite of the
product's (``+z`` for a ``-z`` product); directions everywhere (relations, insertion
directions, ``plan.json``) stay in the product's frame.

Rule (:func:`orient_units`, specs generated from a CAD file only; a user's spec says it with
``subassemblies: {unit: {parts: [...], gravity: +z}}``): each unit is built either as it sits
in the product (gravity ``g``) or upside down (``-g``). For each, its *loose* members are those
no other member keeps from falling (an empty row of the support relation restricted to the
unit: in its workspace only members are there); one of them may be the workspace's first
part (it stands on the fixture), the others need an agent holding them. Upside down is
chosen when it needs strictly fewer holds and its members can be placed one by one
(:func:`asp.fromcad.gravity.one_sequence` over the members), or when only it can be built. The
member placements' ``held`` follow the orientation chosen (a screw driven upwards in the
product is held there, but rests on its head in a half built upside down), and the member
that carries the most others (the top plate) stands first on the bench: the other
members' placements wait for it.

A unit's insertion into the product is always tested along the product's gravity (it is
turned back before it goes in): support of a unit is that of its members in the product.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from asp.spec import DIRECTIONS, AssemblySpec


@dataclass(frozen=True)
class UnitOrientation:
    """How one unit is built.

    Attributes
    ----------
    unit : str
        The unit id.
    gravity : str
        The gravity in its workspace (product frame).
    upside_down : bool
        Built upside down (``gravity`` is the opposite of the product's).
    held : tuple of str
        Members an agent holds in its workspace (generated specs).
    base : str
        The member that stands on the fixture first ("" when any may).
    held_other : int
        How many members the other orientation would need held (-1: it cannot be built).
    """

    unit: str
    gravity: str
    upside_down: bool
    held: tuple[str, ...]
    base: str
    held_other: int

    @property
    def text(self) -> str:
        """One line for a person (stderr and the plan's text)."""
        if not self.upside_down:
            return f"{self.unit}: built as it sits in the product (gravity {self.gravity})"
        other = (
            "cannot be built right side up"
            if self.held_other < 0
            else f"right side up {self.held_other} would need holding"
        )
        on = f", {self.base} first on the bench" if self.base else ""
        return (
            f"{self.unit}: built upside down (gravity {self.gravity} in its workspace{on}), "
            f"then turned over and inserted; {len(self.held)} of its parts held ({other})"
        )


def loose_units(spec: AssemblySpec, relations) -> set[str]:
    """The units that no part outside them can keep from falling along the product's
    gravity (an upper die set sliding down its guide pins, drawn open): each is held while
    it goes in (:func:`asp.subassemblies.hold_unsupported_units`; ``asmplan init`` writes
    ``held: true``). Empty without a support table."""
    sp = getattr(relations, "sp", None)
    if relations is None or sp is None:
        return set()
    index = {str(p): k for k, p in enumerate(relations.parts)}
    rests = np.asarray(sp, dtype=bool)[:, :, DIRECTIONS.index(spec.gravity)]
    loose = set()
    for uid, members in spec.subassemblies:
        rows = [index[m] for m in members if m in index]
        outside = np.ones(len(index), dtype=bool)
        outside[rows] = False
        if rows and not rests[np.ix_(rows, np.flatnonzero(outside))].any():
            loose.add(uid)
    return loose


def opposite(direction: str) -> str:
    """``+z`` <-> ``-z``."""
    return ("-" if direction[0] == "+" else "+") + direction[1:]


def unit_orientation(spec: AssemblySpec, relations, unit: str) -> UnitOrientation:
    """How ``unit`` of ``spec`` is best built (module docstring: the rule)."""
    members = dict(spec.subassemblies)[unit]
    g = spec.gravity
    right = _build(relations, members, g)
    flipped = _build(relations, members, opposite(g))
    flip = flipped is not None and (right is None or len(flipped[0]) < len(right[0]))
    held, base = (flipped if flip else right) or ((), "")
    other = right if flip else flipped
    return UnitOrientation(
        unit=unit,
        gravity=opposite(g) if flip else g,
        upside_down=flip,
        held=tuple(held),
        base=base,
        held_other=-1 if other is None else len(other[0]),
    )


def orient_units(spec: AssemblySpec, relations, say=None) -> AssemblySpec:
    """A generated spec with each unit built upside down where that is better (the rule of
    the module docstring): ``unit_gravity`` set, its member placements' ``held`` following
    the orientation. A user's spec, or one without units or support relations, is
    returned unchanged. ``say`` is called with a line for each unit turned."""
    if (
        not spec.generated
        or not spec.constraints.stability
        or relations is None
        or getattr(relations, "sp", None) is None
        or not spec.subassemblies
    ):
        return spec
    known = {str(p) for p in relations.parts}
    turned = dict(spec.unit_gravity)
    hold: dict[str, bool] = {}
    first: dict[str, list[str]] = {}  # a turned unit's first member -> the others
    for uid, members in spec.subassemblies:
        if uid in turned or not set(members) <= known:
            continue
        o = unit_orientation(spec, relations, uid)
        if not o.upside_down:
            continue
        turned[uid] = o.gravity
        hold.update({m: m in o.held for m in members})
        first[o.base] = [m for m in members if m != o.base]
        if say is not None:
            say(o.text)
    if not hold:
        return spec
    op_of = {p: op.id for op in spec.operations for p in op.parts}
    wait = {op_of[m]: op_of[b] for b, others in first.items() for m in others}
    ops = []
    for op in spec.operations:
        if op.parts and all(p in hold for p in op.parts):
            op = replace(op, held=any(hold[p] for p in op.parts))
        if op.id in wait and wait[op.id] != op.id and wait[op.id] not in op.after:
            op = replace(op, after=(*op.after, wait[op.id]))
        ops.append(op)
    return replace(spec, operations=tuple(ops), unit_gravity=tuple(turned.items()))


def _build(relations, members, gravity: str) -> tuple[list[str], str] | None:
    """The members to hold and the member standing first on the fixture, building
    ``members`` with ``gravity`` (None: no order places them one by one).

    Loose members (nothing among the members keeps them from falling) are held but the
    first; the first is the loose member (any member when none is loose) that keeps the
    most members from falling, of those from which :func:`asp.fromcad.gravity.one_sequence` finds
    (or cannot rule out) an order placing every member.
    """
    from asp.fromcad.gravity import one_sequence

    index = {str(p): k for k, p in enumerate(relations.parts)}
    rows = [index[m] for m in members]
    ix = np.ix_(rows, rows)
    sp = np.asarray(relations.sp, dtype=bool)[ix]
    rests = sp[:, :, DIRECTIONS.index(gravity)].copy()
    np.fill_diagonal(rests, False)
    loose = [k for k in range(len(rows)) if not rests[k].any()]
    carries = rests.sum(axis=0)
    sub = _Tables(
        parts=tuple(members),
        tc=np.asarray(relations.tc, dtype=bool)[ix],
        tt=np.asarray(relations.tt, dtype=bool)[ix],
        sp=sp,
    )
    for base in sorted(loose or range(len(rows)), key=lambda k: (-carries[k], k)):
        held = {k for k in loose if k != base}
        if one_sequence(sub, gravity, base, held) is not False:
            return [members[k] for k in sorted(held)], members[base]
    return None


@dataclass(frozen=True)
class _Tables:
    """The relations among a unit's members (the tables :func:`one_sequence` reads)."""

    parts: tuple[str, ...]
    tc: np.ndarray
    tt: np.ndarray
    sp: np.ndarray


__all__ = ["UnitOrientation", "loose_units", "opposite", "orient_units", "unit_orientation"]
