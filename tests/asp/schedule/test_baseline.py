"""CP-SAT baseline: minimum-cost path == TCT, and the makespan model with tool states."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from asp.game.dag import ANY, HUMAN, ROBOT, from_arrays, from_edges
from asp.game.solve import solve
from asp.game.synth import synthetic_dag
from asp.graph.game_dag import game_dag
from asp.graph.state_graph import build_state_graph
from asp.schedule.assembly import assembly_schedule
from asp.schedule.makespan import ScheduleProblem, Task, min_makespan
from asp.schedule.path import min_cost_path
from asp.spec import load_spec
from tests.asp.graph.test_state_graph import toggle_spec


@pytest.mark.parametrize(
    ("layers", "max_nodes"), [(4, 10), (10, 4), (10, 10), (15, 10), (20, 10), (20, 20)]
)
@pytest.mark.parametrize("seed", [0, 1])
def test_path_equals_tct_on_synthetic(layers, max_nodes, seed):
    dag = synthetic_dag(layers, max_nodes, 4, seed)
    result = min_cost_path(dag, time_limit=20)
    assert result.status == "OPTIMAL"
    assert result.objective == solve(dag).tct
    assert len(result.detail["edges"]) == result.objective
    assert result.detail["path"][0] == dag.node_ids[dag.start]
    assert result.detail["path"][-1] == dag.node_ids[dag.end]


@pytest.mark.parametrize("name", ["MERTENS", "JACKSON", "MITCHELL"])
def test_path_equals_tct_on_in2(shared_data, name):
    spec = load_spec(shared_data / "salbp" / f"{name}.IN2")
    dag = game_dag(build_state_graph(spec))
    result = min_cost_path(dag)
    assert result.objective == solve(dag).tct == len(spec.operations)
    assert "Scholl" in result.credit


@st.composite
def sided_dags(draw):
    """Random layered DAGs with random sides and fractional costs."""
    n = draw(st.integers(2, 9))
    src, dst = [], []
    for u in range(n - 1):
        targets = draw(st.lists(st.integers(u + 1, n - 1), min_size=1, max_size=3, unique=True))
        src += [u] * len(targets)
        dst += targets
    m = len(src)
    sides = draw(st.lists(st.sampled_from([ROBOT, HUMAN, ANY]), min_size=m, max_size=m))
    costs = draw(st.lists(st.sampled_from([0.5, 1.0, 2.0, 3.25]), min_size=m, max_size=m))
    return from_arrays(
        list(range(n)),
        np.array(src),
        np.array(dst),
        np.array(costs),
        np.array(sides, dtype=np.int8),
        start=0,
        end=n - 1,
    )


@settings(max_examples=40, deadline=None)
@given(sided_dags())
def test_path_equals_cooperative_value_under_turns(dag):
    result = min_cost_path(dag, time_limit=10)
    assert result.status == "OPTIMAL"
    assert result.objective == pytest.approx(solve(dag).tct)


def test_forced_passes_matter():
    # The robot moves first and may only take its own edge 0->1; the cheap direct edge 0->2
    # is the human's. Cooperative value under the turns: 1 (robot) + 5 (human 1->2).
    dag = from_edges(
        [0, 1, 2],
        [(0, 2), (0, 1), (1, 2)],
        costs=[1, 1, 5],
        sides=[HUMAN, ROBOT, HUMAN],
    )
    assert solve(dag).tct == 6
    assert min_cost_path(dag).objective == 6
    # Naively ignoring turns would give 1.
    assert (
        min_cost_path(from_edges([0, 1, 2], [(0, 2), (0, 1), (1, 2)], costs=[1, 1, 5])).objective
        == 1
    )


def test_repeatable_with_seed():
    dag = synthetic_dag(10, 10, 4, 3)
    a = min_cost_path(dag, workers=1, seed=5)
    b = min_cost_path(dag, workers=1, seed=5)
    assert a.detail["path"] == b.detail["path"] and a.objective == b.objective


def test_schedule_agents_and_precedence():
    problem = ScheduleProblem(
        name="toy",
        tasks=(
            Task("a", (("R", 3),)),
            Task("b", (("R", 4), ("H", 6))),
            Task("c", (("H", 2),)),
        ),
        precedences=((0, 2),),
    )
    result = min_makespan(problem)
    assert result.status == "OPTIMAL" and result.objective == 7
    rows = {r["task"]: r for r in result.detail["schedule"]}
    assert rows["b"]["agent"] == "R" or rows["b"]["end"] <= 7


def test_modes_of_different_lengths_share_no_end():
    # R1 does a (1), then H does b and c (1 each): makespan 3. With the modes' optional
    # intervals sharing one end variable, OR-Tools 9.15 proved 4 "OPTIMAL".
    problem = ScheduleProblem(
        name="modes",
        tasks=(
            Task("a", (("R1", 1), ("H", 2))),
            Task("b", (("H", 1), ("R1", 3))),
            Task("c", (("H", 1), ("R1", 3))),
        ),
        precedences=((0, 1), (0, 2)),
    )
    result = min_makespan(problem)
    assert result.status == "OPTIMAL" and result.objective == 3
    rows = {r["task"]: r for r in result.detail["schedule"]}
    assert rows["a"]["agent"] == "R1" and rows["a"]["end"] == 1


def test_schedule_respects_tool_states():
    spec = toggle_spec()
    graph = build_state_graph(spec)
    sched = assembly_schedule(spec, graph)
    result = min_makespan(sched.problem)
    assert result.status == "OPTIMAL"
    rows = {r["task"]: r for r in result.detail["schedule"]}
    # b needs cross: after x sets it, and y (back to hex) is not between x and b.
    assert rows["x"]["end"] <= rows["b"]["start"]
    assert rows["y"]["end"] <= rows["x"]["start"] or rows["b"]["end"] <= rows["y"]["start"]
    # a needs hex: before x, or after y when y follows x.
    a, x, y = rows["a"], rows["x"], rows["y"]
    assert a["end"] <= x["start"] or (x["end"] <= y["start"] and y["end"] <= a["start"])
    assert result.objective >= sched.lower_bound


def test_schedule_without_tool_constraint_would_be_shorter():
    # Two robot ops needing different bits, a human changing it: the change forces an order.
    problem = ScheduleProblem(
        name="bits",
        tasks=(
            Task("use_hex", (("R", 5),), requires=(("bit", "hex"),)),
            Task("change", (("H", 2),), sets=(("bit", "cross"),)),
            Task("use_cross", (("R", 5),), requires=(("bit", "cross"),)),
        ),
        tool_initial=(("bit", "hex"),),
    )
    result = min_makespan(problem)
    rows = {r["task"]: r for r in result.detail["schedule"]}
    assert rows["use_hex"]["end"] <= rows["change"]["start"] <= rows["change"]["end"]
    assert rows["change"]["end"] <= rows["use_cross"]["start"]
    assert result.objective == 12


def test_bad_solver_arguments():
    dag = synthetic_dag(4, 4, 2, 0)
    with pytest.raises(ValueError, match="workers"):
        min_cost_path(dag, workers=0)
    with pytest.raises(ValueError, match="time_limit"):
        min_cost_path(dag, time_limit=0)


@pytest.mark.parametrize(
    ("times", "pairs", "makespan"),
    [
        ([1, 1, 1, 1], [], 2),  # four free tasks, one worker per side: two rounds
        ([3, 1, 1, 1], [], 3),  # the long task on one side, the rest on the other
        ([2, 2, 2], [(1, 2), (2, 3)], 6),  # a chain: parallel sides do not help
        ([4, 1, 1, 2], [(1, 4), (2, 4), (3, 4)], 6),  # fork then join
    ],
)
def test_in2_tasks_open_to_either_side_use_both_sides_in_parallel(tmp_path, times, pairs, makespan):
    text = "\n".join([str(len(times)), *map(str, times), *(f"{a},{b}" for a, b in pairs)])
    (tmp_path / "t.IN2").write_text(text + "\n-1,-1\n")
    spec = load_spec(tmp_path / "t.IN2")
    sched = assembly_schedule(spec, build_state_graph(spec))
    result = min_makespan(sched.problem, time_limit=10, workers=1, seed=0)
    assert result.status == "OPTIMAL" and result.objective == makespan
    assert sched.lower_bound <= makespan
    assert sched.load_bound == pytest.approx(sum(times) / 2)


def test_one_node_graph_is_the_empty_path():
    """Issue 14, item 9: a one-node graph was INFEASIBLE although TCT is 0."""
    dag = from_edges(["only"], [], start="only", end="only")
    result = min_cost_path(dag)
    assert (result.status, result.objective) == ("OPTIMAL", 0)
    assert result.to_dict()["path"] == ["only"] and solve(dag).tct == 0


@pytest.mark.parametrize(
    ("costs", "rounded"),
    [((2e-7, 2e-7, 2e-7), False), ((8e-7,), False), ((1 / 3, 1 / 7), False), ((1e9, 1e-9), True)],
)
def test_tiny_and_unscalable_costs(costs, rounded):
    """Issue 14, item 9: a path of cost 6e-7 reported objective 0 (costs scaled by 10**6)."""
    n = len(costs) + 1
    dag = from_arrays(list(range(n)), np.arange(n - 1), np.arange(1, n), costs=list(costs))
    result = min_cost_path(dag)
    assert result.objective == pytest.approx(solve(dag).tct, rel=1e-12)
    assert result.to_dict()["objective"] == pytest.approx(sum(costs), rel=1e-9)
    assert result.detail.get("rounded", False) is rounded
    if not rounded:
        assert result.bound == pytest.approx(result.objective, rel=1e-9)


def test_durations_past_the_exact_range_are_refused():
    """Issue 14, item 5: a horizon beyond int64 was a TypeError inside OR-Tools."""
    from asp.errors import ScheduleError

    problem = ScheduleProblem(
        name="huge", tasks=tuple(Task(id=str(k), modes=(("", 4e15),)) for k in range(3))
    )
    with pytest.raises(ScheduleError, match="huge: durations too large for CP-SAT"):
        min_makespan(problem)


def test_spec_durations_past_the_cost_limit_are_refused_at_load(tmp_path):
    """Issue 14, item 5: magnitudes are checked at load, and the message says the limit."""
    from asp.spec import spec_from_dict

    data = {"agents": {"H": "human"}, "operations": [{"id": "a", "agents": {"H": 1e20}}]}
    with pytest.raises(
        ValueError, match=r"operations\[a\]\.agents\.H: expected a number up to 1e\+12"
    ):
        spec_from_dict(data, source="big.yaml")
