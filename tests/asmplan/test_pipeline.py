"""The public pipeline: each step on its own gives what ``asmplan plan`` gives."""

from __future__ import annotations

import dataclasses

import pytest
from typer.testing import CliRunner

from asmplan import pipeline
from asmplan.cli import app
from asp.game.io import save_dag
from tests.asp.figures import figure4
from tests.cad import shapes
from tests.cad.test_loading import write_folder
from tests.cad.test_subassemblies import rod_tower, tower_spec
from tests.conftest import REPO

PUMP = REPO / "examples" / "vacuum_pump"
FIRST_STEPS = ("[1/5] reading the assembly", "[2/5] building the assembly state graph")


def test_steps_one_by_one_agree_with_the_whole_plan():
    assembly = pipeline.load(PUMP)
    assert assembly.spec.name == "vacuum pump" and assembly.relations is not None
    graph = pipeline.state_graph(assembly)
    dag = pipeline.game(graph, cost="time")
    solution = pipeline.solve_game(dag)
    steps = pipeline.robust_plan(pipeline.Game(dag, assembly.descriptions), solution)
    lines = []
    whole = pipeline.plan(assembly, cost="time", time_limit=20, on_step=lines.append)
    assert numbered(lines) == [
        *FIRST_STEPS,
        "[3/5] solving the robot-vs-human game",
        "[4/5] CP-SAT minimum-makespan schedule",
    ]
    assert (whole.solution.tct, whole.solution.minimax) == (solution.tct, solution.minimax)
    assert whole.steps == steps
    assert whole.graph.n_states == graph.n_states
    data = whole.to_dict()
    assert data["format"] == pipeline.PLAN_FORMAT and data["cost"] == "time"
    assert [s["operation"] for s in data["robust_plan"]] == [s.operation for s in steps]


def numbered(lines: list[str]) -> list[str]:
    """The numbered progress lines (``[3/5] ...``), up to their first ``" ..."``/``" and"``."""
    return [line.split(" ...")[0].split(" and")[0] for line in lines if line[:1] == "["]


def test_a_concurrent_plan_builds_no_alternating_game(monkeypatch):
    """Issue 23 item 4: with the turn model ``concurrent`` the alternating game is neither
    built nor solved (every entry to it refuses), CP-SAT comes first and each step is
    numbered once, in order; the plan keeps its keys (the policy, lines and metrics are
    the concurrent game's)."""
    import asp.graph.game_dag

    def refuse(*_args, **_kwargs):
        raise AssertionError("a concurrent plan must not build or solve the alternating game")

    for module, name in (
        (pipeline, "game"),
        (pipeline, "solve_game"),
        (pipeline, "robust_plan"),
        (pipeline, "played_game"),
        (asp.graph.game_dag, "game_dag"),
    ):
        monkeypatch.setattr(module, name, refuse)
    lines = []
    result = pipeline.plan(PUMP, turn_model="concurrent", time_limit=20, on_step=lines.append)
    assert numbered(lines) == [
        *FIRST_STEPS,
        "[3/5] CP-SAT minimum-makespan schedule",
        "[4/5] solving the concurrent game, W*(k) until flat",
    ]
    assert result.game is None and result.solution is None and result.played is None
    assert result.steps == ()
    with pytest.raises(ValueError, match="a concurrent plan has no alternating game"):
        _ = result.played_game
    doc = result.to_dict()
    assert doc["turn_model"] == "concurrent" and doc["policy"]["turn_model"] == "concurrent"
    assert doc["minimax"] == doc["robustness"][-2]["bound"] == 215  # W*(k) at the plan's k
    assert doc["tct"] == doc["metrics"]["w0"] == doc["schedule"]["objective"] == 215


