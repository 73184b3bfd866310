"""Derived precedences: what every complete sequence keeps, and the proofs that none exists.

Inserting the part ``p`` of operation ``o`` into the assembled set ``S`` is feasible iff its
predecessors are done, ``p`` touches ``S``, rests on ``S`` (unless held) and some direction
``d`` is free: ``B(p, d) & S`` is empty, with ``B(p, d)`` the parts blocking ``p`` along ``d``
(:mod:`asp.graph.feasibility`). Only the *family* of blocker sets matters, not which direction
carries which set, and much of it never decides anything:

1. **Derived precedences** (:func:`reduced_model`): operation ``a`` must come before ``o`` in
   every complete sequence when it is an explicit or transitive predecessor, places the base
   part, places the only part ``o``'s part can touch or rest on, or when ``o``'s part blocks
   ``a``'s part along every direction ``a`` may still use (once ``o`` is in, ``a`` could never
   follow). These are iterated to a fixpoint. Every state from which the assembly can be
   completed respects them (call such states *valid*); the game drops the others.
2. **Reduced tests**: for ``o`` in a valid state, the parts of its predecessors are there and
   the parts of its successors are not. So a blocker set holding a predecessor's part is a
   direction that is never free (dropped), successors' parts are removed from every set,
   a set that contains another is dropped (it is free only when the smaller one is), and a
   contact or support set meeting a predecessor's part is always satisfied.

The symmetry reduction (:mod:`asp.graph.symmetry`) stands on this reduced model.

**Units.** A placement in a unit's workspace is tested against the members placed there
only, and any member may go first into the empty workspace: its reduced test keeps only the
members (with the predecessors' parts there and the successors' not, and dominated blocker
sets dropped), derives only that a member blocking it along every direction left comes
after it, and proves nothing impossible.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from asp.spec import AssemblySpec

TRUE = -1
"""A contact or support test that always holds in valid states (bitset stand-in)."""


@dataclass(frozen=True)
class ReducedModel:
    """The reduced insertion tests of a spec's operations (bitsets as Python ints).

    Attributes
    ----------
    part_of : tuple of int
        Per operation, its part index in the oracle (-1: places no part).
    op_of : dict of int to int
        Part index -> operation placing it.
    must : tuple of int
        Per operation, the operations that precede it in every complete sequence (bitset).
    contact, support : tuple of int
        Per operation, the parts its part may touch / rest on in a valid state (bitset), or
        :data:`TRUE` when a predecessor's part guarantees it.
    family : tuple of frozenset of int
        Per operation, the minimal blocker sets of its allowed directions in valid states.
    raw_near : tuple of int
        Per operation, the operations placing what it may touch or rest on (bitset).
    workspace : tuple of int
        Per operation, the members of the unit whose workspace it builds in (bitset; 0: the
        main assembly). Its tests look at those members only and hold in the empty
        workspace; in the main assembly's tests a unit's part stands for its members.
    """

    part_of: tuple[int, ...]
    op_of: dict[int, int]
    must: tuple[int, ...]
    contact: tuple[int, ...]
    support: tuple[int, ...]
    family: tuple[frozenset[int], ...]
    raw_near: tuple[int, ...] = ()
    workspace: tuple[int, ...] = ()


def bits(mask: int):
    """The indices of the set bits of ``mask``, lowest first."""
    while mask:
        low = mask & -mask
        yield low.bit_length() - 1
        mask ^= low


def _applicable(spec: AssemblySpec, relations) -> bool:
    """The reduction's preconditions: geometry, a base, one part per operation (or a unit's
    insertion)."""
    if relations is None or not spec.constraints.topological or not spec.base_part:
        return False
    placed = [p for op in spec.operations if not op.unit for p in op.parts]
    return all(len(op.parts) <= 1 or op.unit for op in spec.operations) and len(placed) == len(
        set(placed)
    )


def reduced_model(spec: AssemblySpec, relations) -> ReducedModel | None:
    """The derived precedences and reduced tests of ``spec`` (None: not applicable).

    None when the spec has subassemblies, an operation placing several parts, no base part or
    no geometry, or when the derived precedences show the assembly cannot be completed
    (:func:`infeasibility`): the state graph then reports why.
    """
    return derive(spec, relations)[0]


def infeasibility(spec: AssemblySpec, relations) -> str:
    """Why the derived precedences prove that no complete sequence exists ("" if they do not):
    a part with nothing to touch or rest on or no direction left once its predecessors are
    in, or a cycle of precedences."""
    return derive(spec, relations)[1]


@dataclass(frozen=True)
class Refutation:
    """A proof from the derived precedences that no complete sequence exists.

    Attributes
    ----------
    why : str
        One line (:func:`infeasibility`).
    operation : str
        The operation it names.
    parts : tuple of str
        The parts its failing test looks at before the derived precedences leave some out
        (what it could touch, rest on, or is blocked by), or the parts of the operations of a
        cycle of precedences: what a different grouping into units could change.
    """

    why: str
    operation: str
    parts: tuple[str, ...]


def refutation(spec: AssemblySpec, relations) -> Refutation | None:
    """The proof of :func:`infeasibility` with what it involves (None: no proof)."""
    return derive(spec, relations)[2]


def derive(spec: AssemblySpec, relations) -> tuple[ReducedModel | None, str, Refutation | None]:
    """:func:`reduced_model`, :func:`infeasibility` and :func:`refutation` in one pass.

    From the spec's own precedences (and the base part first), to a fixed point: close them
    transitively (a cycle is a proof), then reduce each operation's tests under them
    (:func:`_reduced_row`, which may add precedences or find a proof).
    """
    if not _applicable(spec, relations):
        return None, "", None
    t = _tests(spec, relations)
    n_ops = len(spec.operations)
    must = _first_must(spec, t)
    while True:
        must = _closure(must)
        cycle = [i for i in range(n_ops) if must[i] >> i & 1]
        if cycle:
            why = f"operation {spec.operations[cycle[0]].id} must precede itself"
            looked = t.parts_of(sum(1 << i for i in cycle)) & ~t.initial
            return None, why, _refuted(spec, t.oracle, why, cycle[0], looked)
        ancestors = {
            p: (t.parts_of(must[t.op_of[p]]) if p in t.op_of else t.initial) | 1 << p
            for p in range(len(t.oracle.parts))
        }
        after = [0] * n_ops
        for i in range(n_ops):
            for a in bits(must[i]):
                after[a] |= 1 << i
        rows = []
        changed = False
        for i in range(n_ops):
            row = _reduced_row(spec, t, i, must, after, ancestors)
            if row.failure is not None:
                why, looked = row.failure
                return None, why, _refuted(spec, t.oracle, why, i, looked)
            rows.append(row)
            changed |= row.changed
        if not changed:
            model = ReducedModel(
                part_of=t.part_of,
                op_of=t.op_of,
                must=tuple(must),
                contact=tuple(r.contact for r in rows),
                support=tuple(r.support for r in rows),
                family=tuple(r.family for r in rows),
                raw_near=tuple(t.ops_of(t.contact[i] | t.support[i]) for i in range(n_ops)),
                workspace=t.workspace,
            )
            return model, "", None


@dataclass(frozen=True)
class _Tests:
    """What :func:`derive` reads of the insertion oracle, per operation (bitsets over the
    oracle's parts).

    ``raw_*``: the oracle's rows (what the part may touch, rest on, is blocked by along each
    allowed direction); ``contact``, ``support``, ``blocked``: the same as the operation's
    test sees them (its workspace's members only, or the main assembly's parts with a unit
    for its members). ``initial``: the base part when no operation places it; ``absent``:
    the parts no operation places.
    """

    oracle: object
    part_of: tuple[int, ...]
    workspace: tuple[int, ...]
    op_of: dict[int, int]
    initial: int
    absent: int
    raw_contact: tuple[int, ...]
    raw_support: tuple[int, ...]
    raw_blocked: tuple[tuple[int, ...], ...]
    contact: tuple[int, ...]
    support: tuple[int, ...]
    blocked: tuple[tuple[int, ...], ...]
    held: tuple[bool, ...]

    def parts_of(self, ops: int) -> int:
        """The parts the operations of ``ops`` place, with ``initial``."""
        out = self.initial
        for i in bits(ops):
            if self.part_of[i] >= 0:
                out |= 1 << self.part_of[i]
        return out

    def ops_of(self, parts: int) -> int:
        """The operations placing the parts of ``parts``."""
        out = 0
        for p in bits(parts):
            if p in self.op_of:
                out |= 1 << self.op_of[p]
        return out


def _tests(spec: AssemblySpec, relations) -> _Tests:
    """The oracle's rows of ``spec``'s operations (:class:`_Tests`)."""
    from asp.graph.feasibility import insertion_oracle, unpack_words

    oracle = insertion_oracle(spec, relations)
    pidx = {p: k for k, p in enumerate(oracle.parts)}
    # a unit is one body of the main assembly (its oracle row ORs its members'): the main
    # assembly sees its members only once it is inserted, so in the tests of the main
    # assembly a member stands for its unit (:func:`_as_units`); a placement in a unit's
    # workspace is tested against the unit's members placed there only (any member may
    # go first into the empty workspace)
    units = [(pidx[u], sum(1 << pidx[m] for m in ms)) for u, ms in spec.subassemblies]
    room = {m: mask for _, mask in units for m in bits(mask)}
    part_of = tuple(
        pidx[op.unit] if op.unit else (pidx[op.parts[0]] if op.parts else -1)
        for op in spec.operations
    )
    workspace = tuple(
        room.get(p, 0) if not op.unit else 0 for p, op in zip(part_of, spec.operations, strict=True)
    )
    op_of = {p: i for i, p in enumerate(part_of) if p >= 0}
    base = oracle.base
    initial = 0 if base in op_of or base < 0 else 1 << base
    absent = ((1 << len(oracle.parts)) - 1) & ~initial & ~sum(1 << p for p in op_of)
    raw_contact = tuple(unpack_words(oracle.contact[p]) if p >= 0 else 0 for p in part_of)
    raw_support = tuple(unpack_words(oracle.support[p]) if p >= 0 else 0 for p in part_of)
    raw_blocked = tuple(
        tuple(unpack_words(oracle.blocked[p, d]) for d in range(6) if oracle.directions[d])
        if p >= 0
        else ()
        for p in part_of
    )

    def seen(i: int, mask: int) -> int:
        """``mask`` as operation ``i``'s test sees it: its workspace's members, or the
        main assembly's parts with the units for their members."""
        return mask & workspace[i] if workspace[i] else _as_units(mask, units)

    return _Tests(
        oracle=oracle,
        part_of=part_of,
        workspace=workspace,
        op_of=op_of,
        initial=initial,
        absent=absent,
        raw_contact=raw_contact,
        raw_support=raw_support,
        raw_blocked=raw_blocked,
        contact=tuple(seen(i, m) for i, m in enumerate(raw_contact)),
        support=tuple(seen(i, m) for i, m in enumerate(raw_support)),
        blocked=tuple(tuple(seen(i, m) for m in masks) for i, masks in enumerate(raw_blocked)),
        held=tuple(op.held or not oracle.stability for op in spec.operations),
    )


