"""Interchangeable parts with subassemblies (asp/graph/symmetry.py with units): a unit is one body
of the main assembly, its workspace is left alone, and the reduced graph keeps the full
graph's TCT and W*; a proof of infeasibility with units is never wrong."""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from asp.errors import SpecError
from asp.game.solve import solve
from asp.graph.checker import check_line
from asp.graph.game_dag import game_dag
from asp.graph.precedences import infeasibility
from asp.graph.symmetry import interchangeable_blocks, reduced_state_graph
from asp.spec import with_subassemblies
from tests.asp.graph.test_symmetry_ring import (
    RING,
    _random_spec,
    _random_tables,
    ring_meshes,
    ring_spec,
    values,
)


def pin_units(spec, ks):
    """``spec`` with pin k and its roller (or, in the ring, ``pin{k}``, ``roller{k}``) as unit
    ``u{k}`` for each k of ``ks``."""
    names = set(spec.part_ids)
    pairs = [(f"p{k}", f"r{k}") if f"p{k}" in names else (f"pin{k}", f"roller{k}") for k in ks]
    return with_subassemblies(spec, [(f"u{k}", pair) for k, pair in zip(ks, pairs, strict=True)])


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    data=st.data(),
    copies=st.integers(2, 3),
    singles=st.integers(0, 2),
    units=st.integers(1, 3),
)
def test_random_tables_with_units_reduce_without_changing_tct_and_w_star(
    data, copies, singles, units
):
    rel = _random_tables(data.draw, copies, singles)
    held = data.draw(st.sets(st.sampled_from("psr")))
    spec = pin_units(_random_spec(rel.parts, held), range(min(units, copies)))
    assert_reduction_keeps_values(spec, rel, "time")


def assert_reduction_keeps_values(spec, rel, cost: str) -> None:
    """The reduced graph of a spec with units has the full graph's TCT and W*, its lines
    pass the checker, and a feasible assembly is never proved infeasible (nothing to
    compare when the full graph has no complete sequence or nothing is reduced)."""
    try:
        full, expected = values(spec, rel, cost)
    except SpecError:
        return  # no complete sequence with these units: nothing to compare
    why = infeasibility(spec, rel)
    assert not why, f"derived precedences call a feasible assembly with units infeasible: {why}"
    pruned = reduced_state_graph(spec, rel)
    if pruned is None:
        return  # nothing to reduce
    sol = solve(game_dag(pruned, cost=cost))
    assert (sol.tct, sol.minimax) == expected
    assert pruned.n_states <= full.n_states
    for seq in pruned.sequences(limit=10):
        check_line(spec, rel, seq)


@pytest.fixture(scope="module")
def ring():
    from cad import Assembly, compute_relations

    meshes = ring_meshes(hub=False)
    return ring_spec(list(meshes)), compute_relations(Assembly.from_meshes(meshes))


@pytest.mark.parametrize("units", [(0, 1), (0, 1, 2, 3), (1,)], ids=["two", "all", "one"])
@pytest.mark.parametrize("cost", ["steps", "time"])
def test_ring_with_interchangeable_units_keeps_tct_and_w_star(ring, units, cost):
    """Pins with their rollers as units, alike: the reduced graph leaves the units (and
    their workspaces) alone and still chains the loose pins, with the full graph's values."""
    spec, rel = ring
    spec = pin_units(spec, units)
    full, expected = values(spec, rel, cost)
    reduced = reduced_state_graph(spec, rel)
    assert reduced is not None
    sol = solve(game_dag(reduced, cost=cost))
    assert (sol.tct, sol.minimax) == expected
    assert reduced.n_states <= full.n_states
    loose = [k for k in range(RING) if k not in units]
    blocks = interchangeable_blocks(spec, rel)
    moved = {o for cls in blocks for block in cls for o in block}
    members = {p for _, ms in spec.subassemblies for p in ms}
    assert not moved & {o.id for o in spec.operations if o.unit or set(o.parts) & members}
    if len(loose) >= 2:
        assert blocks == [[[f"pin{k}", f"roller{k}"] for k in loose]]
    for seq in reduced.sequences(limit=20):
        check_line(spec, rel, seq)
