"""The symmetry reduction on built geometry with a unit: a die set whose guide pins and
screws are alike in the main body and whose bushings and screws are alike in the upper
half's workspace. The reduced graphs the pipeline builds have the full graph's TCT and W*
(both costs), and the one for the concurrent turn model its W*(0) and W*(inf)."""

from __future__ import annotations

import pytest

from asmplan import pipeline
from asp.concurrent.model import concurrent_model
from asp.concurrent.robustness import robustness
from asp.game.solve import solve
from asp.graph.game_dag import game_dag
from asp.graph.state_graph import build_state_graph
from asp.graph.symmetry import interchangeable_blocks
from asp.spec import with_subassemblies
from asp.subassemblies import prepared_units


@pytest.fixture(scope="module")
def die_set_graphs(tmp_path_factory):
    from cad import Assembly
    from tests.cad.real_shapes import die_set
    from tests.cad.test_loading import write_folder

    folder = write_folder(tmp_path_factory.mktemp("die_set"), Assembly.from_meshes(die_set()))
    assembly = pipeline.load(folder, on_step=lambda _: None)
    reduced = pipeline.state_graph(assembly)
    loose = pipeline.state_graph(assembly, concurrent=True)
    units = reduced.spec.subassemblies
    assert loose.spec.subassemblies == units
    spec = prepared_units(with_subassemblies(assembly.spec, units), assembly.relations)
    full = build_state_graph(spec, assembly.relations)
    return spec, assembly.relations, reduced, full, loose


def test_alike_parts_in_the_body_and_in_the_workspace_are_classes(die_set_graphs):
    spec, rel, reduced, full, loose = die_set_graphs
    assert len(spec.subassemblies) == 1
    members = set(spec.subassemblies[0][1])
    placed = {op.id: op.parts[0] for op in spec.operations if op.parts}
    classes = [[placed[b[0]] for b in cls] for cls in interchangeable_blocks(spec, rel)]
    inside = [c for c in classes if set(c) <= members]
    outside = [c for c in classes if not set(c) & members]
    assert inside and outside and len(inside) + len(outside) == len(classes)
    assert reduced.n_states < loose.n_states < full.n_states


@pytest.mark.parametrize("cost", ["steps", "time"])
def test_the_reduced_graphs_keep_tct_and_w_star(die_set_graphs, cost):
    _, _, reduced, full, loose = die_set_graphs
    a = solve(game_dag(full, cost=cost))
    for graph in (reduced, loose):
        b = solve(game_dag(graph, cost=cost))
        assert (b.tct, b.minimax) == (a.tct, a.minimax)


def test_the_concurrent_graph_keeps_the_concurrent_game(die_set_graphs):
    _, _, _, full, loose = die_set_graphs
    a, b = (robustness(concurrent_model(g.spec, g), max_k=0) for g in (full, loose))
    assert (b.bounds, b.unbounded) == (a.bounds, a.unbounded)
