"""Subassemblies: parts built in a workspace of their own and inserted as one rigid unit.

DESIGN.md ("Parts and subassemblies from CAD"). A unit ``U`` with member parts ``M``:

- the operations placing ``M`` (each placing members only) form the unit's workspace: each is
  tested against the members already placed there, not against the main assembly (the first
  member stands on the fixture, as the base part does);
- one *insertion operation*, id ``U``, inserts the finished unit into the main assembly
  (its predecessors: every member operation). It is tested as one rigid body: ``U`` is free
  along ``d`` from ``S`` iff every member is free along ``d`` from every part of ``S``;
  touches iff some member touches; is supported iff some member is (the pairwise relations
  ORed over the members, :func:`asp.graph.feasibility.insertion_oracle`). Its duration for an
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

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, replace

import numpy as np

from asp.errors import InfeasibleAssembly, SpecError, StateLimit
from asp.spec import AssemblySpec, with_subassemblies

MAX_ROUNDS = 8
"""Rounds of automatic detection (each adds the units of the root causes found)."""
PROVED_ROUND_STATES = 500_000
"""A round of automatic units whose failure the derived precedences prove builds its graph
(for the stuck operations) up to this many states; beyond, the operation the proof names
stands for them (a clutch's pressure plate held by its 13 pins: 15.7M states otherwise)."""
MAX_WORKSPACE_PRODUCT = 64
"""Beyond this product of ``members + 1`` over the units, they are built one after another
(:func:`built_in_turn`)."""


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
    from asp.graph.feasibility import unpack_words

    contact = unpack_words(oracle.contact[p])
    out: list[set[int]] = []
    for d in range(6):
        by = contact & unpack_words(oracle.blocked[p, d])
        group = {p} | {j for j in range(len(oracle.parts)) if by >> j & 1}
        if len(group) >= 2 and base not in group and group not in out:
            out.append(group)
    return sorted(out, key=len)


def build_with_units(
    spec: AssemblySpec,
    relations=None,
    *,
    hierarchy: bool = False,
    reduce: bool = False,
    concurrent: bool = False,
    on_unit: Callable[[str], None] | None = None,
    given_up: Iterable[str] | None = None,
    **kwargs,
):
    """Build the state graph with the CAD file's sub-assemblies and, when a part can never
    go in alone, automatic subassemblies.

    With ``hierarchy`` (a spec generated from a CAD file), the file's sub-assemblies that
    pass :func:`cad_units` become units first. When the assembly has no complete sequence,
    a sub-assembly of the file whose insertion (or a member's placement in its workspace)
    is among the stuck operations (:func:`stuck_operations`) is given up (its own
    sub-assemblies may then become units) and the graph built again; when none is, each
    stuck part is grouped with the parts that hold it (:func:`host_groups`: the smallest
    group, preferring one that shares parts with a unit already found, so that the parts
    held by one host enter with it), overlapping groups merge (with the units of earlier
    rounds too), and the graph is built again (at most :data:`MAX_ROUNDS` rounds); if no
    new unit can be found, the file's remaining sub-assemblies are given up before the
    first error is raised (a round of automatic units over the state limit raises the
    first round's proof, led by the pairs that lock each other: :func:`_with_locking`).
    With ``reduce``, a round whose derived precedences already prove
    that no complete sequence exists (:func:`asp.graph.precedences.refutation`, milliseconds)
    builds no checked graph, and its graph for the stuck operations only up to
    :data:`PROVED_ROUND_STATES` states; beyond, the operation the proof names is the stuck
    one (a clutch's pressure plate blocked by its 13 pins: 15.7M states built twice before).
    Every unit is checked by the state graph itself: its members
    must go into its own workspace one by one and the finished unit into the assembly as
    one rigid body, so units only ever give sound plans.

    Parameters
    ----------
    spec : AssemblySpec
    relations : cad Relations, optional
    hierarchy : bool
        Use the CAD file's sub-assemblies (:func:`with_cad_units`).
    reduce : bool
        Build each graph with the symmetry reduction
        (:func:`asp.graph.symmetry.reduced_state_graph`: interchangeable parts in the main
        assembly and in each unit's workspace in a fixed order; the full graph when there
        is nothing to reduce), for the spec with every unit of that round; with
        ``concurrent``, the reduction that keeps the concurrent game's values too.
    on_unit : callable, optional
        Called with a line for each unit decision (a person reads it on stderr).
    given_up : iterable of str, optional
        The file's sub-assemblies given up already (default: :func:`refuted_units`, whose
        lines go to ``on_unit``).
    **kwargs
        For :func:`asp.graph.state_graph.build_state_graph`.

    Returns
    -------
    StateGraph
        Its ``spec`` holds the units used (``spec.subassemblies``).
    """
    from asp.graph.state_graph import build_state_graph

    say = on_unit or (lambda _line: None)

    def build(with_units: AssemblySpec, **more):
        if reduce:
            from asp.graph.precedences import refutation
            from asp.graph.symmetry import reduced_state_graph

            proof = refutation(with_units, relations)
            if proof is not None:  # no complete sequence: known without a graph
                raise _Proved(with_units, proof)
            graph = reduced_state_graph(
                with_units, relations, concurrent=concurrent, **kwargs, **more
            )
            if graph is not None:
                return graph
        return build_state_graph(with_units, relations, **kwargs, **more)

    def next_units(with_units: AssemblySpec, proof, base, found, optional, drop: set[str]):
        """The round's new units (:func:`_new_units`; ``drop`` filled instead when a unit of
        the file is stuck) and whether a whole state graph was built for them.

        The stuck operations come from the graph built without the check. When the derived
        precedences prove there is no complete sequence (``proof``, from :func:`build`),
        that graph is built up to :data:`PROVED_ROUND_STATES` states only; beyond, the
        operation the proof names is the stuck one, and the whole graph is built only if
        that gives nothing new."""
        from asp.graph.state_keys import operation_model

        def units_of(graph, stuck: list[int]):
            drop.update(_stuck_units(graph.spec, stuck, optional))
            return None if drop else _new_units(graph, stuck, base, found, optional, drop)

        unchecked = {**kwargs, "check": False}
        if proof is not None:
            cap = min(kwargs.get("max_states") or PROVED_ROUND_STATES, PROVED_ROUND_STATES)
            try:
                graph = build_state_graph(with_units, relations, **{**unchecked, "max_states": cap})
            except StateLimit:
                view = _Round(with_units, operation_model(with_units, relations))
                groups = units_of(view, [with_units.op_index(proof.operation)])
                if drop or groups is not None:
                    return groups, False
            else:
                return units_of(graph, stuck_operations(graph)), False
        try:
            graph = build_state_graph(with_units, relations, **unchecked)
        except StateLimit:
            if proof is None:
                raise
            # too many states to find the stuck operations: the file's units the proof
            # involves are given up (None: all of them, or the proof is the error)
            drop.update(_proof_units(with_units, proof, optional))
            return None, True
        return units_of(graph, stuck_operations(graph)), True

    first_error = None
    if given_up is None:
        given_up = refuted_units(spec, relations, on_unit=say) if hierarchy else set()
    given_up = set(given_up)
    while True:
        base, choices = with_cad_units(spec, relations, given_up) if hierarchy else (spec, ())
        optional = {u.id: set(u.members) for u in choices if u.used}
        for u in choices:
            say(hierarchy_line(u))
        found: list[tuple[str, ...]] = []
        current = base
        plain = None  # the units without the parts hung on them, if those fail
        graph_rounds = proved_rounds = 0
        while graph_rounds <= MAX_ROUNDS and proved_rounds <= len(spec.operations):
            current = prepared_units(current, relations, say)
            fastened = _fastener_fallback(current, relations, first_error)
            over = fastened and fastener_projection(
                current, relations, fastened[1], concurrent, kwargs
            )
            try:
                if over:  # sure to go over: the order first, the full graph only if it fails
                    graph = _fasteners_in_order(build, current, *fastened, say, over)
                    if graph is not None:
                        return graph
                # with an answer past the limit (the joining parts' order; in a round
                # guessed for a proved failure, the proof), a graph sure to go over stops
                # sooner
                behind = fastened or isinstance(first_error, _Proved)
                return build(current, **({"projection_margin": 1} if behind else {}))
            except StateLimit:
                if not isinstance(first_error, _Proved):
                    graph = (
                        None
                        if not fastened or over
                        else _fasteners_in_order(build, current, *fastened, say)
                    )
                    if graph is None:
                        raise
                    return graph
                # units guessed for a proved failure, too many states to try: the proof
                said = _with_locking(first_error, relations)
                raise InfeasibleAssembly(
                    f"{said}; the automatic subassemblies tried for it exceed the state limit"
                ) from None
            except InfeasibleAssembly as exc:
                if relations is None:
                    raise
                first_error = first_error or exc
                proof = exc.proof if isinstance(exc, _Proved) else None
                if plain is not None:
                    current, plain = plain, None
                    say("no complete sequence with the held parts in the units: without them")
                    continue
            drop = set()
            groups, built = next_units(current, proof, base, found, optional, drop)
            graph_rounds += built
            proved_rounds += not built
            if drop:
                break
            if groups is None:
                drop = set(optional)
                break
            try:
                current = with_subassemblies(base, _named(base, groups))
            except ValueError:
                drop = set(optional)
                break
            found = groups
            say(
                "no complete sequence with single parts: trying subassemblies "
                + "; ".join(f"[{', '.join(g)}]" for g in groups)
            )
            hung = hung_on_units(base, relations, groups)
            if hung != groups:
                plain = current
                current = with_subassemblies(base, _named(base, hung))
                say(
                    "held parts that rest on a unit built upside down go in with it: "
                    + "; ".join(
                        f"{', '.join(h[len(g) :])} with {g[0]}'s unit"
                        for h, g in zip(hung, groups, strict=True)
                        if h != g
                    )
                )
        else:
            drop = set(optional)
        if not drop:
            if isinstance(first_error, _Proved):  # the graph's report names more
                first_error = _graph_report(first_error, relations, kwargs)
            raise first_error from None
        given_up |= drop
        say(
            f"the file's sub-assembl{'y' if len(drop) == 1 else 'ies'} {', '.join(sorted(drop))}"
            f": {GIVEN_UP}; planned without it"
        )


def _fastener_fallback(spec: AssemblySpec, relations, first_error):
    """``(ordered, found)`` of :func:`asp.graph.fasteners.fastener_order` when ``spec`` has
    joining parts and a state-limit failure of its full graph may fall back on them (not in
    a round guessed for a proved failure), else None: decided before the full graph is
    built, so that it is built with the tighter projection margin."""
    if relations is None or isinstance(first_error, _Proved):
        return None
    from asp.graph.fasteners import fastener_order

    ordered, found = fastener_order(spec, relations)
    return (ordered, found) if found else None


def fastener_projection(
    spec: AssemblySpec, relations, found, concurrent: bool, kwargs
) -> str | None:
    """Why the full state graph of ``spec`` is not even tried first: its joining parts
    ``found`` alone multiply its states past the limit
    (:func:`asp.graph.fasteners.joining_states`), or None. ``concurrent`` and ``kwargs`` as
    :func:`build_with_units` has them.

    The limit is the build's (``max_states``, else the spec's, else
    :data:`asp.graph.state_graph.DEFAULT_MAX_STATES`); the count is that of the graph the
    full build makes (:func:`asp.graph.symmetry.reduced_state_graph`: alike joining parts
    in a fixed order count as one chain). Not trying it never makes a plan unsound (the
    ordered graph's plans are checked like any); when the ordered graph fails, the full
    graph is built as before and its answer stands."""
    from asp.graph.fasteners import joining_states
    from asp.graph.state_graph import DEFAULT_MAX_STATES
    from asp.graph.symmetry import symmetry_reduction

    limit = kwargs.get("max_states") or spec.max_states or DEFAULT_MAX_STATES
    if len(found) < 2 or 2 ** len(found) <= limit:  # a chain only lowers the count
        return None
    states = joining_states(found, symmetry_reduction(spec, relations, concurrent=concurrent)[3])
    if states <= limit:
        return None
    return (
        f"the {len(found)} joining parts alone give at least {states:,} states, over the "
        f"limit of {limit:,}: the full graph is not built"
    )


def _fasteners_in_order(
    build, spec: AssemblySpec, ordered: AssemblySpec, found, say, projected: str = ""
):
    """The state graph of ``ordered``: ``spec`` with its joining parts ``found`` (screws,
    pins) in one order after the parts they join (:func:`asp.graph.fasteners.fastener_order`:
    sound, and complete whenever some complete sequence places each after its two parts),
    or None when that graph also fails (the caller's error stands). ``projected`` says why
    the full graph was not tried first (:func:`fastener_projection`)."""

    def listed(ids: list[str]) -> str:
        return ", ".join(ids[:6]) + (f" and {len(ids) - 6} more" if len(ids) > 6 else "")

    held = [
        op.parts[0]
        for op, was in zip(ordered.operations, spec.operations, strict=True)
        if op.held > was.held
    ]
    say(
        f"too many states ({projected or 'the full graph exceeds the limit'}): "
        f"{len(found)} joining parts (each touches only the parts it "
        "joins and goes in whatever else is there: screws, pins) placed in one order, each "
        f"after the parts it joins ({listed([j.part for j in found])}; "
        "asp/graph/fasteners.py)"
        + (f"; held while its joining parts go in: {listed(held)}" if held else "")
    )
    try:
        graph = build(ordered)
    except (StateLimit, InfeasibleAssembly) as exc:
        say(f"with the joining parts in one order: {exc}")
        return None
    chain = tuple((j.part, *j.joins) for j in found)  # for the plan (fasteners_in_order)
    return replace(graph, model=replace(graph.model, fasteners_in_order=chain))


def refuted_units(
    spec: AssemblySpec,
    relations,
    exclude: Iterable[str] = (),
    on_unit: Callable[[str], None] | None = None,
) -> set[str]:
    """The CAD file's sub-assemblies to give up before any state graph is built: those the
    derived precedences prove leave no complete sequence (:func:`refuted_reasons`), with
    ``exclude``; each given up is said with its proof on ``on_unit``."""
    return set(exclude) | set(_said_refuted(spec, relations, on_unit, exclude))


@dataclass(frozen=True)
class Refuted:
    """File units given up together, and the proof that they leave no complete sequence.

    Attributes
    ----------
    units : tuple of str
        The units, sorted.
    why : str
        The proof (:attr:`asp.graph.precedences.Refutation.why`, with what it means for
        the units when a part's hosts reach into them).
    """

    units: tuple[str, ...]
    why: str

    @property
    def reason(self) -> str:
        """Why each unit is not used (a spec comment, ``plan.json``'s ``units``)."""
        with_them = "it as one unit" if len(self.units) == 1 else "them as units"
        return f"no complete sequence with {with_them} ({self.why})"

    @property
    def line(self) -> str:
        """The line a person reads on stderr."""
        one = len(self.units) == 1
        return (
            f"the file's sub-assembl{'y' if one else 'ies'} {', '.join(self.units)}: "
            f"{self.reason}; planned without {'it' if one else 'them'}"
        )


def _said_refuted(
    spec: AssemblySpec,
    relations,
    on_unit: Callable[[str], None] | None,
    exclude: Iterable[str] = (),
    *,
    inserted_only: bool = False,
) -> dict[str, Refuted]:
    """:func:`refuted_reasons`, each distinct decision's line said on ``on_unit``."""
    reasons = refuted_reasons(spec, relations, exclude, inserted_only=inserted_only)
    if on_unit is not None:
        for refuted in dict.fromkeys(reasons.values()):
            on_unit(refuted.line)
    return reasons


def refuted_reasons(
    spec: AssemblySpec, relations, exclude: Iterable[str] = (), *, inserted_only: bool = False
) -> dict[str, Refuted]:
    """The CAD file's sub-assemblies the derived precedences prove leave no complete
    sequence (:func:`asp.graph.precedences.refutation`, milliseconds), each with the proof
    (the units given up together share one :class:`Refuted`); ``exclude``: given up already.
    With ``inserted_only``, only the units a proof names (their insertion, or the hosts of
    a part, below), stopping at the first proof that names none (what ``asmplan init``
    writes: :func:`file_units`).

    While the file's units (:func:`with_cad_units`, without the ones given up) admit such a
    proof, the units it involves are given up:

    - the unit whose insertion it names, alone (blocked along every direction by parts
      that must be there before it: a piston with its pin, grouped without the rod the pin
      passes through): that operation does not exist without it;
    - when it names a part whose every host group (:func:`host_groups`, the parts it could
      go in with as an automatic unit) takes parts of the file's units, the units of its
      smallest group (:func:`_units_in_the_way`, the rule the plan's rounds of automatic
      units apply: the satellite's USB board, resting only on the connectors of two boards
      the file groups with their standoffs, can go in only with both boards), whether or
      not the part fails without the units too: with them fixed, no automatic unit can
      hold it;
    - else (not ``inserted_only``), those whose members its failing test looks at (what a
      part could rest on, touch or is blocked by; all of them when it names none), unless
      the same operation fails in the spec without units (a holder blocked by its
      bearings, whatever the file groups): the units are then not the cause and are left
      to the state graph (:func:`build_with_units`: automatic units).

    The file's inner groups may then become units. Giving a unit up removes no plan that
    was possible. The proof holds for every order of the spec with the units of that
    round, so that spec has no complete sequence (every plan is a complete sequence):
    with the unit there is no plan to lose; without it (its members placed one by one, or
    in an automatic unit) any plan the state graph finds is checked as every plan is.
    """
    from asp.graph.feasibility import insertion_oracle
    from asp.graph.precedences import refutation

    given_up = set(exclude)
    fixed = {m for _, ms in spec.subassemblies for m in ms}
    placed_by = {p for op in spec.operations for p in op.parts}
    out: dict[str, Refuted] = {}
    while True:
        with_units, choices = with_cad_units(spec, relations, given_up)
        used = {u.id: set(u.members) for u in choices if u.used}
        if not used:
            return out
        proof = refutation(hold_unsupported_units(with_units, relations), relations)
        if proof is None:
            return out
        op = with_units.operation(proof.operation)
        why = proof.why
        drop: set[str] = set()
        if op.unit in used:
            drop = {op.unit}
        else:
            oracle = insertion_oracle(with_units, relations)
            owner = {m: u for u, ms in used.items() for m in ms}
            for name in (op.unit,) if op.unit else op.parts:
                candidates = _host_candidates(
                    with_units, oracle, oracle.index(name), fixed, placed_by
                )
                drop |= _units_in_the_way(candidates, owner)
                if drop:
                    hosts = sorted(min(candidates, key=len) - {name})
                    why += f"; it can go in only with {', '.join(hosts)} holding it"
                    break
        if not drop:
            if inserted_only:
                return out
            alone = refutation(spec, relations)
            if alone is not None and alone.operation == proof.operation:
                return out  # the same part fails without units: they are not the cause
            drop = _proof_units(with_units, proof, used) or set(used)
        given_up |= drop
        out.update(dict.fromkeys(drop, Refuted(tuple(sorted(drop)), why)))


def _proof_units(spec: AssemblySpec, proof, units: dict[str, set[str]]) -> set[str]:
    """The units of ``units`` (id -> members) a proof involves: the one whose insertion it
    names (that unit alone: it can never go in, whatever the other units are; the others
    are judged again without it), else those whose members its operation places or its
    failing test looks at."""
    op = spec.operation(proof.operation)
    if op.unit in units:
        return {op.unit}
    named = set(proof.parts) | set(op.parts)
    return {u for u, members in units.items() if u == op.unit or members & named}


def file_units(
    spec: AssemblySpec, relations, on_unit: Callable[[str], None] | None = None
) -> tuple[HierarchyUnit, ...]:
    """The decisions on the CAD file's sub-assemblies that a plan of the file starts from
    (``asmplan init`` writes them): :func:`cad_units` without the ones the derived
    precedences prove leave no complete sequence as units (:func:`refuted_reasons` with
    ``inserted_only``: their reason is the proof, said on ``on_unit`` too), so a written
    spec never fixes a unit that is in no complete sequence (the two-cylinder engine's
    piston with its pin, grouped without the rod the pin passes through; the satellite's
    ultrasonic sensors, which can only go in built into the front) nor one that keeps a
    part from its only hosts (the satellite's USB board and its two boards). A proof that
    names no unit is left to the plan (its automatic units), the units kept."""
    reasons = _said_refuted(spec, relations, on_unit, inserted_only=True)
    out = []
    for u in cad_units(spec, relations, reasons):
        if u.id in reasons and u.reason == GIVEN_UP:
            u = replace(u, reason=reasons[u.id].reason)
        out.append(u)
    return tuple(out)


def prepared_units(spec: AssemblySpec, relations, on_unit=None) -> AssemblySpec:
    """``spec``'s units ready to build: each in its build orientation
    (:func:`asp.fromcad.orientation.orient_units`, said through ``on_unit``), held when nothing
    outside it can keep it from falling (:func:`hold_unsupported_units`), and built one
    after another when their workspaces would multiply the states (:func:`built_in_turn`)."""
    from asp.fromcad.orientation import orient_units

    turned = orient_units(spec, relations, on_unit or (lambda _line: None))
    return built_in_turn(hold_unsupported_units(turned, relations))


def hold_unsupported_units(spec: AssemblySpec, relations) -> AssemblySpec:
    """A generated spec with ``held: true`` on the insertion of each unit that no part
    outside it can keep from falling (an upper die set sliding down its guide pins), as
    :func:`asp.fromcad.generate.hold_unsupported` does for single parts; other specs unchanged."""
    if not spec.generated or not spec.constraints.stability or relations is None:
        return spec
    from dataclasses import replace

    from asp.fromcad.orientation import loose_units

    loose = loose_units(spec, relations)
    if not loose:
        return spec
    ops = [replace(op, held=True) if op.unit in loose else op for op in spec.operations]
    return replace(spec, operations=tuple(ops))


def built_in_turn(spec: AssemblySpec) -> AssemblySpec:
    """``spec`` with its units built one after another when their workspaces would
    multiply the states.

    Each workspace under construction multiplies the states by the number of its partial
    builds, so ``k`` units of two parts built in any interleaving give ``3**k`` times as
    many. When the product of ``members + 1`` over the units exceeds
    :data:`MAX_WORKSPACE_PRODUCT`, each unit's member operations wait for every member
    operation of the unit before it (the units in the order of their first member
    operation): one workspace is under construction at a time, which the states grow by
    the sum instead of the product. Inserting the units stays free, so every plan is
    still sound; a person still builds a unit while a robot works on the main body.
    """
    units = list(spec.subassemblies)
    if math.prod(len(ms) + 1 for _, ms in units) <= MAX_WORKSPACE_PRODUCT:
        return spec
    from asp.graph.precedences import with_waits

    position = {p: k for k, op in enumerate(spec.operations) for p in op.parts}
    units.sort(key=lambda u: min(position[m] for m in u[1]))
    ops_of = {
        uid: [op.id for op in spec.operations if op.parts and set(op.parts) <= set(ms)]
        for uid, ms in units
    }
    wait: dict[str, tuple[str, ...]] = {}
    for (before, _), (uid, _) in zip(units, units[1:], strict=False):
        for o in ops_of[uid]:
            wait[o] = tuple(ops_of[before])
    return with_waits(spec, wait)


def hung_on_units(
    spec: AssemblySpec, relations, groups: list[tuple[str, ...]]
) -> list[tuple[str, ...]]:
    """Automatic units with the held parts that hang on them (a spec generated from CAD).

    A part an agent must hold in the product (``held``: nothing below keeps it from
    falling along the gravity ``g``), placed alone and in no unit, *hangs on* a unit when
    some member keeps it from falling along ``-g``: built upside down, the unit carries it
    (the guide bushings of a die set's upper half, pressed into the top plate from below,
    rest on it with the top plate on the bench). It joins the unit when the unit with it
    is then built upside down (:func:`asp.fromcad.orientation.unit_orientation`) without holding
    it: a toolmaker presses the bushings in there instead of holding each on its guide pin
    until the top plate comes down. The state graph still checks the unit
    (:func:`build_with_units` falls back to the units without them)."""
    if not spec.generated or not spec.constraints.stability or relations is None:
        return groups
    sp = getattr(relations, "sp", None)
    if sp is None:
        return groups
    from asp.fromcad.orientation import opposite, unit_orientation
    from asp.spec import DIRECTIONS

    index = {str(p): k for k, p in enumerate(relations.parts)}
    up = DIRECTIONS.index(opposite(spec.gravity))
    taken = {m for g in groups for m in g} | {m for _, ms in spec.subassemblies for m in ms}
    loose = [
        op.parts[0]
        for op in spec.operations
        if op.held and len(op.parts) == 1 and op.parts[0] not in taken and op.parts[0] in index
    ]
    loose = [p for p in loose if p != spec.base_part]
    out = []
    for group in groups:
        rows = [index[m] for m in group if m in index]
        hangers = [p for p in loose if np.asarray(sp)[index[p], rows, up].any()]
        if hangers:
            wider = (*group, *hangers)
            trial = with_subassemblies(spec, [("_hung", wider)])
            o = unit_orientation(trial, relations, "_hung")
            if o.upside_down and not set(hangers) & set(o.held):
                loose = [p for p in loose if p not in hangers]
                group = wider
        out.append(group)
    return out


def _stuck_units(spec: AssemblySpec, stuck: list[int], optional: dict[str, set[str]]) -> set[str]:
    """The optional units whose insertion or members' placement is among ``stuck``."""
    out = set()
    for i in stuck:
        op = spec.operations[i]
        for uid, members in optional.items():
            if op.unit == uid or set(op.parts) & members:
                out.add(uid)
    return out


class _Proved(InfeasibleAssembly):
    """No complete sequence, proved by the derived precedences without a state graph."""

    def __init__(self, spec: AssemblySpec, proof):
        super().__init__(f"{spec.source}: infeasible assembly, no complete sequence: {proof.why}")
        self.spec, self.proof = spec, proof


def _graph_report(proof: _Proved, relations, kwargs: dict) -> SpecError:
    """The state graph's own report of a proved failure (it names the blockers along each
    direction and a state where the part was tried), or the proof if the graph has none."""
    from asp.graph.state_graph import build_state_graph

    try:
        build_state_graph(proof.spec, relations, **kwargs)
    except StateLimit:  # too many states to report on: the proof is the report
        return _with_locking(proof, relations)
    except SpecError as exc:
        return exc
    return proof


def _with_locking(proof: _Proved, relations) -> InfeasibleAssembly:
    """``proof`` led by the pairs of parts that block each other along every direction and
    the ``flex:`` line for them (:func:`asp.cad_keys.flex_hint`), as the state graph's
    report leads with them; the proof itself when no pair locks."""
    from asp.cad_keys import flex_hint
    from cad.freedom import locking_pairs

    pairs = locking_pairs(relations.tt, relations.parts) if relations is not None else []
    if not pairs:
        return proof
    return InfeasibleAssembly(
        f"{proof.spec.source}: infeasible assembly, no complete sequence: "
        f"{flex_hint(pairs)}{proof.proof.why}"
    )


@dataclass(frozen=True)
class _Round:
    """What a round of :func:`build_with_units` reads of its state graph (the spec and the
    operation model), when a proof took the place of the graph."""

    spec: AssemblySpec
    model: object


def stuck_operations(graph) -> list[int]:
    """Operations whose part cannot go in alone: those never done although ready somewhere;
    when every operation is done in some order but none completes, those left ready in the
    furthest dead ends (the states of the last layer), such as the last of four gussets,
    held by the other three whichever it is."""
    from asp.graph.state_graph import never_done

    never = never_done(graph)
    if never or not graph.n_states:
        return never
    model = graph.model
    last = np.arange(int(graph.layer_ptr[-2]), int(graph.layer_ptr[-1]))
    keys = graph.keys[last]
    return [i for i in range(model.n_ops) if model.part_lists[i] and model.ready(keys, i).any()]


def _new_units(
    graph,
    ops: list[int],
    spec: AssemblySpec,
    found: list[tuple[str, ...]],
    optional: dict[str, set[str]] | None = None,
    drop: set[str] | None = None,
):
    """The automatic units after a round: ``found`` with the parts of the stuck
    operations ``ops`` grouped with their hosts (None when nothing changes).

    A group may not take parts of the spec's units; when the only groups of a stuck part
    take parts of ``optional`` units (the CAD file's), the units of its smallest group
    are added to ``drop`` (to be given up) instead.
    """
    model = graph.model
    oracle = model.oracle
    optional = optional or {}
    owner = {m: u for u, ms in optional.items() for m in ms}
    fixed = {m for _, ms in spec.subassemblies for m in ms} - set(owner)
    placed_by = {p for op in spec.operations for p in op.parts}
    groups = [set(g) for g in found]
    before = sorted(map(sorted, groups))
    for i in ops:
        for p in model.part_lists[i]:
            grouped = set().union(*groups) if groups else set()
            candidates = _host_candidates(graph.spec, oracle, p, fixed, placed_by)
            in_the_way = _units_in_the_way(candidates, owner)
            if in_the_way and drop is not None:
                drop |= in_the_way
                continue
            # a group inside one unit adds nothing; one spanning several units merges them
            # (a stripper plate hanging on the bolts of one and the punch of the other)
            candidates = [
                c for c in candidates if not c & set(owner) and not any(c <= g for g in groups)
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


def _host_candidates(
    spec: AssemblySpec, oracle, p: int, fixed: set[str], placed_by: set[str]
) -> list[set[str]]:
    """The groups that could carry row ``p`` of ``oracle`` (a part, or a unit of ``spec``)
    in: its host groups (:func:`host_groups`; a unit's: each member's, with the other
    members), without those taking parts of the ``fixed`` units' members or parts no
    operation places (``placed_by``: the parts the operations place)."""
    if p >= len(spec.part_ids) and spec.part_ids:
        # a unit's insertion: the unit with what holds one of its members
        name = oracle.parts[p]
        members = dict(spec.subassemblies)[name]
        candidates = [
            {oracle.parts[j] for j in g} | set(members) - {name}
            for m in members
            for g in host_groups(oracle, oracle.index(m), oracle.base)
        ]
    else:
        candidates = [{oracle.parts[j] for j in g} for g in host_groups(oracle, p, oracle.base)]
    return [c for c in candidates if not c & fixed and c <= placed_by]


def _units_in_the_way(candidates: list[set[str]], owner: dict[str, str]) -> set[str]:
    """The CAD file's units (``owner``: member -> unit) that a part's host groups
    ``candidates`` (:func:`_host_candidates`) run into: when every group takes parts of
    them, the units of the smallest group (given up, its parts may join the part's
    automatic unit); else nothing."""
    if candidates and all(c & set(owner) for c in candidates):
        return {owner[m] for m in min(candidates, key=len) if m in owner}
    return set()


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


GIVEN_UP = "no complete sequence with it as one unit"
"""Why a sub-assembly of the file that passed :func:`cad_units` is not used."""
BUILD_SEARCH_LIMIT = 20_000
"""Partial workspaces tried when checking that a sub-assembly can be built on its own;
beyond it the check is left to the state graph."""


@dataclass(frozen=True)
class HierarchyUnit:
    """One sub-assembly of the CAD file and whether it is planned as a unit.

    Attributes
    ----------
    id : str
        The unit id (the group's cleaned name).
    members : tuple of str
        Its parts (the spec's ids).
    used : bool
        Planned as a unit (built in its own workspace, inserted as one body).
    reason : str
        Why it is not used (empty when it is).
    """

    id: str
    members: tuple[str, ...]
    used: bool
    reason: str = ""


def hierarchy_line(unit: HierarchyUnit) -> str:
    """One line for a person: the file's sub-assembly, used or why not."""
    head = f"the file's sub-assembly {unit.id} [{', '.join(unit.members)}]"
    return head + (
        ": built on its own, inserted as one unit" if unit.used else f": not used ({unit.reason})"
    )


def cad_units(
    spec: AssemblySpec, relations, exclude: Iterable[str] = ()
) -> tuple[HierarchyUnit, ...]:
    """Decide which of the CAD file's sub-assemblies become units.

    The file's groups (``spec.hierarchy``, as the file was read), outermost first; a part
    belongs to one unit, so a group inside a used one is not used. A group is used when

    - it does not hold the base part (that stands first in the main assembly);
    - each of its parts is placed by an operation of its own, placing no other part;
    - it can be built on its own: its parts go into its workspace one by one, each free
      along a direction the gripper approaches from, touching and supported (unless held)
      by the parts already there, right side up or upside down (gravity reversed: a lid
      with flanged pegs pressed in from below, :mod:`asp.fromcad.orientation` then picks the way
      up) (a search over the orders, at most :data:`BUILD_SEARCH_LIMIT` partial
      workspaces; undecided counts as buildable);
    - it can be inserted as one rigid body: free from the base part along such a
      direction and touching a part outside it (one that rests on nothing outside it is
      held while it goes in, :func:`hold_unsupported_units`).

    The state graph decides the rest (:func:`build_with_units` gives up a unit that
    leaves no complete sequence). ``exclude``: groups given up already (their own groups
    are then candidates).
    """
    from asp.graph.feasibility import insertion_oracle

    if relations is None:
        return ()
    groups = spec.hierarchy
    if not groups:
        return ()
    exclude = set(exclude)
    oracle = insertion_oracle(spec, relations)
    index = {p: k for k, p in enumerate(oracle.parts)}
    op_of = {p: op for op in spec.operations for p in op.parts}
    taken_ids = set(spec.op_ids) | set(spec.part_ids) | {u for u, _ in spec.subassemblies}
    in_unit: dict[str, str] = {m: u for u, ms in spec.subassemblies for m in ms}
    flipped = []  # the oracle with gravity reversed, made when first needed

    def upside_down():
        if not flipped:
            from dataclasses import replace

            from asp.fromcad.orientation import opposite

            turned = replace(spec, gravity=opposite(spec.gravity))
            flipped.append(insertion_oracle(turned, relations))
        return flipped[0]

    out = []
    for gid, members in groups:
        uid = gid if gid not in taken_ids else f"{gid}_unit"
        reason = _unit_problem(spec, oracle, index, op_of, in_unit, members, upside_down)
        if uid in exclude and not reason:
            reason = GIVEN_UP
        out.append(HierarchyUnit(uid, members, not reason, reason))
        if not reason:
            in_unit.update(dict.fromkeys(members, uid))
            taken_ids.add(uid)
    return tuple(out)


def _unit_problem(spec, oracle, index, op_of, in_unit, members, upside_down=None) -> str:
    """Why a group cannot be a unit ("" when it can); ``upside_down()`` gives the oracle
    with gravity reversed (a group built upside down)."""
    inside = {in_unit[m] for m in members if m in in_unit}
    if inside:
        return f"its parts are in the unit {sorted(inside)[0]} (one level of units)"
    if spec.base_part in members:
        return f"it holds the base part {spec.base_part}, placed first in the main assembly"
    for m in members:
        op = op_of.get(m)
        if op is None:
            return f"no operation places {m}"
        if not set(op.parts) <= set(members):
            return f"operation {op.id} places parts inside and outside it"
    idx = [index[m] for m in members]
    held = {index[m]: op_of[m].held for m in members}
    why = _build_problem(oracle, idx, held)
    if why and upside_down is not None and not _build_problem(upside_down(), idx, held):
        why = ""
    if why:
        return f"it cannot be built on its own: {why}"
    return _insert_problem(spec, oracle, idx)


def _build_problem(oracle, members: list[int], held: dict[int, bool]) -> str:
    """Why no order builds ``members`` in a workspace of their own ("" if one does)."""
    dead: set[int] = set()
    best = [0]
    tried = [0]

    def grow(s: int, left: frozenset) -> bool:
        if not left:
            return True
        if s in dead:
            return False
        tried[0] += 1
        if tried[0] > BUILD_SEARCH_LIMIT:
            raise _Undecided
        if s.bit_count() > best[0].bit_count():
            best[0] = s
        for p in sorted(left):
            fits = s == 0 or oracle.feasible(p, [s], held=held[p], workspace=True)[0]
            if fits and grow(s | 1 << p, left - {p}):
                return True
        dead.add(s)
        return False

    try:
        if grow(0, frozenset(members)):
            return ""
    except _Undecided:
        return ""
    s = best[0]
    placed = [oracle.parts[j] for j in members if s >> j & 1]
    p = next(j for j in members if not s >> j & 1)
    reasons = oracle.reasons(p, s, held=held[p], workspace=True)
    return f"with {', '.join(placed)} placed, {oracle.parts[p]} cannot go in ({'; '.join(reasons)})"


class _Undecided(Exception):
    """The build search reached its limit."""


def _insert_problem(spec, oracle, members: list[int]) -> str:
    """Why the finished group cannot go into any assembly as one body ("" if it may)."""
    from asp.graph.feasibility import unpack_words

    unit = sum(1 << j for j in members)
    outside = ((1 << len(oracle.parts)) - 1) & ~unit
    contact = 0
    blocked = [0] * 6
    for j in members:
        contact |= unpack_words(oracle.contact[j])
        for d in range(6):
            blocked[d] |= unpack_words(oracle.blocked[j, d])
    if not contact & outside:
        return "it touches no part outside it"
    if oracle.base >= 0:
        ways = [d for d in range(6) if oracle.directions[d] and not blocked[d] >> oracle.base & 1]
        if not ways:
            return f"the base part {oracle.parts[oracle.base]} blocks it along every direction"
    return ""


def units_report(
    spec: AssemblySpec, relations, used: Iterable[tuple[str, Iterable[str]]]
) -> list[dict]:
    """Every unit and sub-assembly of the file, for ``plan.json``'s ``units``.

    ``spec`` is the assembly's spec before planning and ``used`` the units the state graph
    used (``graph.spec.subassemblies``). Each entry: ``id``, ``parts``, ``source`` (``spec``,
    ``cad`` or ``automatic``), ``used`` and ``reason`` (why a sub-assembly of the file is
    not used; empty when it is).
    """
    used = {u: tuple(ms) for u, ms in used}
    own = {u for u, _ in spec.subassemblies}
    choices: tuple[HierarchyUnit, ...] = ()
    if spec.generated:
        exclude: set[str] = set()
        while True:  # the decisions build_with_units reached: the given-up ones excluded
            choices = cad_units(spec, relations, exclude)
            lost = {u.id for u in choices if u.used and u.id not in used}
            if not lost:
                break
            exclude |= lost
    cad = {u.id for u in choices}
    out = [
        {"id": u.id, "parts": list(u.members), "source": "cad", "used": u.used, "reason": u.reason}
        for u in choices
    ]
    for uid, members in used.items():
        if uid not in cad:
            source = "spec" if uid in own else "automatic"
            out.append(
                {"id": uid, "parts": list(members), "source": source, "used": True, "reason": ""}
            )
    return out


def with_cad_units(
    spec: AssemblySpec, relations, exclude: Iterable[str] = ()
) -> tuple[AssemblySpec, tuple[HierarchyUnit, ...]]:
    """``spec`` with the CAD file's sub-assemblies that :func:`cad_units` accepts as units,
    and every decision (used or why not)."""
    choices = cad_units(spec, relations, exclude)
    used = [(u.id, u.members) for u in choices if u.used]
    return (with_subassemblies(spec, used) if used else spec), choices


def unit_parts_of_line(spec: AssemblySpec, operations: Iterable[str]) -> list[list[str]]:
    """For each operation of a line, the parts it places (a unit's insertion: its members)."""
    members = unit_members(spec)
    by_id = {op.id: op for op in spec.operations}
    return [list(members.get(by_id[o].unit, by_id[o].parts)) for o in operations]


__all__ = [
    "HierarchyUnit",
    "Refuted",
    "build_with_units",
    "cad_units",
    "file_units",
    "hierarchy_line",
    "host_groups",
    "refuted_reasons",
    "refuted_units",
    "unit_members",
    "unit_parts_of_line",
    "units_report",
    "with_cad_units",
    "with_subassemblies",
    "workspace_of",
]
