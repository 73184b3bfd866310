"""Interchangeable parts: identical choices do not multiply the states.

The reduced model of :mod:`asp.graph.precedences` (derived precedences and every
operation's reduced test, valid states) is where symmetries are looked for.

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
placement in a unit's workspace is tested against the members placed there only
(:mod:`asp.graph.precedences`). The insertions stay in place, so a symmetry maps each workspace
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
from dataclasses import replace

import numpy as np

from asp.graph.precedences import (
    TRUE,
    ReducedModel,
    bits,
    derive,
    reduced_model,
    with_derived_precedences,
)
from asp.spec import AssemblySpec


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
            for j in bits(near[i]):
                near[j] |= 1 << i
        after = [0] * n
        for i in range(n):
            for a in bits(m.must[i]):
                after[a] |= 1 << i
        self.relations = (near, list(m.must), after)
        # a unit's insertion is never moved (its members' placements are, within its
        # workspace)
        self.fixed = sum(1 << i for i, op in enumerate(spec.operations) if op.unit)
        self.workspace = m.workspace or (0,) * n

    def _map_ops(self, perm: dict[int, int], mask: int) -> int:
        out = 0
        for i in bits(mask):
            out |= 1 << perm.get(i, i)
        return out

    def _map_parts(self, perm: dict[int, int], mask: int) -> int:
        if mask == TRUE:
            return TRUE
        m = self.m
        out = 0
        for p in bits(mask):
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
            for i in bits(mask):
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
        return sorted(bits(block), key=lambda i: (bin(self.m.must[i] & block).count("1"), i))

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
                image = sum(1 << perm[i] for i in bits(block))
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
    model, why, _ = derive(spec, relations)
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
    :func:`asp.graph.state_keys.operation_model`'s ``loose``), the classes of blocks ordered,
    and those put in a fixed order at every position (``fixed``, for
    :attr:`asp.graph.state_keys.OperationModel.fixed`).

    The slack of position ``p`` of a class's blocks is ``s(p) = s(p - 1) + m(p)``, ``m(p)``
    the :func:`class_slack` of the operations at ``p`` (``s(-1) = 0``): the block to move,
    the first of those neither ahead nor running, has below it only blocks running
    their operation ``p`` (at most ``m(p)``) or still before ``p`` (at most ``s(p - 1)``:
    the rule held when it did its operation ``p - 1``, and the count only falls)."""
    model, why, _ = derive(spec, relations)
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
    instead (``(m, ids)``, :meth:`asp.graph.state_keys.OperationModel._loose_order`, the slack
    of :func:`_reduced`), so that two of them may still run at once: a fixed order would
    forbid it and change the concurrent game's W* (the CP-SAT schedule undoes a fixed
    order instead, :mod:`asp.graph.fixed_order`).
    It holds more states (the 26-part shear mold stand-in: 459,182 instead of 15,019).
    A class whose blocks are not chains (a shaft with its two bearings and a collar,
    three times around a drive) cannot be put in a fixed order by precedences; its first
    operations are chained when a block has one operation every other of it needs, and the
    state graph moves only the first of equal blocks
    (:meth:`asp.graph.state_keys.OperationModel.enabled`, pass the classes as
    ``operation_model(..., symmetric=...)``): the alternating game's values only.
    """
    model, why, _ = derive(spec, relations)
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
    from asp.graph.state_graph import build_state_graph
    from asp.graph.state_keys import operation_model

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