def _first_must(spec: AssemblySpec, t: _Tests) -> list[int]:
    """Per operation, the operations the spec puts before it (bitset), with the base part's
    placement before every placement in the main assembly."""
    index = {op.id: i for i, op in enumerate(spec.operations)}
    must = [sum(1 << index[a] for a in op.after) for op in spec.operations]
    base = t.oracle.base
    if base in t.op_of:
        b = t.op_of[base]
        for i in range(len(must)):
            if i != b and t.part_of[i] >= 0 and not t.workspace[i]:
                must[i] |= 1 << b
    return must


@dataclass(frozen=True)
class _Row:
    """An operation's reduced tests (:func:`_reduced_row`): contact and support masks
    (``TRUE``: always passes), the family of blocking sets, whether it added precedences,
    and ``failure``, ``(why, looked)`` when it can never be done."""

    contact: int
    support: int
    family: frozenset[int]
    changed: bool = False
    failure: tuple[str, int] | None = None


def _reduced_row(
    spec: AssemblySpec, t: _Tests, i: int, must: list[int], after: list[int], ancestors: dict
) -> _Row:
    """Operation ``i``'s tests reduced under the derived precedences ``must`` (its
    successors ``after``; ``ancestors``: per part, the parts always there before it and
    itself). Adds to ``must`` what they prove: the only part it can touch or rest on comes
    first; a part blocking it along every direction left comes after it."""
    p = t.part_of[i]
    if p < 0 or p == t.oracle.base:  # no part, or the base part (placed first, into nothing)
        return _Row(TRUE, TRUE, frozenset({0}))
    there, never = t.parts_of(must[i]), (t.parts_of(after[i]) & ~t.initial) | t.absent
    room = t.workspace[i]
    if room:
        # in a unit's workspace: only its members count, and nothing is proved
        # impossible or needed first (any member may go first into it)
        there, never = there & room, never & room
    tests = [
        TRUE if mask == TRUE or mask & there else mask & ~never
        for mask in (t.contact[i], TRUE if t.held[i] else t.support[i])
    ]
    # a set holding every part it may touch (or rest on) is never free
    sets = {b & ~never for b in t.blocked[i] if not b & there}
    changed = False
    if room:  # a set holding another is free only when that one is
        family = frozenset(b for b in sets if not any(s != b and s & b == s for s in sets))
    else:
        family = _free_family(sets, tests, ancestors)
        why, test = _never(spec, i, tests, family)
        if why:
            looked = (t.raw_contact[i], t.raw_support[i], _union(t.raw_blocked[i]))[test]
            return _Row(tests[0], tests[1], family, failure=(why, looked))
        # the only part it can touch or rest on comes first
        for mask in tests:
            if mask not in (TRUE, 0) and mask & (mask - 1) == 0:
                q = t.ops_of(mask)
                if q and not must[i] & q:
                    must[i] |= q
                    changed = True
    # a part blocking it along every direction left comes after it
    common = ~0
    for s in family:
        common &= s
    for r in bits(t.ops_of(common & ~t.initial) if common > 0 else 0):
        if not must[r] >> i & 1:
            must[r] |= 1 << i
            changed = True
    return _Row(tests[0], tests[1], family, changed)


