"""Interchangeable parts: identical choices do not multiply the states.

Two placement operations ``a`` and ``b`` (placing parts ``p`` and ``q``) are interchangeable
when swapping ``p`` and ``q`` maps the whole problem onto itself: every relation table row
and column of ``p`` equals that of ``q`` (contact, freedom and support towards every other
part, and between the two the same both ways), and the operations are alike in everything
but their id and part (agents and durations, tools read and written, ``held``, their own
predecessors, and every other operation needs both or neither). Pins standing in the holes of
one disc, or the balls of a bearing, are such parts.

A class of ``k`` interchangeable operations is acted on by every permutation of it, and each
set of done operations has exactly one image in which the class's done members are its first
``m``; so the graph restricted to those states (the class done in a fixed order, a chain of
precedences) is the quotient of the full graph by the symmetry. Every move of the full game
maps onto a move of the quotient with the same cost and an isomorphic future, so TCT and W*
are the same (tested against the full graph), with ``k + 1`` states for the class instead of
``2**k``.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from asp.spec import AssemblySpec


def interchangeable_classes(spec: AssemblySpec, relations) -> list[list[str]]:
    """Classes (two or more operation ids, in spec order) of interchangeable operations."""
    if relations is None:
        return []
    rel_ids = [str(p) for p in relations.parts]
    idx = {p: k for k, p in enumerate(rel_ids)}
    tables = [np.asarray(relations.tc), np.asarray(relations.tt)]
    if getattr(relations, "sp", None) is not None:
        tables.append(np.asarray(relations.sp))
    in_units = {m for _, ms in spec.subassemblies for m in ms}
    needed_by = {
        op.id: frozenset(o.id for o in spec.operations if op.id in o.after)
        for op in spec.operations
    }
    candidates = [
        op
        for op in spec.operations
        if len(op.parts) == 1
        and op.parts[0] in idx
        and op.parts[0] not in in_units
        and op.parts[0] != spec.base_part
        and not op.unit
    ]

    def signature(op):
        return (
            tuple(sorted(op.durations)),
            tuple(sorted(op.ranges)) if hasattr(op, "ranges") else (),
            op.requires,
            op.sets,
            op.held,
            frozenset(op.after),
            needed_by[op.id],
        )

    def same(a: int, b: int) -> bool:
        others = [k for k in range(len(rel_ids)) if k not in (a, b)]
        for t in tables:
            if not (
                np.array_equal(t[a, others], t[b, others])
                and np.array_equal(t[others, a], t[others, b])
            ):
                return False
            if not np.array_equal(t[a, b], t[b, a]):
                return False
        return True

    classes: list[list] = []
    for op in candidates:
        for cls in classes:
            # every transposition in the class must be a symmetry (the whole permutation group)
            if signature(cls[0]) == signature(op) and all(
                same(idx[o.parts[0]], idx[op.parts[0]]) for o in cls
            ):
                cls.append(op)
                break
        else:
            classes.append([op])
    return [[op.id for op in cls] for cls in classes if len(cls) > 1]


def with_fixed_order(spec: AssemblySpec, classes: list[list[str]]) -> AssemblySpec:
    """``spec`` with each class done in its listed order (the quotient by the symmetry)."""
    if not classes:
        return spec
    prev = {b: a for cls in classes for a, b in zip(cls, cls[1:], strict=False)}
    ops = tuple(
        replace(op, after=(*op.after, prev[op.id])) if op.id in prev else op
        for op in spec.operations
    )
    return replace(spec, operations=ops)


def reduce_interchangeable(spec: AssemblySpec, relations) -> AssemblySpec:
    """:func:`with_fixed_order` of the :func:`interchangeable_classes` of ``spec``."""
    return with_fixed_order(spec, interchangeable_classes(spec, relations))
