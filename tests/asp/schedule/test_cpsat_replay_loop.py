"""The CP-SAT replay loop on assemblies where fixed precedences are not enough.

Random small assemblies whose parts rest on one of several others (an OR of supports, not a
precedence) or block each other: the loop must cut, return only schedules that replay through
the state graph, claim OPTIMAL only at the concurrent game's W*(0), and always have a schedule
(the list schedule along a state-graph path is the fallback).
"""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from asp.concurrent.build import build_game
from asp.concurrent.model import concurrent_model
from asp.concurrent.robustness import value
from asp.game.solve import solve
from asp.graph.state_graph import build_state_graph
from asp.schedule.assembly import assembly_schedule
from asp.schedule.assembly_makespan import assembly_makespan
from asp.schedule.cuts import PlacementCuts
from asp.schedule.list_schedule import list_schedule
from asp.schedule.makespan import min_makespan
from asp.schedule.replay import replay_model, schedule_violation
from asp.spec import spec_from_dict
from tests.asp.helpers_assembly import relations


@st.composite
def resting_assemblies(draw):
    """A base B and 2..5 parts; each rests on one to three parts placed before it in a
    hidden order (any of them supports it), and some parts block others from above."""
    k = draw(st.integers(2, 5))
    parts = ["B"] + [f"P{i}" for i in range(k)]
    contacts, blocks = [], []
    for i in range(k):
        below = draw(st.lists(st.sampled_from(parts[: i + 1]), min_size=1, max_size=3, unique=True))
        contacts += [(f"P{i}", q, "-z") for q in below]
        if i and draw(st.booleans()):  # an earlier part cannot come down past this one
            j = draw(st.integers(0, i - 1))
            blocks.append((f"P{j}", f"P{i}", "+z"))
    rel = relations(tuple(parts), contacts=contacts, blocks=blocks)
    ops = []
    for i in range(k):
        allowed = draw(st.lists(st.sampled_from(["H", "R1"]), min_size=1, max_size=2, unique=True))
        ops.append(
            {
                "id": f"p{i}",
                "agents": {a: draw(st.integers(1, 6)) for a in allowed},
                "part": f"P{i}",
            }
        )
    used = {a for op in ops for a in op["agents"]}
    agents = {a: {"side": "human" if a == "H" else "robot"} for a in ("H", "R1") if a in used}
    spec = spec_from_dict(
        {"name": "resting", "parts": parts, "base_part": "B", "agents": agents, "operations": ops}
    )
    return spec, rel


def graph_of(spec, rel):
    try:
        graph = build_state_graph(spec, rel)
    except ValueError:  # no complete sequence (blocked every way)
        assume(False)
    return graph


def w0(spec, graph) -> float:
    game = build_game(concurrent_model(spec, graph), 0)
    return value(game, solve(game.dag), 0)


def ladder():
    """Three posts A, C, E on the base, and a cap on top of each post; either cap of a pair
    (A with C, C with E) may carry a bar over the pair. Fixed precedences allow the bars at
    once; the state graph needs a cap under each first."""
    parts = ("B", "A", "C", "E", "a", "c", "e", "X", "Y")
    contacts = [(p, "B", "-z") for p in "ACE"] + [("a", "A", "-z"), ("c", "C", "-z")]
    contacts += [("e", "E", "-z"), ("X", "a", "-z"), ("X", "c", "-z")]
    contacts += [("Y", "c", "-z"), ("Y", "e", "-z")]
    rel = relations(parts, contacts=contacts)
    ops = [{"id": p, "agents": {"R1": 2, "H": 3}, "part": p} for p in parts[1:7]]
    ops += [
        {"id": "X", "agents": {"H": 6}, "part": "X"},
        {"id": "Y", "agents": {"H": 6}, "part": "Y"},
    ]
    spec = spec_from_dict(
        {
            "name": "ladder",
            "parts": list(parts),
            "base_part": "B",
            "agents": {"H": {"side": "human"}, "R1": {"side": "robot"}},
            "operations": ops,
        }
    )
    return spec, build_state_graph(spec, rel)


def test_ladder_needs_cuts_and_ends_optimal():
    spec, graph = ladder()
    relaxed = min_makespan(assembly_schedule(spec, graph).problem, time_limit=10)
    assert schedule_violation(replay_model(spec, graph), relaxed.detail["schedule"]) is not None
    _, result = assembly_makespan(spec, graph, time_limit=20)
    assert result.status == "OPTIMAL" and result.detail["cuts"] >= 1
    assert schedule_violation(replay_model(spec, graph), result.detail["schedule"]) is None
    assert result.objective == w0(spec, graph)
    assert result.bound == result.objective


