"""Interchangeable parts inside a unit's workspace (asp/graph/symmetry.py): alike members of one
workspace are chained like alike parts of the main assembly, and the reduced graph keeps the
full graph's TCT and W*."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from asp.game.solve import solve
from asp.graph.game_dag import game_dag
from asp.graph.symmetry import interchangeable_blocks, reduced_state_graph
from asp.spec import with_subassemblies
from tests.asp.graph.test_symmetry_ring import _random_spec, _random_tables, values
from tests.asp.graph.test_symmetry_units import assert_reduction_keeps_values

MIRROR = [1, 0, 3, 2, 5, 4]

# which parts form units: pins and rollers of every copy together, the pins (their
# rollers outside), the pins with the first single part, the pins and the rollers apart
GROUPINGS = {
    "pins+rollers": lambda c, s: [("u", [f"p{k}" for k in range(c)] + [f"r{k}" for k in range(c)])],
    "pins": lambda c, s: [("u", [f"p{k}" for k in range(c)])],
    "pins+single": lambda c, s: [("u", ["s0"] + [f"p{k}" for k in range(c)])] if s else [],
    "two units": lambda c, s: [
        ("u", [f"p{k}" for k in range(c)]),
        ("v", [f"r{k}" for k in range(c)]),
    ],
}


def alike_copies(rel, copies: int, singles: int):
    """``rel`` with the relations between two different copies the same for every ordered
    pair (pin to pin, pin to roller, roller to pin, roller to roller), so that any two
    copies may be alike."""
    first = 1 + singles
    pin = list(range(first, first + copies))
    roller = list(range(first + copies, first + 2 * copies))
    tc, tt, sp = rel.tc.copy(), rel.tt.copy(), rel.sp.copy()
    for table in (tc, tt, sp):
        for a, b in ((pin, pin), (pin, roller), (roller, pin), (roller, roller)):
            for i in range(copies):
                for j in range(copies):
                    if i != j and (i, j) != (0, 1):
                        table[a[i], b[j]] = table[a[0], b[1]]
    tc = tc | tc.transpose(1, 0, 2)[:, :, MIRROR]
    n = len(rel.parts)
    for table in (tc, sp):
        table[np.arange(n), np.arange(n)] = False
    tt[np.arange(n), np.arange(n)] = True
    return type(rel)(rel.parts, tc, tt, sp)


def random_alike_spec(draw, copies: int, singles: int, grouping):
    """``(spec, rel)``: random tables of alike pins with their rollers
    (:func:`alike_copies`), random ``held`` parts and the units of ``GROUPINGS[grouping]``
    (none for None)."""
    rel = alike_copies(_random_tables(draw, copies, singles), copies, singles)
    held = draw(st.sets(st.sampled_from("psr")))
    spec = _random_spec(rel.parts, held)
    units = GROUPINGS[grouping](copies, singles) if grouping else []
    if units:
        spec = with_subassemblies(spec, units)
    return spec, rel


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    data=st.data(),
    copies=st.integers(2, 3),
    singles=st.integers(0, 2),
    grouping=st.sampled_from(sorted(GROUPINGS)),
    alike=st.booleans(),
    cost=st.sampled_from(["steps", "time"]),
)
def test_random_units_with_alike_members_keep_tct_and_w_star(
    data, copies, singles, grouping, alike, cost
):
    rel = _random_tables(data.draw, copies, singles)
    if alike:
        rel = alike_copies(rel, copies, singles)
    held = data.draw(st.sets(st.sampled_from("psr")))
    units = GROUPINGS[grouping](copies, singles)
    if not units:
        return
    spec = with_subassemblies(_random_spec(rel.parts, held), units)
    assert_reduction_keeps_values(spec, rel, cost)


def _workspace_pins(copies: int = 3):
    """Random-free tables: a base, a unit of a plate and ``copies`` pins standing in it
    (each pin touches and rests on the plate, blocked by it along every direction but +z),
    the unit going onto the base from above."""
    from tests.asp.helpers_assembly import LATERAL, relations

    pins = [f"p{k}" for k in range(copies)]
    parts = ("B", "plate", *pins)
    contacts = [("plate", "B", "-z"), *((p, "plate", "-z") for p in pins)]
    blocks = [("plate", "B", "-z")] + [(p, "plate", d) for p in pins for d in ("-z", *LATERAL)]
    return parts, relations(parts, contacts, blocks)


def test_alike_members_of_a_workspace_are_one_class_and_keep_the_values():
    parts, rel = _workspace_pins()
    spec = with_subassemblies(_random_spec(parts, set()), [("u", ["plate", "p0", "p1", "p2"])])
    assert interchangeable_blocks(spec, rel) == [[["p0"], ["p1"], ["p2"]]]
    for cost in ("steps", "time"):
        full, expected = values(spec, rel, cost)
        reduced = reduced_state_graph(spec, rel)
        sol = solve(game_dag(reduced, cost=cost))
        assert (sol.tct, sol.minimax) == expected
        assert reduced.n_states < full.n_states


def test_members_of_different_workspaces_are_not_swapped():
    """Two units of a plate with a pin each: the pins are alike but in two workspaces (the
    units stay in place), so nothing is chained across them."""
    parts, rel = _workspace_pins(2)
    spec = _random_spec(parts, set())
    spec = with_subassemblies(spec, [("u", ["plate", "p0"])])
    blocks = interchangeable_blocks(spec, rel)
    assert not any("p0" in b for cls in blocks for b in cls)


@pytest.mark.parametrize("cost", ["steps", "time"])
def test_a_pin_outside_sees_the_unit_not_its_members(cost):
    """Pins of the main assembly touching different members of a unit (one each) are alike
    once the unit is in: the main assembly sees the unit as one body."""
    from tests.asp.helpers_assembly import LATERAL, relations

    parts = ("B", "a0", "a1", "q0", "q1")
    contacts = [("a0", "B", "-z"), ("a1", "a0", "-z"), ("q0", "a0", "-z"), ("q1", "a1", "-z")]
    blocks = [("a0", "B", "-z"), ("a1", "a0", "-z")]
    blocks += [(f"q{k}", f"a{k}", d) for k in range(2) for d in ("-z", *LATERAL)]
    rel = relations(parts, contacts, blocks)
    spec = with_subassemblies(_random_spec(parts, set()), [("u", ["a0", "a1"])])
    assert [["q0"], ["q1"]] in interchangeable_blocks(spec, rel)
    full, expected = values(spec, rel, cost)
    reduced = reduced_state_graph(spec, rel)
    sol = solve(game_dag(reduced, cost=cost))
    assert (sol.tct, sol.minimax) == expected
