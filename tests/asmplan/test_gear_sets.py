"""Gear sets built in code (tests/cad/products.py): a helical pair and a planetary stage.

Meshing teeth are a contact that blocks rotation, not translation along the shafts: spur
teeth (the planets with the sun and the ring) let a gear slide along its axis or leave its
mate along the line of centres; helical teeth block the slide too (a helical gear cannot
slide onto its shaft past its mate). Both plan with default settings into plans both
checkers accept; the three planets are one class of interchangeable parts, and the
reduced graph keeps the full graph's TCT and W*."""

from __future__ import annotations

import functools

import pytest

from asmplan import pipeline
from asp.fromcad.generate import gravity_choice
from asp.game.solve import solve
from asp.graph.game_dag import game_dag
from asp.graph.state_graph import build_state_graph
from asp.graph.symmetry import interchangeable_blocks
from asp.spec import with_subassemblies
from asp.subassemblies import prepared_units
from cad import DIRECTIONS, Assembly, compute_relations
from tests.asmplan.checked import plan_and_check
from tests.cad import products
from tests.cad.test_loading import write_folder


@functools.cache
def relations(name: str):
    return compute_relations(Assembly.from_meshes(getattr(products, name)()))


def free(name: str, i: str, j: str) -> set[str]:
    rel = relations(name)
    row = rel.tt[rel.index(i), rel.index(j)]
    return {d for d, v in zip(DIRECTIONS, row, strict=True) if v}


@pytest.mark.parametrize(
    ("name", "i", "j", "expected"),
    [
        ("helical_pair", "gear_a", "gear_b", {"-x"}),  # apart only: the helix blocks z
        ("helical_pair", "gear_b", "gear_a", {"+x"}),
        ("helical_pair", "gear_a", "shaft_a", {"+z"}),
        ("planetary_stage", "planet_1", "sun", {"+x", "+z", "-z"}),  # along its pin or apart
        ("planetary_stage", "planet_1", "ring", {"+z", "-z"}),
        ("planetary_stage", "ring", "planet_2", {"+z", "-z"}),
        ("planetary_stage", "sun", "planet_1", {"-x", "+z", "-z"}),
    ],
)
def test_meshing_teeth_block_what_they_should(name, i, j, expected):
    assert free(name, i, j) == expected


def test_a_helical_pair_blocked_on_its_shafts_is_not_called_another_axis_up():
    """Along -z no order exists even with every part held (the helix, not gravity): the
    sideways plan is said as such, never as a Y-up file."""
    assembly = Assembly.from_meshes(products.helical_pair())
    choice = gravity_choice(relations("helical_pair"), assembly, "-z")
    assert choice.feasible["-z"] is False and choice.blocked_anyway
    assert "even with every part held" in choice.reason and "likely" not in choice.reason


@pytest.mark.slow
def test_a_helical_pair_plans_with_defaults(tmp_path):
    assembly = Assembly.from_meshes(products.helical_pair())
    source = write_folder(tmp_path / "helical", assembly)
    plan_and_check(source, tmp_path / "out", "--time-limit", "5")


@pytest.fixture(scope="module")
def planetary_graphs(tmp_path_factory):
    folder = write_folder(
        tmp_path_factory.mktemp("planetary"), Assembly.from_meshes(products.planetary_stage())
    )
    assembly = pipeline.load(folder, on_step=lambda _: None)
    reduced = pipeline.state_graph(assembly)
    spec = prepared_units(
        with_subassemblies(assembly.spec, reduced.spec.subassemblies), assembly.relations
    )
    return folder, spec, assembly.relations, reduced, build_state_graph(spec, assembly.relations)


def test_the_planets_are_interchangeable_and_the_reduction_keeps_the_game(planetary_graphs):
    _, spec, rel, reduced, full = planetary_graphs
    placed = {op.id: op.parts[0] for op in spec.operations if op.parts}
    # a planet with its pin is a block (either may go first: not a chain, so the blocks
    # are moved first of equals rather than put in a fixed order)
    classes = interchangeable_blocks(spec, rel, chains_only=False)
    blocks = [sorted(placed[op] for op in block) for cls in classes for block in cls]
    assert sorted(blocks) == [[f"pin_{k}", f"planet_{k}"] for k in (1, 2, 3)]
    assert reduced.n_states < full.n_states
    a, b = (solve(game_dag(g, cost="time")) for g in (full, reduced))
    assert (b.tct, b.minimax) == (a.tct, a.minimax)


@pytest.mark.slow
def test_a_planetary_stage_plans_with_defaults(planetary_graphs, tmp_path):
    folder = planetary_graphs[0]
    doc = plan_and_check(folder, tmp_path / "out", "--time-limit", "5")
    assert doc["gravity"] == "-z"
