"""The reduction of interchangeable parts keeps the concurrent game's values too.

A fixed order of alike parts would forbid placing two of them at once (the concurrent
game runs two operations together only if both orders are transitions), so the graph for
the concurrent game (``reduced_state_graph(..., concurrent=True)``) keeps alike operations
that several workers may do in a loose order instead
(:meth:`asp.graph.state_keys.OperationModel._loose_order`): W*(k) and W*(inf) on the reduced
graph equal the full graph's, in the main assembly and in a unit's workspace.
"""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from asp.concurrent.model import concurrent_model
from asp.concurrent.robustness import robustness
from asp.errors import SpecError
from asp.graph.state_graph import build_state_graph
from asp.graph.symmetry import (
    class_slack,
    interchangeable_blocks,
    reduce_interchangeable,
    reduced_state_graph,
)
from asp.spec import with_subassemblies
from tests.asp.graph.test_symmetry import pinned_disc
from tests.asp.graph.test_symmetry_ring import _random_spec
from tests.asp.graph.test_symmetry_workspaces import GROUPINGS, random_alike_spec


def curve(graph, max_k: int = 2) -> tuple:
    r = robustness(concurrent_model(graph.spec, graph), max_k=max_k)
    return (*r.bounds, r.unbounded)


def test_a_fixed_order_of_alike_parts_would_change_the_concurrent_game():
    """The pinned disc's pins and screws: in a fixed order no two pins go in at once, and
    the cooperative makespan W*(0) grows; the reduced graph keeps the full graph's curve."""
    spec, rel = pinned_disc(3, 2)
    full = build_state_graph(spec, rel)
    fixed = build_state_graph(reduce_interchangeable(spec, rel), rel)
    assert curve(fixed)[0] > curve(full)[0]
    assert reduced_state_graph(spec, rel).n_states == fixed.n_states  # the alternating game's
    reduced = reduced_state_graph(spec, rel, concurrent=True)
    assert curve(reduced) == curve(full)
    assert fixed.n_states < reduced.n_states < full.n_states


def test_the_slack_is_one_less_than_the_workers_who_may_do_them():
    spec, _ = pinned_disc(3, 2)
    assert class_slack(spec, ["pin0", "pin1", "pin2"]) == 1  # H and R
    only_r = spec.operation("pin0").durations[:1]
    assert len(only_r) == 1
    from dataclasses import replace

    ops = tuple(
        replace(op, durations=op.durations[:1]) if op.id.startswith("pin") else op
        for op in spec.operations
    )
    assert class_slack(replace(spec, operations=ops), ["pin0", "pin1", "pin2"]) == 0


@pytest.mark.parametrize("copies", [2, 3])
def test_alike_members_of_a_workspace_keep_the_concurrent_game(copies):
    from tests.asp.graph.test_symmetry_workspaces import _workspace_pins

    parts, rel = _workspace_pins(copies)
    members = ["plate", *(f"p{k}" for k in range(copies))]
    spec = with_subassemblies(_random_spec(parts, set()), [("u", members)])
    full = build_state_graph(spec, rel)
    reduced = reduced_state_graph(spec, rel, concurrent=True)
    # two workers: two alike pins may go in at once, so two of them stay unordered
    assert reduced.n_states < full.n_states if copies > 2 else reduced.n_states <= full.n_states
    assert curve(reduced) == curve(full)


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    data=st.data(),
    copies=st.integers(2, 3),
    singles=st.integers(0, 2),
    grouping=st.sampled_from([None, *sorted(GROUPINGS)]),
)
def test_random_tables_keep_the_concurrent_game(data, copies, singles, grouping):
    """Random tables, with or without units: whenever the blocks of interchangeable
    operations are chains (single operations, or a pin with its roller), the reduced graph
    has the full graph's W*(k)."""
    spec, rel = random_alike_spec(data.draw, copies, singles, grouping)
    try:
        full = build_state_graph(spec, rel)
    except SpecError:
        return  # no complete sequence
    if interchangeable_blocks(spec, rel, chains_only=False) != interchangeable_blocks(spec, rel):
        return  # blocks that are not chains (first of equals): the alternating game's only
    reduced = reduced_state_graph(spec, rel, concurrent=True)
    if reduced is None:
        return
    assert curve(reduced) == curve(full)


@pytest.fixture(scope="module", params=[False, True], ids=["ring", "ring+hub"])
def ring(request):
    from cad import Assembly, compute_relations
    from tests.asp.graph.test_symmetry_ring import ring_meshes, ring_spec

    meshes = ring_meshes(hub=request.param)
    return ring_spec(list(meshes)), compute_relations(Assembly.from_meshes(meshes))


def test_pins_with_their_rollers_keep_the_concurrent_game(ring):
    """Blocks of two operations (a pin and the roller threaded on it), ordered position by
    position with the slack of the pins added to the rollers'."""
    spec, rel = ring
    assert interchangeable_blocks(spec, rel) == [[[f"pin{k}", f"roller{k}"] for k in range(4)]]
    full = build_state_graph(spec, rel)
    reduced = reduced_state_graph(spec, rel, concurrent=True)
    assert reduced.n_states < full.n_states
    assert curve(reduced) == curve(full)
