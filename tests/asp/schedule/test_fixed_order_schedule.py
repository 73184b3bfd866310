"""The CP-SAT makespan on a graph reduced by a fixed order of alike parts is the full graph's.

The alternating game's graph chains interchangeable operations in a fixed order
(:mod:`asp.graph.symmetry`); the schedule stage undoes it (:mod:`asp.graph.fixed_order`:
relabelling in the replay, start-order symmetry breaking instead of the chain, cuts stated
with counts), so alike parts may run at once again. Without it the makespan grows (the chain
is a precedence and two alike parts never overlap).
"""

from __future__ import annotations

from dataclasses import replace

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from asp.errors import SpecError
from asp.graph.state_graph import build_state_graph
from asp.graph.symmetry import reduced_state_graph
from asp.schedule.assembly_makespan import assembly_makespan
from asp.schedule.replay import replay_model, schedule_violation
from asp.spec import Agent
from tests.asp.graph.test_symmetry import pinned_disc
from tests.asp.graph.test_symmetry_ring import ring_case
from tests.asp.graph.test_symmetry_workspaces import GROUPINGS, random_alike_spec


def makespan(spec, graph, fixed_order: bool = True):
    """The proven optimum (CP-SAT, one worker, fixed seed), checked by a replay without
    short cuts."""
    _, result = assembly_makespan(
        spec, graph, time_limit=60.0, workers=1, seed=0, fixed_order=fixed_order
    )
    assert result.status == "OPTIMAL", result.detail.get("status_note")
    rows = result.detail["schedule"]
    model = replay_model(spec, graph, cuts=False, fixed_order=fixed_order)
    assert schedule_violation(model, rows) is None
    return result.objective


def conservative(spec, graph) -> float:
    """The makespan with the fixed order kept (as before: the chain a precedence)."""
    return makespan(spec, graph, fixed_order=False)


def with_agents(spec, robots: int, humans: int):
    """``spec`` with ``robots`` robots and ``humans`` people, each with the durations of the
    spec's robot ``R`` or person ``H``."""
    names = [f"R{k}" for k in range(robots)] + [f"H{k}" for k in range(humans)]
    agents = tuple(Agent(name=a, side="robot" if a[0] == "R" else "human") for a in names)
    ops = []
    for op in spec.operations:
        d = dict(op.durations)
        ops.append(replace(op, durations=tuple((a, d[a[0]]) for a in names)))
    return replace(spec, agents=agents, operations=tuple(ops))


@pytest.mark.parametrize(
    ("pins", "screws", "robots", "humans"),
    [(3, 2, 1, 1), (4, 2, 1, 1), (4, 3, 1, 1), (4, 2, 2, 1)],
)
def test_pinned_disc_makespan_is_the_full_graphs(pins, screws, robots, humans):
    spec, rel = pinned_disc(pins, screws)
    if (robots, humans) != (1, 1):
        spec = with_agents(spec, robots, humans)
    full = build_state_graph(spec, rel)
    reduced = reduced_state_graph(spec, rel)
    assert reduced.model.fixed and reduced.n_states < full.n_states
    exact = makespan(spec, full)
    assert makespan(reduced.spec, reduced) == exact
    assert conservative(reduced.spec, reduced) > exact


@pytest.fixture(scope="module", params=[False, True], ids=["ring", "ring+hub"])
def ring(request):
    return ring_case(request.param)


def test_pins_with_their_rollers(ring):
    """Blocks of two operations: each block done in its order, the blocks relabelled."""
    spec, rel = ring
    full = build_state_graph(spec, rel)
    reduced = reduced_state_graph(spec, rel)
    assert [len(b) for b in reduced.model.fixed[0]] == [2, 2, 2, 2]
    exact = makespan(spec, full)
    assert makespan(reduced.spec, reduced) == exact
    assert conservative(reduced.spec, reduced) > exact


def test_full_precedences_and_start_order():
    """The chain is no precedence; what every pin needs stays one; the pins start in order."""
    from asp.schedule.assembly import assembly_schedule

    spec, rel = pinned_disc(3, 2)
    full = build_state_graph(spec, rel)
    reduced = reduced_state_graph(spec, rel)
    a = assembly_schedule(spec, full).problem
    b = assembly_schedule(reduced.spec, reduced).problem
    assert set(a.precedences) == set(b.precedences)
    ids = spec.op_ids
    assert [(ids[x], ids[y]) for x, y in b.start_order] == [
        ("pin0", "pin1"),
        ("pin1", "pin2"),
        ("screw0", "screw1"),
    ]
    assert not a.start_order


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    data=st.data(),
    copies=st.integers(2, 3),
    singles=st.integers(0, 2),
    grouping=st.sampled_from([None, *sorted(GROUPINGS)]),
)
def test_random_tables_keep_the_makespan(data, copies, singles, grouping):
    """Random tables of pins with their rollers, with or without units: the reduced graph's
    makespan (relabelled) is the full graph's."""
    spec, rel = random_alike_spec(data.draw, copies, singles, grouping)
    try:
        full = build_state_graph(spec, rel)
    except SpecError:
        return  # no complete sequence
    reduced = reduced_state_graph(spec, rel)
    if reduced is None or reduced.model.symmetric:
        return  # nothing reduced, or blocks moved first of equals (kept as they are)
    assert makespan(reduced.spec, reduced) == makespan(spec, full)


def test_a_block_out_of_its_order_fails_the_replay(ring):
    """Relabelling takes any roller for the next one, counts alone pass: the replay checks
    first that each roller's own pin ends before it starts."""
    spec, rel = ring
    reduced = reduced_state_graph(spec, rel)
    _, result = assembly_makespan(reduced.spec, reduced, time_limit=30.0, workers=1, seed=0)
    rows = [dict(r) for r in result.detail["schedule"]]
    model = replay_model(reduced.spec, reduced)
    assert schedule_violation(model, rows) is None
    by_task = {r["task"]: r for r in rows}
    pins = sorted((r for r in rows if r["task"].startswith("pin")), key=lambda r: r["end"])
    first, last = pins[0], pins[-1]
    roller = by_task["roller" + first["task"][3:]]
    assert roller["start"] < last["end"]  # the first pin's roller starts before the last pin ends
    first["task"], last["task"] = last["task"], first["task"]
    message, cut = schedule_violation(model, rows)
    ids = reduced.spec.op_ids
    assert "starts before" in message
    assert cut == [(ids.index(last["task"]), ids.index(roller["task"]))]