def _free_family(sets: set[int], tests: list[int], ancestors: dict) -> frozenset[int]:
    """The blocking sets of an operation in the main assembly that can still be free: a set
    holding an ancestor (or itself) of every part it may touch or rest on is never free; a
    set holding an ancestor of every part of another set is free only when that one is
    (valid states hold the ancestors of what they hold)."""

    def covers(b: int, m: int) -> bool:
        """Every part of ``m`` has an ancestor (or itself) in ``b``."""
        return all(ancestors[r] & b for r in bits(m))

    need = [m for m in tests if m != TRUE]
    sets = {b for b in sets if not any(covers(b, m) for m in need)}
    return frozenset(b for b in sets if not any(covers(b, m) and not covers(m, b) for m in sets))


def _never(spec: AssemblySpec, i: int, tests: list[int], family: frozenset[int]) -> tuple[str, int]:
    """Why operation ``i`` can never be done once its predecessors are ("" if it can), and
    the test that fails (0 contact, 1 support, 2 free direction)."""
    op = spec.operations[i]
    what = f"unit {op.unit}" if op.unit else f"part {op.parts[0]} (operation {op.id})"
    if tests[0] == 0:
        return f"{what} touches nothing that can be there before it", 0
    if tests[1] == 0:
        return f"{what} rests on nothing that can be there before it", 1
    if not family:
        why = f"{what} is blocked along every direction by parts that must be there before it"
        return why, 2
    return "", -1


