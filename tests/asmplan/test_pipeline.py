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


def test_steps_one_by_one_agree_with_the_whole_plan():
    assembly = pipeline.load(PUMP)
    assert assembly.spec.name == "vacuum pump" and assembly.relations is not None
    graph = pipeline.state_graph(assembly)
    dag = pipeline.game(graph, cost="time")
    solution = pipeline.solve_game(dag)
    steps = pipeline.robust_plan(pipeline.Game(dag, assembly.descriptions), solution)
    whole = pipeline.plan(assembly, cost="time", time_limit=20)
    assert (whole.solution.tct, whole.solution.minimax) == (solution.tct, solution.minimax)
    assert whole.steps == steps
    assert whole.graph.n_states == graph.n_states
    data = whole.to_dict()
    assert data["format"] == pipeline.PLAN_FORMAT and data["cost"] == "time"
    assert [s["operation"] for s in data["robust_plan"]] == [s.operation for s in steps]


@pytest.mark.parametrize("proved", [True, False])
def test_an_infeasible_assembly_graph_is_built_once(monkeypatch, proved):
    """Issue 22 B2: ``state_graph`` is one call of ``build_with_units``. The rod tower's
    holders never go in alone: each spec of the rounds (without units, then with the
    holders' units) is reduced once and its graph built once checked, once unchecked at
    most, never again by a first round of the pipeline's own; ``proved=False``: the
    derived precedences prove nothing, the state graph finds the stuck parts itself."""
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
        monkeypatch.setattr(asp.graph.symmetry, "refutation", lambda *_args, **_kw: None)
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
