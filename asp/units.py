"""Subassemblies: parts built in a workspace of their own and inserted as one rigid unit.

DESIGN.md ("Parts and subassemblies from CAD"). A unit ``U`` with member parts ``M``:

- the operations placing ``M`` (each placing members only) form the unit's workspace: each is
  tested against the members already placed there, not against the main assembly (the first
  member stands on the fixture, as the base part does);
- one *insertion operation*, id ``U``, inserts the finished unit into the main assembly
  (its predecessors: every member operation). It is tested as one rigid body: ``U`` is free
  along ``d`` from ``S`` iff every member is free along ``d`` from every part of ``S``;
  touches iff some member touches; is supported iff some member is (the pairwise relations
  ORed over the members, :func:`asp.feasibility.insertion_oracle`). Its duration for an
  agent is the longest member operation that agent may do (a documented default);
- a state is still the set of operations done, so the game runs over the product of the
  workspaces: a person may build a unit while a robot works on the main body.

Sources, in this order: the spec's ``subassemblies:`` (:func:`asp.spec.with_subassemblies`),
and automatic detection when a part can never be inserted alone (:func:`build_with_units`):
a part that is never inserted, or is left in every furthest dead end, enters with the parts
that hold it along some direction (:func:`host_groups`: a holder with the flanged bearings
pressed into it; a gusset with one of the two walls whose pockets hold its tabs, the other
gussets of that wall joining the same unit). Every unit is checked by the state graph
itself (built in its own workspace, inserted as one rigid body), so units only ever make
sound plans.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from asp.spec import AssemblySpec, with_subassemblies

MAX_ROUNDS = 8
"""Rounds of automatic detection (each adds the units of the root causes found)."""


def unit_members(spec: AssemblySpec) -> dict[str, tuple[str, ...]]:
    """Unit id -> member part ids."""
    return dict(spec.subassemblies)


def workspace_of(spec: AssemblySpec) -> dict[str, str]:
    """Operation id -> the unit whose workspace it builds in (``""``: the main assembly)."""
    owner = {m: u for u, ms in spec.subassemblies for m in ms}
    out = {}
    for op in spec.operations:
        units = {owner.get(p, "") for p in op.parts}
        out[op.id] = units.pop() if len(units) == 1 else ""
    return out


def host_groups(oracle, p: int, base: int) -> list[set[int]]:
    """The ways part ``p`` can be held by the parts it is engaged with, smallest first.

    For each direction ``d``, ``p`` with the parts it touches that block it along ``d``
    (the parts that must be there before it for it to move along ``d`` with them, as a
    gusset with one of the two sides whose slots hold it, or a holder with all the flanged
    bearings pressed into it). Directions where nothing touching blocks ``p``, or where the
    base part does, give no group; equal groups count once.
    """
    from asp.feasibility import unpack_words

    contact = unpack_words(oracle.contact[p])
    out: list[set[int]] = []
    for d in range(6):
        by = contact & unpack_words(oracle.blocked[p, d])
        group = {p} | {j for j in range(len(oracle.parts)) if by >> j & 1}
        if len(group) >= 2 and base not in group and group not in out:
            out.append(group)
    return sorted(out, key=len)


def build_with_units(spec: AssemblySpec, relations=None, *, on_unit=None, **kwargs):
    """Build the state graph, adding a subassembly for each part that can never go in alone.

    When the assembly has no complete sequence, each root-cause part (an operation never
    done although ready somewhere) is grouped with the parts that hold it
    (:func:`host_groups`: the smallest group, preferring one that shares parts with a unit
    already found, so that the parts held by one host enter with it), overlapping groups
    merge (with the units of earlier rounds too), and the graph is built again with those
    units (at most :data:`MAX_ROUNDS` rounds). The original error is raised if that does
    not help. Every unit is checked by the state graph itself: its members must go into
    its own workspace one by one and the finished unit into the assembly as one rigid body,
    so a unit that cannot be built or inserted gives no plan. Keyword arguments go to
    :func:`asp.state_graph.build_state_graph`; ``on_unit`` is called with a line for each
    round that adds units.

    Returns
    -------
    StateGraph
        Its ``spec`` holds the units found (``spec.subassemblies``).
    """
    from asp.state_graph import build_state_graph

    first_error = None
    found: list[tuple[str, ...]] = []
    current = spec
    for _ in range(MAX_ROUNDS + 1):
        try:
            return build_state_graph(current, relations, **kwargs)
        except ValueError as exc:
            if relations is None or "infeasible assembly" not in str(exc):
                raise
            first_error = first_error or exc
            graph = build_state_graph(current, relations, **{**kwargs, "check": False})
            groups = _new_units(graph, stuck_operations(graph), spec, found)
            if groups is None:
                raise first_error from None
            try:
                current = with_subassemblies(spec, _named(spec, groups))
            except ValueError:
                raise first_error from None
            found = groups
            if on_unit is not None:
                on_unit(
                    "no complete sequence with single parts: trying subassemblies "
                    + "; ".join(f"[{', '.join(g)}]" for g in groups)
                )
    raise first_error


def stuck_operations(graph) -> list[int]:
    """Operations whose part cannot go in alone: those never done although ready somewhere;
    when every operation is done in some order but none completes, those left ready in the
    furthest dead ends (the states of the last layer), such as the last of four gussets,
    held by the other three whichever it is."""
    from asp.state_graph import never_done

    never = never_done(graph)
    if never or not graph.n_states:
        return never
    model = graph.model
    last = np.arange(int(graph.layer_ptr[-2]), int(graph.layer_ptr[-1]))
    keys = graph.keys[last]
    return [i for i in range(model.n_ops) if model.part_lists[i] and model.ready(keys, i).any()]


def _new_units(graph, ops: list[int], spec: AssemblySpec, found: list[tuple[str, ...]]):
    """The automatic units after a round: ``found`` with the parts of the never-done
    operations ``ops`` grouped with their hosts (None when nothing changes)."""
    model = graph.model
    oracle = model.oracle
    fixed = {m for _, ms in spec.subassemblies for m in ms}  # the spec's own units stay
    placed_by = {p for op in spec.operations for p in op.parts}
    groups = [set(g) for g in found]
    before = sorted(map(sorted, groups))
    for i in ops:
        for p in model.part_lists[i]:
            if p >= len(graph.spec.part_ids) and graph.spec.part_ids:
                # a unit's insertion: the unit with what holds one of its members
                name = oracle.parts[p]
                members = dict(graph.spec.subassemblies)[name]
                candidates = [
                    {oracle.parts[j] for j in g} | set(members) - {name}
                    for m in members
                    for g in host_groups(oracle, oracle.index(m), oracle.base)
                ]
            else:
                candidates = [
                    {oracle.parts[j] for j in g} for g in host_groups(oracle, p, oracle.base)
                ]
            grouped = set().union(*groups) if groups else set()
            candidates = [
                c for c in candidates if not c & fixed and c <= placed_by and not c <= grouped
            ]
            if not candidates:
                continue
            group = min(candidates, key=lambda c: (len(c - grouped), len(c)))
            for g in [g for g in groups if g & group]:
                groups.remove(g)
                group |= g
            groups.append(group)
    order = {p: k for k, p in enumerate(oracle.parts)}
    out = [tuple(sorted(g, key=order.__getitem__)) for g in groups]
    return None if sorted(map(sorted, out)) == before else out


def _named(spec: AssemblySpec, groups: list[tuple[str, ...]]) -> list[tuple[str, tuple[str, ...]]]:
    """Unit ids ``sub_<first member>`` (numbered if taken) for automatic units."""
    taken = set(spec.op_ids) | set(spec.part_ids) | {u for u, _ in spec.subassemblies}
    out = []
    for names in groups:
        uid, k = "sub_" + names[0], 2
        while uid in taken:
            uid, k = f"sub_{names[0]}_{k}", k + 1
        taken.add(uid)
        out.append((uid, names))
    return out


def unit_parts_of_line(spec: AssemblySpec, operations: Iterable[str]) -> list[list[str]]:
    """For each operation of a line, the parts it places (a unit's insertion: its members)."""
    members = unit_members(spec)
    by_id = {op.id: op for op in spec.operations}
    return [list(members.get(by_id[o].unit, by_id[o].parts)) for o in operations]


__all__ = [
    "build_with_units",
    "host_groups",
    "unit_members",
    "unit_parts_of_line",
    "with_subassemblies",
    "workspace_of",
]