def _refuted(spec: AssemblySpec, oracle, why: str, i: int, looked: int) -> Refutation:
    """The :class:`Refutation` naming operation ``i`` and the parts of ``looked`` (a unit's
    row stands for its members)."""
    members = dict(spec.subassemblies)
    parts: list[str] = []
    for p in bits(looked):
        name = oracle.parts[p]
        parts.extend(members.get(name, (name,)))
    return Refutation(why, spec.operations[i].id, tuple(dict.fromkeys(parts)))


def _as_units(mask: int, units: list[tuple[int, int]]) -> int:
    """``mask`` with the members of each unit ``(unit part, members mask)`` replaced by the
    unit's part: the main assembly holds a unit's members exactly when it holds the unit."""
    for unit, members in units:
        if mask & members:
            mask = mask & ~members | 1 << unit
    return mask


def _union(masks) -> int:
    out = 0
    for m in masks:
        out |= m
    return out


def _closure(must: list[int]) -> list[int]:
    """Transitive closure of the predecessor bitsets."""
    out = list(must)
    changed = True
    while changed:
        changed = False
        for i, m in enumerate(out):
            full = m
            for a in bits(m):
                full |= out[a]
            if full != m:
                out[i] = full
                changed = True
    return out


def with_waits(spec: AssemblySpec, wait: dict[str, tuple[str, ...]]) -> AssemblySpec:
    """``spec`` with each operation ``o`` of ``wait`` also after ``wait[o]`` (``after``, each
    predecessor once): precedences added, so the state graph only loses sequences."""
    ops = tuple(
        replace(op, after=tuple(dict.fromkeys((*op.after, *wait[op.id]))))
        if wait.get(op.id)
        else op
        for op in spec.operations
    )
    return replace(spec, operations=ops)


def with_derived_precedences(spec: AssemblySpec, relations) -> AssemblySpec:
    """``spec`` with the derived precedences of :func:`reduced_model` as ``after`` (only the
    direct ones: a predecessor implied by another is left out). Every completable state keeps
    them, so the graph loses only dead ends."""
    model = reduced_model(spec, relations)
    if model is None:
        return spec
    ids = [op.id for op in spec.operations]
    ops = []
    for i, op in enumerate(spec.operations):
        implied = 0
        for a in bits(model.must[i]):
            implied |= model.must[a]
        direct = [ids[a] for a in bits(model.must[i] & ~implied) if ids[a] not in op.after]
        ops.append(replace(op, after=(*op.after, *direct)) if direct else op)
    return replace(spec, operations=tuple(ops))
