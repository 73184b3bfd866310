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
and
automatic detection when a part can never be inserted alone (:func:`build_with_units`): the
part and the parts it is engaged with (those it touches and that block it along some
direction, such as the flanged bearings pressed into a holder) enter together.
"""

from __future__ import annotations

from collections.abc import Iterable

from asp.spec import AssemblySpec, with_subassemblies

MAX_ROUNDS = 4
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


def engaged_group(oracle, p: int, base: int) -> set[int]:
    """Part ``p`` and the parts it touches that also block it along some direction."""
    from asp.feasibility import unpack_words

    contact = unpack_words(oracle.contact[p])
    blocking = 0
    for d in range(6):
        blocking |= unpack_words(oracle.blocked[p, d])
    group = {p}
    for j in range(len(oracle.parts)):
        if contact >> j & 1 and blocking >> j & 1 and j != base:
            group.add(j)
    return group


def build_with_units(spec: AssemblySpec, relations=None, **kwargs):
    """Build the state graph, adding a subassembly for each part that can never go in alone.

    When the assembly has no complete sequence, each root-cause part (an operation never
    done although ready somewhere) is grouped with the parts it is engaged with
    (:func:`engaged_group`), overlapping groups merge, and the graph is built again with
    those units (at most :data:`MAX_ROUNDS` rounds). The original error is raised if that
    does not help. Keyword arguments go to :func:`asp.state_graph.build_state_graph`.

    Returns
    -------
    StateGraph
        Its ``spec`` holds the units found (``spec.subassemblies``).
    """
    from asp.state_graph import build_state_graph, never_done

    first_error = None
    current = spec
    for _ in range(MAX_ROUNDS + 1):
        try:
            return build_state_graph(current, relations, **kwargs)
        except ValueError as exc:
            if relations is None or "infeasible assembly" not in str(exc):
                raise
            first_error = first_error or exc
            graph = build_state_graph(current, relations, **{**kwargs, "check": False})
            units = _new_units(graph, never_done(graph))
            if not units:
                raise first_error from None
            try:
                current = with_subassemblies(current, units)
            except ValueError:
                raise first_error from None
    raise first_error


def _new_units(graph, ops: list[int]) -> list[tuple[str, tuple[str, ...]]]:
    """Units grouping the parts of the never-done operations ``ops`` with their engaged parts."""
    model = graph.model
    spec, oracle = model.spec, model.oracle
    taken = {m for _, ms in spec.subassemblies for m in ms}
    placed_by = {p: op for op in spec.operations for p in op.parts}
    groups: list[set[int]] = []
    for i in ops:
        for p in model.part_lists[i]:
            if p >= len(spec.part_ids) and spec.part_ids:
                continue  # a unit's insertion
            group = engaged_group(oracle, p, oracle.base)
            names = {oracle.parts[j] for j in group}
            if len(group) < 2 or names & taken or not all(n in placed_by for n in names):
                continue
            merged = [g for g in groups if g & group]
            for g in merged:
                groups.remove(g)
                group |= g
            groups.append(group)
    out = []
    for group in groups:
        names = tuple(oracle.parts[j] for j in sorted(group))
        uid = "sub_" + names[0]
        k = 2
        while uid in set(spec.op_ids) | set(spec.part_ids):
            uid, k = f"sub_{names[0]}_{k}", k + 1
        out.append((uid, names))
    return out


def unit_parts_of_line(spec: AssemblySpec, operations: Iterable[str]) -> list[list[str]]:
    """For each operation of a line, the parts it places (a unit's insertion: its members)."""
    members = unit_members(spec)
    by_id = {op.id: op for op in spec.operations}
    return [list(members.get(by_id[o].unit, by_id[o].parts)) for o in operations]


__all__ = [
    "build_with_units",
    "engaged_group",
    "unit_members",
    "unit_parts_of_line",
    "with_subassemblies",
    "workspace_of",
]