def test_short_cuts_name_the_supports():
    spec, graph = ladder()
    cuts = PlacementCuts(graph)
    ids = spec.op_ids
    # X right after A, C alone: it needs a cap (a or c) first.
    cut = cuts.cut({ids.index("A"), ids.index("C")}, ids.index("X"))
    assert sorted(ids[y] for y, _ in cut) == ["a", "c"]
    assert {ids[x] for _, x in cut} == {"X"}


def test_list_schedule_along_a_sequence_and_off_the_graph():
    spec, graph = ladder()
    model = replay_model(spec, graph)
    problem = assembly_schedule(spec, graph).problem
    for sequence in graph.sequences(limit=20):
        rows = list_schedule(model, problem, sequence)
        assert rows is not None and schedule_violation(model, rows) is None
    # Not a path of the state graph: the bar before any cap.
    assert list_schedule(model, problem, ["X", "A", "C", "E", "a", "c", "e", "Y"]) is None


def test_time_out_reports_the_fallback_as_feasible():
    spec, graph = ladder()
    model = replay_model(spec, graph)
    problem = assembly_schedule(spec, graph).problem
    fallback = list_schedule(model, problem)

    def replay(rows):
        found = schedule_violation(model, rows)
        return None if found is None else found[1]

    # Every cut is a schedule to throw away; with a budget of one solve the fallback stands.
    result = min_makespan(problem, time_limit=1e-3, replay=replay, incumbent=fallback)
    assert result.status in ("FEASIBLE", "OPTIMAL")
    assert result.detail["schedule"] and result.detail["replay"] == "passed"
    assert schedule_violation(model, result.detail["schedule"]) is None
    if result.status == "FEASIBLE":  # a bound only when a solve proved one
        assert result.bound is None or result.bound <= result.objective


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(resting_assemblies(), st.sampled_from([1e-3, 0.05, 20.0]))
def test_any_returned_schedule_replays(data, time_limit):
    spec, rel = data
    graph = graph_of(spec, rel)
    _, result = assembly_makespan(spec, graph, time_limit=time_limit)
    assert result.status in ("OPTIMAL", "FEASIBLE")  # the fallback is always there
    rows = result.detail["schedule"]
    assert schedule_violation(replay_model(spec, graph, cuts=False), rows) is None
    best = w0(spec, graph)
    assert result.bound is None or result.bound <= best + 1e-9
    assert best <= result.objective + 1e-9
    if result.status == "OPTIMAL":
        assert result.objective == pytest.approx(best)
    if time_limit == 20.0:
        assert result.status == "OPTIMAL"


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(resting_assemblies())
def test_short_cuts_hold_for_every_feasible_schedule(data):
    """Every short cut (for every state and every operation it cannot take) is satisfied by
    the list schedule along every complete sequence of the state graph."""
    spec, rel = data
    graph = graph_of(spec, rel)
    model = replay_model(spec, graph)
    problem = assembly_schedule(spec, graph).problem
    schedules = []
    for sequence in graph.sequences(limit=50):
        rows = list_schedule(model, problem, sequence)
        assert rows is not None
        schedules.append(
            {spec.op_ids.index(r["task"]): (float(r["start"]), float(r["end"])) for r in rows}
        )
    alive = graph.coreachable()
    n = len(spec.op_ids)
    for s in range(graph.n_states):
        if not alive[s]:
            continue
        done = {i for i in range(n) if graph.key(s) >> i & 1}
        for b in range(n):
            if b in done or model.steps.get((s, b)) is not None:
                continue
            cut = model.cuts.cut(done, b)
            if cut is None:
                continue
            for sched in schedules:
                assert any(sched[y][1] <= sched[x][0] for y, x in cut), (done, b, cut)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(resting_assemblies())
def test_early_cuts_hold_for_every_feasible_schedule(data):
    """The cuts for operations a schedule starts too early (:meth:`PlacementCuts.early`):
    none for a feasible schedule, and each one found for the relaxed CP-SAT schedule is
    satisfied by the list schedule along every complete sequence."""
    spec, rel = data
    graph = graph_of(spec, rel)
    model = replay_model(spec, graph)
    problem = assembly_schedule(spec, graph).problem
    n = len(spec.op_ids)

    def times(rows):
        out = {spec.op_ids.index(r["task"]): (float(r["start"]), float(r["end"])) for r in rows}
        return [out[i][0] for i in range(n)], [out[i][1] for i in range(n)]

    feasible = [times(list_schedule(model, problem, s)) for s in graph.sequences(limit=50)]
    for start, end in feasible:
        assert model.cuts.early(start, end) == []
    relaxed = min_makespan(problem, time_limit=10).detail["schedule"]
    for cut in model.cuts.early(*times(relaxed)):
        for start, end in feasible:
            assert any(end[y] <= start[x] for y, x in cut), cut
