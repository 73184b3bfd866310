"""The vacuum-pump case (paper, section 4.2): meshes, relations, the story, the CLI."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from asmplan.cli import app, main
from asp.game.plan import play_steps, relations_summary
from asp.game.solve import certified_worst_case, solve
from asp.graph.checker import check_line, plan_operations
from asp.graph.feasibility import load_relations
from asp.graph.game_dag import game_dag
from asp.graph.state_graph import build_state_graph
from asp.schedule.assembly import assembly_schedule
from asp.schedule.makespan import min_makespan
from asp.schedule.path import min_cost_path
from asp.spec import load_spec

PUMP = Path(__file__).resolve().parents[2] / "examples" / "vacuum_pump"


@pytest.fixture(scope="module")
def pump():
    spec = load_spec(PUMP)
    rel = load_relations(spec)
    graph = build_state_graph(spec, rel)
    return spec, rel, graph


def test_meshes_are_small_and_listed():
    for part in load_spec(PUMP).parts:
        path = PUMP / part.file
        assert path.is_file() and path.stat().st_size < 200 * 1024
    assert (PUMP / "bom.csv").read_text().startswith("id,name,file,quantity,type")


def test_relations_follow_the_drawing(pump):
    _, rel, _ = pump
    summary = {r["part"]: r for r in relations_summary(rel)}
    assert summary["PC"]["contacts"] == {"BD": ["-z"], "VT1": ["+z"]}
    assert summary["VT2"]["contacts"] == {"BC": ["-z"]}
    assert summary["EV"]["contacts"] == {"BD": ["+z"], "FOR": ["+z"]}
    for screw in ("VT1", "VT2", "VT3", "VT4"):
        assert summary[screw]["free"] == ["+z"]
    assert summary["EV"]["free"] == ["-z"]


def test_geometry_orders_what_the_spec_leaves_open(pump):
    spec, rel, graph = pump
    # FOR (5.4) rests on EV: geometry puts 5.2 first though the spec does not say so.
    assert "5.2" not in spec.operation("5.4").after
    for seq in graph.sequences(limit=200):
        assert seq.index("5.2") < seq.index("5.4")
        check_line(spec, rel, seq)
    assert graph.count_sequences() < build_state_graph(spec).count_sequences()


def test_state_graph_and_game(pump):
    spec, _, graph = pump
    assert graph.count_sequences() > 1
    for cost in ("steps", "time"):
        dag = game_dag(graph, cost=cost)
        sol = solve(dag)
        assert sol.tct <= sol.minimax
        assert min_cost_path(dag).objective == pytest.approx(sol.tct)
    assert solve(game_dag(graph, cost="steps")).tct == len(spec.operations)


def test_forgetful_human_story(pump):
    """The operator places BC with the hex bit still mounted: the robot adapts."""
    spec, _, graph = pump
    dag = game_dag(graph, cost="time")
    sol = solve(dag)
    order = {op: k for k, op in enumerate(spec.op_ids)}

    def forgetful(v, moves):
        ops = {dag.operations[e]: e for e in moves}
        if "2.2" in ops and "1.2" in ops:  # BC is there, the bit is not changed: place BC
            return ops["2.2"]
        others = [e for e in moves if dag.operations[e] != "1.2"] or moves
        return min(others, key=lambda e: order[dag.operations[e]])

    steps = play_steps(dag, sol.robot_policy, forgetful)
    done = [s.operation for s in steps if s.operation]
    assert sorted(done) == sorted(spec.op_ids)  # the plan completes
    check_line(spec, load_relations(spec), done)
    assert done.index("2.2") < done.index("1.2")  # BC placed with the hex bit on
    assert done.index("2.5") < done.index("1.2")  # the robot screws VT2 with hex first
    assert done.index("1.2") < done.index("1.6") < done.index("2.1")
    cost = sum(s.cost for s in steps)
    assert cost <= sol.minimax + 1e-9
    assert certified_worst_case(dag, sol.robot_policy) == pytest.approx(sol.minimax)


def test_makespan_beats_the_serial_time(pump):
    spec, _, graph = pump
    sched = assembly_schedule(spec, graph)
    result = min_makespan(sched.problem, time_limit=20)
    assert result.status == "OPTIMAL"
    serial = solve(game_dag(graph, cost="time")).tct
    assert sched.lower_bound <= result.objective < serial
    rows = {r["task"]: r for r in result.detail["schedule"]}
    assert rows["1.2"]["end"] <= rows["1.6"]["start"]


def test_plan_command_writes_plan_and_picture(tmp_path, pump):
    out = CliRunner().invoke(app, ["plan", str(PUMP), "--output", str(tmp_path)])
    assert out.exit_code == 0, out.output
    for text in ("states", "TCT", "W*", "robust plan", "CP-SAT makespan", "touches"):
        assert text in out.output
    plan = json.loads((tmp_path / "plan.json").read_text())
    assert plan["states"] > 0 and plan["sequences"] > 0
    assert plan["tct"] <= plan["minimax"]
    assert {s["operation"] for s in plan["robust_plan"] if s["operation"]} == set(
        load_spec(PUMP).op_ids
    )
    assert plan["schedule"]["status"] == "OPTIMAL"
    spec, rel, _ = pump
    check_line(spec, rel, plan_operations(plan))
    assert (tmp_path / "dag.png").read_bytes()[:4] == b"\x89PNG"


def test_graph_command(tmp_path, shared_data):
    target = tmp_path / "g.json"
    out = CliRunner().invoke(app, ["graph", str(PUMP), "--output", str(target)])
    assert out.exit_code == 0, out.output
    data = json.loads(out.output)
    assert {"states", "transitions", "sequences", "game_nodes", "game_edges"} <= set(data)
    from asp.game.io import load_dag

    dag = load_dag(target)
    assert dag.n_nodes == data["game_nodes"] and dag.operations is not None
    jackson = shared_data / "salbp" / "JACKSON.IN2"
    out = CliRunner().invoke(app, ["graph", str(jackson), "-o", str(target), "--cost", "time"])
    data = json.loads(out.output)
    assert (data["states"], data["transitions"], data["sequences"]) == (52, 112, 756)
    base = CliRunner().invoke(app, ["baseline", str(target), "--format", "json"])
    assert json.loads(base.output)["objective"] == 46


def test_bad_input_is_a_one_line_error(tmp_path, capsys):
    (tmp_path / "assembly.yaml").write_text(
        "agents: {H: {side: human}}\noperations: [{id: a, agents: {R7: 1}}]\n"
    )
    with pytest.raises(SystemExit) as info:
        main(["graph", str(tmp_path), "--output", str(tmp_path / "g.json")])
    assert info.value.code == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("asmplan: error: ") and "unknown agent 'R7'" in err
    assert "\n" not in err
    assert not (tmp_path / "g.json").exists()