def test_the_preview_is_solved_on_the_concurrent_plans_graph():
    """Issue 23 item 4: an alternate plan's graph puts the pinned disc's alike pins in a
    fixed order, so its concurrent game cannot place two at once (W*(0) 13 there, the
    schedule run as a plan 15, beside a CP-SAT optimum of 11). The preview is solved on
    the graph the concurrent plan uses, alike parts in any order: W*(0) and the schedule's
    worst case at k = 0 are the optimum, and it says that graph's size."""
    from tests.asp.graph.test_symmetry import pinned_disc

    spec, rel = pinned_disc(3, 1)
    assembly = pipeline.Assembly(spec, rel)
    graph = pipeline.state_graph(assembly)
    sched = pipeline.schedule(assembly, graph, time_limit=5)
    assert (sched.result.status, sched.result.objective) == ("OPTIMAL", 11)
    bounds = (sched.result, sched.lower_bound)
    fixed = pipeline.concurrent_preview(graph.spec, graph, schedule=bounds)
    # the search's rules undo the fixed order themselves (asp.concurrent.rules): 11, not
    # the compiled game's conservative 13 of before
    assert fixed["robustness"][0]["bound"] == 11
    preview = pipeline.alternate_preview(assembly, graph, schedule=bounds)
    assert preview["robustness"][0] == {
        "k": 0,
        "bound": 11,
        "lower": 11,
        "upper": 11,
        "exact": True,
    }
    assert preview["concurrent"]["schedule_worst_case"][0] == {"k": 0, "bound": 11}
    loose = pipeline.state_graph(assembly, concurrent=True)
    assert (preview["states"], preview["sequences"]) == (10, 4)
    assert (loose.n_states, loose.count_sequences()) == (10, 4)
    assert (graph.n_states, graph.count_sequences()) == (7, 1)


def test_a_preview_whose_concurrent_graph_is_too_large_says_so(monkeypatch):
    from tests.asp.graph.test_symmetry import pinned_disc

    spec, rel = pinned_disc(3, 1)
    assembly = pipeline.Assembly(spec, rel)
    graph = pipeline.state_graph(assembly)
    monkeypatch.setattr("asmplan.pipeline.PREVIEW_MAX_STATES", 8)  # 7 fixed, 10 loose
    assert pipeline.alternate_preview(assembly, graph) == {
        "why": "over 8 assembly states with alike parts in any order (the report solves the "
        "concurrent game up to 8)"
    }


@pytest.mark.parametrize("proved", [True, False])
def test_an_infeasible_assembly_graph_is_built_once(monkeypatch, proved):
    """Issue 22 B2: ``state_graph`` is one call of ``build_with_units``. The rod tower's
    holders never go in alone: each spec of the rounds (without units, then with the
    holders' units) is reduced once and its graph built once checked, once unchecked at
    most, never again by a first round of the pipeline's own; ``proved=False``: the
    derived precedences prove nothing, the state graph finds the stuck parts itself."""
    import asp.graph.precedences
    import asp.graph.state_graph
    import asp.graph.symmetry
    from cad import Assembly, compute_relations

    rel = compute_relations(Assembly.from_meshes(rod_tower()))
    calls = []

    def spy(module, name):
        real = getattr(module, name)

        def counted(spec, *args, **kwargs):
            calls.append((name, spec.subassemblies, kwargs.get("check", True)))
            return real(spec, *args, **kwargs)

        monkeypatch.setattr(module, name, counted)

    spy(asp.graph.state_graph, "build_state_graph")
    spy(asp.graph.symmetry, "symmetry_reduction")
    if not proved:
        monkeypatch.setattr(asp.graph.precedences, "refutation", lambda *_args, **_kw: None)
    lines = []
    graph = pipeline.state_graph(pipeline.Assembly(tower_spec(rel), rel), on_step=lines.append)
    assert len(graph.spec.subassemblies) == 2
    assert len(calls) == len(set(calls)), calls
    assert ("build_state_graph", (), False) in calls
    assert sum("trying subassemblies" in line for line in lines) == 1


def test_values_are_frozen():
    assembly = pipeline.load(PUMP)
    with pytest.raises(dataclasses.FrozenInstanceError):
        assembly.spec = None


