"""Interchangeable parts: identical choices do not multiply the states.

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

A permutation ``sigma`` of the operations (and of their parts) is a *symmetry* when it maps
every operation's reduced test onto the image operation's (the same durations, agents,
tools and ``held``; ``sigma`` of its predecessors, contact, support and blocker family). Then
``sigma`` maps valid states and their feasible moves onto valid states and feasible moves of
the same cost, so it is an automorphism of the game restricted to completable states.

Symmetries are found as involutions swapping two operations of identical parts together with
the parts attached to them (:func:`_swap`): a dowel and the roller it carries are swapped with
another dowel and its roller; the rollers are found through their contacts. The operations
moved from one side form a *block*. A class of ``k`` blocks where every transposition is a
symmetry is acted on by the whole permutation group; when each block's operations are totally
ordered by the derived precedences (a valid state has a prefix of each block done), the states
whose blocks are sorted by prefix length (longest first) hold exactly one state of every orbit.
Those are the states in which, for every position ``i`` in the blocks, the ``i``-th operations
of the blocks are done in block order: chains of precedences (:func:`with_fixed_order`). From a
sorted state every move is mapped by a transposition of two blocks with the same prefix onto a
move of the sorted graph with the same cost and an isomorphic future, so TCT and W* are the
same (tested against the full graph), with far fewer states.

**Units.** A unit is one body of the main assembly: the main assembly sees its members only
once it is inserted, so in the main assembly's tests a member stands for the unit's part (a
guide pin touching one bushing of the upper half of a die set touches that half). A
placement in a unit's workspace is tested against the members placed there only, and any
member may go first into the empty workspace: its reduced test keeps only the members (with
the predecessors' parts there and the successors' not, and dominated blocker sets dropped),
derives only that a member blocking it along every direction left comes after it, and
proves nothing impossible. The insertions stay in place, so a symmetry maps each workspace
onto itself: alike bushings or screws of one workspace are interchangeable like alike parts
of the main assembly, and are ordered the same way.

**The concurrent game** runs two operations at once only if both orders are transitions, so
a fixed order of alike parts would forbid placing two of them together and change its W*.
A graph for the concurrent game (``reduced_state_graph(..., concurrent=True)``) keeps a
*loose* order instead: of a class of single operations that ``w`` workers may do, the
``j``-th may be done while at most ``w - 1`` of those
before it are not. Starting the first one neither done nor running is then always a move
(the others before it are running, at most ``w - 1``), it is the move any other start is
mapped onto by a symmetry fixing the state (done and running), and the count only falls as
operations are done, so a running one stays a transition whichever finishes first: both
games keep their values. Blocks of several operations (a dowel with its roller) are ordered
position by position, each position with the slack of the one before it plus its own (a
block may be behind lower ones by what the position before allowed). The classes of blocks
that are not chains (moved first of equals) keep the alternating game's values only. A loose
order holds many more states (the 26-part shear mold stand-in: 459,182 instead of 15,019; a
70-part drive with 20 pins and rollers over 20 million instead of 697,641), so the pipeline
builds it for the concurrent turn model only.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass, replace

import numpy as np

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


def _bits(mask: int):
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
    return _derive(spec, relations)[0]


def infeasibility(spec: AssemblySpec, relations) -> str:
    """Why the derived precedences prove that no complete sequence exists ("" if they do not):
    a part with nothing to touch or rest on or no direction left once its predecessors are
    in, or a cycle of precedences."""
    return _derive(spec, relations)[1]


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
    return _derive(spec, relations)[2]


def _derive(spec: AssemblySpec, relations) -> tuple[ReducedModel | None, str, Refutation | None]:
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
            for a in _bits(must[i]):
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
    """What :func:`_derive` reads of the insertion oracle, per operation (bitsets over the
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
        for i in _bits(ops):
            if self.part_of[i] >= 0:
                out |= 1 << self.part_of[i]
        return out

    def ops_of(self, parts: int) -> int:
        """The operations placing the parts of ``parts``."""
        out = 0
        for p in _bits(parts):
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
    room = {m: mask for _, mask in units for m in _bits(mask)}
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
    for r in _bits(t.ops_of(common & ~t.initial) if common > 0 else 0):
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
        return all(ancestors[r] & b for r in _bits(m))

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
    for p in _bits(looked):
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
            for a in _bits(m):
                full |= out[a]
            if full != m:
                out[i] = full
                changed = True
    return out


def _signature(spec: AssemblySpec, i: int):
    op = spec.operations[i]
    shape = None
    if op.parts:
        record = next((p for p in spec.parts if p.id == op.parts[0]), None)
        shape = getattr(record, "shape", None) or None
    return (
        tuple(sorted(op.durations)),
        tuple(sorted(op.ranges)),
        op.requires,
        op.sets,
        op.held,
        shape,
    )


class _Symmetry:
    """Checks and builds operation permutations that are symmetries of a reduced model."""

    def __init__(self, spec: AssemblySpec, model: ReducedModel):
        self.spec, self.m = spec, model
        n = len(spec.operations)
        self.n = n
        self.sig = [_signature(spec, i) for i in range(n)]
        m = model
        self.colour = [
            (
                self.sig[i],
                bin(m.must[i]).count("1"),
                -1 if m.contact[i] == TRUE else bin(m.contact[i]).count("1"),
                -1 if m.support[i] == TRUE else bin(m.support[i]).count("1"),
                tuple(sorted(bin(s).count("1") for s in m.family[i])),
                m.workspace[i] if m.workspace else 0,
            )
            for i in range(n)
        ]
        # relations to propagate a swap along: the raw contacts and supports (both ways),
        # the derived predecessors and successors
        near = [m.raw_near[i] for i in range(n)]
        for i in range(n):
            for j in _bits(near[i]):
                near[j] |= 1 << i
        after = [0] * n
        for i in range(n):
            for a in _bits(m.must[i]):
                after[a] |= 1 << i
        self.relations = (near, list(m.must), after)
        # a unit's insertion is never moved (its members' placements are, within its
        # workspace)
        self.fixed = sum(1 << i for i, op in enumerate(spec.operations) if op.unit)
        self.workspace = m.workspace or (0,) * n

    def _map_ops(self, perm: dict[int, int], mask: int) -> int:
        out = 0
        for i in _bits(mask):
            out |= 1 << perm.get(i, i)
        return out

    def _map_parts(self, perm: dict[int, int], mask: int) -> int:
        if mask == TRUE:
            return TRUE
        m = self.m
        out = 0
        for p in _bits(mask):
            q = m.part_of[perm[m.op_of[p]]] if p in m.op_of and m.op_of[p] in perm else p
            out |= 1 << q
        return out

    def breakers(self, perm: dict[int, int]) -> list[int]:
        """The operations whose reduced tests ``perm`` (identity elsewhere) does not map onto
        their image's: none for a symmetry."""
        m = self.m
        if any(
            self.sig[i] != self.sig[j] or self.workspace[i] != self.workspace[j]
            for i, j in perm.items()
        ):  # the units stay in place, so a placement stays in its workspace
            return list(perm)
        # only operations whose tests mention a moved one can change
        moved_parts = sum(1 << m.part_of[i] for i in perm if m.part_of[i] >= 0)
        moved_ops = sum(1 << i for i in perm)
        out = []
        for i in range(self.n):
            j = perm.get(i, i)
            if i == j:
                touches = m.must[i] & moved_ops or any(
                    t != TRUE and t & moved_parts for t in (m.contact[i], m.support[i])
                )
                if not touches and not any(s & moved_parts for s in m.family[i]):
                    continue
            if (
                self._map_ops(perm, m.must[i]) != m.must[j]
                or self._map_parts(perm, m.contact[i]) != m.contact[j]
                or self._map_parts(perm, m.support[i]) != m.support[j]
                or frozenset(self._map_parts(perm, s) for s in m.family[i]) != m.family[j]
            ):
                out.append(i)
        return out

    def swap(self, a: int, b: int) -> tuple[dict[int, int], int] | None:
        """An involution swapping ``a`` and ``b`` and the operations attached to them, and
        the block of ``a`` (the operations it moves on ``a``'s side); None if none found."""
        perm = {a: b, b: a}
        if (1 << a | 1 << b) & self.fixed:
            return None
        if not self.breakers(perm):
            return perm, 1 << a
        side = {a: 0, b: 1}
        queue = [a, b]
        while queue:
            x = queue.pop()
            y = perm[x]
            for rel in self.relations:
                if not self._pair_up(rel[x] & ~rel[y], rel[y] & ~rel[x], x, y, perm, side, queue):
                    return None
        if self.breakers(perm) or any(self.fixed >> i & 1 for i in perm):
            return None
        return perm, sum(1 << i for i, s in side.items() if s == 0)

    def _pair_up(self, mine, theirs, x, y, perm, side, queue) -> bool:
        """Extend ``perm`` so that it maps ``mine`` onto ``theirs`` (False: no unique way)."""
        by_colour: dict = defaultdict(lambda: ([], []))
        for k, mask in ((0, mine), (1, theirs)):
            for i in _bits(mask):
                by_colour[self.colour[i]][k].append(i)
        for xs0, ys0 in by_colour.values():
            xs = [i for i in xs0 if perm.get(i) not in ys0]
            ys = [i for i in ys0 if perm.get(i) not in xs0]
            if not xs and not ys:
                continue
            if len(xs) != 1 or len(ys) != 1:
                return False
            u, v = xs[0], ys[0]
            if u in perm or v in perm:
                return False
            perm[u], perm[v] = v, u
            side[u], side[v] = side[x], side[y]
            queue += [u, v]
        return True

    def block_order(self, block: int) -> list[int]:
        """The block's operations in derived-precedence order (by how many of the block come
        before each, then by index): a chain when :meth:`is_chain`."""
        return sorted(_bits(block), key=lambda i: (bin(self.m.must[i] & block).count("1"), i))

    def is_chain(self, order: list[int]) -> bool:
        """Whether each operation of ``order`` needs every one before it."""
        block = sum(1 << i for i in order)
        return all(bin(self.m.must[i] & block).count("1") == k for k, i in enumerate(order))


def interchangeable_blocks(
    spec: AssemblySpec, relations, *, chains_only: bool = True
) -> list[list[list[str]]]:
    """Classes of interchangeable blocks of operations (ids), each block in its
    derived-precedence order.

    A class ``[[a1, a2], [b1, b2], ...]`` says: every transposition of two of its blocks
    (``a1 <-> b1`` together with ``a2 <-> b2``) is a symmetry of the reduced model. With
    ``chains_only`` (default) only classes whose blocks are chains (each block's operations
    are done in that order in every complete sequence). Blocks of different classes are
    disjoint.
    """
    model = reduced_model(spec, relations)
    if model is None:
        return []
    sym = _Symmetry(spec, model)
    base = model.op_of.get(_base_index(spec, model), -1)
    groups: dict = defaultdict(list)
    for i in range(sym.n):
        if model.part_of[i] >= 0 and i != base and not spec.operations[i].unit:
            groups[sym.colour[i]].append(i)
    used = 0
    out = []
    ids = [op.id for op in spec.operations]
    for members in groups.values():
        left = [i for i in members if not used >> i & 1]
        while len(left) > 1:
            first, rest = left[0], left[1:]
            blocks, block0, order0 = [], None, None
            taken = 0
            for j in rest:
                if used >> j & 1 or taken >> j & 1:
                    continue
                found = sym.swap(first, j)
                if found is None:
                    continue
                perm, block = found
                if block0 is None:
                    order0 = sym.block_order(block)
                    if block & used:
                        break
                    block0 = block
                elif block != block0:
                    continue
                image = sum(1 << perm[i] for i in _bits(block))
                if image & (used | taken | block0):
                    continue
                blocks.append([perm[i] for i in order0])
                taken |= image
            if blocks and (sym.is_chain(order0) or not chains_only):
                out.append([[ids[i] for i in order0]] + [[ids[i] for i in b] for b in blocks])
                used |= block0 | taken
            left = [i for i in rest if not (used | taken) >> i & 1]
    return out


def _base_index(spec: AssemblySpec, model: ReducedModel) -> int:
    """The oracle index of the base part."""
    for i, op in enumerate(spec.operations):
        if op.parts and op.parts[0] == spec.base_part:
            return model.part_of[i]
    return -1


def interchangeable_classes(spec: AssemblySpec, relations) -> list[list[str]]:
    """Classes (two or more operation ids, in spec order) of interchangeable operations: the
    first operation of each block of :func:`interchangeable_blocks` (or, for a spec the
    reduced model does not apply to, the operations an exact swap of table rows exchanges)."""
    model, why, _ = _derive(spec, relations)
    if model is None:
        return [] if why else _exact_classes(spec, relations)
    return [[b[0] for b in cls] for cls in interchangeable_blocks(spec, relations)]


def _exact_classes(spec: AssemblySpec, relations) -> list[list[str]]:
    """Classes of operations whose parts an exact swap of the relation tables' rows and
    columns exchanges (the test for specs :func:`reduced_model` does not apply to:
    subassemblies, operations placing several parts)."""
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
    """``spec`` reduced for the state graph, with the full graph's TCT and W* (the
    alternating game).

    With the reduced model (:func:`reduced_model`): its derived precedences become ``after``
    (:func:`with_derived_precedences`; only dead ends go) and, for every class of
    :func:`interchangeable_blocks`, the ``i``-th operations of its blocks are chained in block
    order. Otherwise the classes of an exact swap are chained. A spec the derived precedences
    prove infeasible is returned as it is (the state graph names the cause).
    """
    return _reduced(spec, relations, concurrent=False)[0]


def _reduced(spec: AssemblySpec, relations, concurrent: bool):
    """:func:`reduce_interchangeable` and, with ``concurrent``, the chains of the classes
    of blocks kept in a loose order instead, with their slack (``(m, ids)`` for
    :func:`asp.graph.feasibility.operation_model`'s ``loose``), the classes of blocks ordered,
    and those put in a fixed order at every position (``fixed``, for
    :attr:`asp.graph.feasibility.OperationModel.fixed`).

    The slack of position ``p`` of a class's blocks is ``s(p) = s(p - 1) + m(p)``, ``m(p)``
    the :func:`class_slack` of the operations at ``p`` (``s(-1) = 0``): the block to move,
    the first of those neither ahead nor running, has below it only blocks running
    their operation ``p`` (at most ``m(p)``) or still before ``p`` (at most ``s(p - 1)``:
    the rule held when it did its operation ``p - 1``, and the count only falls)."""
    model, why, _ = _derive(spec, relations)
    if model is None:
        if why:
            return spec, [], [], []
        base, classes = spec, [[[o] for o in cls] for cls in _exact_classes(spec, relations)]
    else:
        base = with_derived_precedences(spec, relations)
        classes = interchangeable_blocks(spec, relations)
    chains, loose, fixed = [], [], []
    for cls in classes:
        slack = 0
        for position in range(len(cls[0])):
            chain = [block[position] for block in cls]
            if concurrent:  # lower blocks behind it at the position before, or running
                slack = min(slack + class_slack(spec, chain), len(chain) - 1)
            if slack:
                loose.append((slack, chain))
            else:
                chains.append(chain)
        if not slack:  # the slack only grows with the position: every position is fixed
            fixed.append(cls)
    return with_fixed_order(base, chains), loose, classes, fixed


def class_slack(spec: AssemblySpec, ids: list[str]) -> int:
    """How many of the interchangeable operations ``ids`` may run besides one starting: one
    less than the workers who may do them (an agent of side ``any`` is a robot and a person
    in the concurrent game), at most ``len(ids) - 1``."""
    sides = {a.name: a.side for a in spec.agents}
    agents = {a for o in ids for a, _ in spec.operation(o).durations}
    workers = sum(2 if sides.get(a) == "any" else 1 for a in agents)
    return max(0, min(workers, len(ids)) - 1)


def symmetry_reduction(
    spec: AssemblySpec, relations, *, concurrent: bool = False
) -> tuple[
    AssemblySpec,
    list[list[list[str]]],
    list[tuple[int, list[str]]],
    list[list[list[str]]],
    list[list[list[str]]],
]:
    """The reduction of interchangeable parts for a state graph.

    Returns the reduced spec, the classes whose blocks are not chains, with
    ``concurrent`` the chains kept in a loose order with their slack, and every class of
    interchangeable blocks the reduction uses (chains first, then the others; each block
    in its position order): the symmetries a runtime maps a physical observation by
    (:func:`reduced_state_graph` records them on the graph's model).
    Last, the classes of blocks in a fixed order (the ``i``-th operations of the blocks
    chained in block order at every position ``i``; ``operation_model(..., fixed=...)``):
    the schedule stage undoes that order (:mod:`asp.graph.fixed_order`).

    Classes of blocks that are chains are put in a fixed order position by position
    (:func:`reduce_interchangeable`): the alternating game keeps its values. With
    ``concurrent`` (a graph for the concurrent game too) they keep a *loose* order
    instead (``(m, ids)``, :meth:`asp.graph.feasibility.OperationModel._loose_order`, the slack
    of :func:`_reduced`), so that two of them may still run at once: a fixed order would
    forbid it and change the concurrent game's W* (the CP-SAT schedule undoes a fixed
    order instead, :mod:`asp.graph.fixed_order`).
    It holds more states (the 26-part shear mold stand-in: 459,182 instead of 15,019).
    A class whose blocks are not chains (a shaft with its two bearings and a collar,
    three times around a drive) cannot be put in a fixed order by precedences; its first
    operations are chained when a block has one operation every other of it needs, and the
    state graph moves only the first of equal blocks
    (:meth:`asp.graph.feasibility.OperationModel.enabled`, pass the classes as
    ``operation_model(..., symmetric=...)``): the alternating game's values only.
    """
    model, why, _ = _derive(spec, relations)
    reduced, loose, ordered, fixed = _reduced(spec, relations, concurrent=concurrent)
    if model is None:
        return reduced, [], loose, ordered, fixed
    index = {op.id: i for i, op in enumerate(spec.operations)}
    chains, others = [], []
    for cls in interchangeable_blocks(spec, relations, chains_only=False):
        block = sum(1 << index[o] for o in cls[0])
        if all(bin(model.must[index[o]] & block).count("1") == k for k, o in enumerate(cls[0])):
            continue  # a chain: _reduced ordered it
        others.append(cls)
        root = index[cls[0][0]]
        if all(model.must[index[o]] >> root & 1 for o in cls[0][1:]):
            chains.append([b[0] for b in cls])
    return with_fixed_order(reduced, chains), others, loose, [*ordered, *others], fixed


def reduced_state_graph(spec: AssemblySpec, relations, *, concurrent: bool = False, **kwargs):
    """The state graph of :func:`symmetry_reduction` (the full graph's TCT and W*; with
    ``concurrent``, also its concurrent game's W*(k) and makespans), without the states
    that are stuck (dead ends, see ``build_state_graph(drop_stuck=...)``).

    Keyword arguments go to :func:`asp.graph.state_graph.build_state_graph`; returns None when
    there is nothing to reduce (build the full graph). The graph's
    ``model.interchangeable`` holds the classes of interchangeable blocks used (the plan
    file's ``interchangeable``: a runtime maps an alike physical operation onto the
    canonical one the graph keeps).
    """
    from asp.graph.feasibility import operation_model
    from asp.graph.state_graph import build_state_graph

    reduced, others, loose, classes, fixed = symmetry_reduction(
        spec, relations, concurrent=concurrent
    )
    if reduced is spec and not others and not loose:
        return None
    model = operation_model(
        reduced, relations, symmetric=others, loose=loose, interchangeable=classes, fixed=fixed
    )
    return build_state_graph(reduced, relations, model=model, drop_stuck=True, **kwargs)


def reduce_exact(spec: AssemblySpec, relations) -> AssemblySpec:
    """``spec`` with the classes of an exact swap of table rows chained (for specs with
    subassemblies, where :func:`reduce_interchangeable` keeps to this test)."""
    return with_fixed_order(spec, _exact_classes(spec, relations))


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
        for a in _bits(model.must[i]):
            implied |= model.must[a]
        direct = [ids[a] for a in _bits(model.must[i] & ~implied) if ids[a] not in op.after]
        ops.append(replace(op, after=(*op.after, *direct)) if direct else op)
    return replace(spec, operations=tuple(ops))