def test_load_game_reads_graph_files_and_assemblies(tmp_path):
    path = save_dag(figure4(), tmp_path / "fig4.json")
    game = pipeline.load_game(path)
    assert game.dag.n_nodes == figure4().n_nodes and game.descriptions == {}
    with pytest.raises(ValueError, match="--cost applies to assemblies only"):
        pipeline.load_game(path, cost="time")
    pump = pipeline.load_game(PUMP, cost="steps")
    assert pump.dag.cost_model == "steps" and "1.1" in pump.descriptions
    with pytest.raises(FileNotFoundError, match="nope"):
        pipeline.load_game(tmp_path / "nope")


def test_relations_of_a_folder_read_its_assembly_yaml(tmp_path):
    """Issue 14, item 8: ``relations FOLDER`` ignored the folder's assembly.yaml."""
    folder = write_folder(tmp_path / "asm", shapes.boxed_container())
    plain = pipeline.part_relations(folder)
    files = sorted(p.name for p in folder.iterdir() if p.suffix == ".stl")
    parts = "\n".join(f"  - {{id: P{k}, file: {name}}}" for k, name in enumerate(files))
    ops = "\n".join(f"  - {{id: '{k}', agents: {{H: 1}}, part: P{k}}}" for k in range(len(files)))
    (folder / "assembly.yaml").write_text(
        f"units: mm\nparts:\n{parts}\nagents: {{H: {{side: human}}}}\noperations:\n{ops}\n"
    )
    through_yaml = pipeline.part_relations(folder)
    assert through_yaml.parts == tuple(f"P{k}" for k in range(len(files)))
    assert len(plain.parts) == len(through_yaml.parts)

    (folder / "assembly.yaml").write_text("parts: [oops\n")
    result = CliRunner().invoke(app, ["relations", str(folder)])
    assert result.exit_code == 2
    assert "assembly.yaml" in result.output


def test_the_plan_says_which_joining_parts_it_put_in_order(monkeypatch):
    """Issue 24: screws put in one order past the state limit are a rule of the cell; the
    plan says so (``fasteners_in_order``, in the schema), and says nothing without it."""
    from asmplan.planfile import validate_plan
    from asp.graph.fasteners import fastener_order
    from tests.asp.graph.test_fasteners import screwed_brackets

    monkeypatch.setattr(pipeline, "geometry_record", lambda *_: None)  # table relations
    spec, rel = screwed_brackets(n_brackets=3, screws=2)  # 125 states in all, 22 ordered
    doc = pipeline.plan(pipeline.Assembly(spec, rel), max_states=40, time_limit=5).to_dict()
    validate_plan(doc)
    chain = [[j.part, *j.joins] for j in fastener_order(spec, rel)[1]]
    assert len(chain) == 6
    assert doc["fasteners_in_order"] == chain
    free = pipeline.plan(pipeline.Assembly(spec, rel), time_limit=5).to_dict()
    assert free["fasteners_in_order"] == []


def test_a_round_guessed_for_a_proved_failure_stops_at_a_margin_of_one(monkeypatch):
    """Issue 24: past the state limit, a round of units guessed for a proved failure
    ends in the proof's error; its graph is given up as soon as the projection passes the
    limit (margin 1; the toy truck without its flex: line built 8.6 M states, 26 s of its
    54, in a layer it did not need). The first round, with nothing behind it, keeps 2."""
    import asp.graph.state_graph
    from cad import Assembly, compute_relations

    rel = compute_relations(Assembly.from_meshes(rod_tower()))
    real = asp.graph.state_graph.build_state_graph
    margins = []

    def recording(spec, *args, **kwargs):
        margin = kwargs.get("projection_margin", asp.graph.state_graph.PROJECTION_MARGIN)
        margins.append((bool(spec.subassemblies), kwargs.get("check", True), margin))
        return real(spec, *args, **kwargs)

    monkeypatch.setattr(asp.graph.state_graph, "build_state_graph", recording)
    pipeline.state_graph(pipeline.Assembly(tower_spec(rel), rel))
    assert (True, True, 1) in margins  # the round with the holders' units
    assert all(m == 2 for units, check, m in margins if not units and check)
