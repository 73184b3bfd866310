"""Explanations: what blocks a part along each direction; overlaps that are unit mistakes."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import trimesh

from cad import Assembly, compute_relations
from cad.explain import peel_depths, why_blocked
from tests.cad import shapes


@pytest.fixture(scope="module")
def tower():
    """A base, a post on it, a cap on the post (stacked along z)."""
    b = shapes.box_between
    return compute_relations(
        Assembly.from_meshes(
            {
                "base": b((0, 0, 0), (40, 40, 5)),
                "post": b((15, 15, 5), (25, 25, 30)),
                "cap": b((10, 10, 30), (30, 30, 35)),
            }
        )
    )


def test_why_names_blockers_and_depth(tower):
    rows = {b.direction: b for b in why_blocked(tower, "post")}
    assert rows["+z"].blockers == ("cap",) and rows["+z"].depth == 1
    assert rows["-z"].blockers == ("base",) and rows["-z"].depth == 1
    assert rows["+x"].blockers == () and rows["+x"].depth == 0
    assert {b.direction: b.depth for b in why_blocked(tower, "base")}["-z"] == 0
    assert {b.direction: b.depth for b in why_blocked(tower, "base")}["+z"] == 2


def test_interlocked_parts_are_never_free():
    tt = np.ones((2, 2, 6), dtype=bool)
    tt[0, 1, 0] = tt[1, 0, 0] = False  # each blocks the other along +x
    assert peel_depths(tt, 0) == [None, None]
    assert peel_depths(tt, 1) == [0, 0]


def test_unknown_part_suggests_the_nearest(tower):
    with pytest.raises(ValueError, match=r"unknown part 'psot' \(did you mean post"):
        why_blocked(tower, "psot")


def _overlap_message(meshes, units="mm") -> str:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ValueError) as info:
            compute_relations(Assembly.from_meshes(meshes, units=units))
    return str(info.value)


def test_metres_read_as_millimetres_name_the_unit_and_never_say_about_0_mm():
    cubes = shapes.stacked_cubes(1.0)  # 10 mm cubes overlapping by 1 mm
    message = _overlap_message({p.id: p.mesh.copy().apply_scale(0.001) for p in cubes.parts})
    assert "interpenetrate" in message and "about 0 mm" not in message
    assert "only 0.0237 mm across: if its files are in metres use units m" in message


def test_millimetres_declared_as_metres():
    cubes = shapes.stacked_cubes(1.0)
    message = _overlap_message({p.id: p.mesh for p in cubes.parts}, units="m")
    assert "23.7 m across: if its numbers are millimetres" in message


def test_a_part_in_inches_among_millimetres_is_named():
    b = shapes.box_between
    message = _overlap_message(
        {
            "base": b((0, 0, 0), (100, 100, 10)),
            "cap": b((1, 1, 1), (2.5, 2.5, 2)),  # a 38 mm cap drawn in inches, nested in base
            "lid": b((0, 0, 10), (100, 100, 12)),
        }
    )
    assert "part 'cap' is about 60 times smaller than the others and sits nested" in message
    assert "its file may be in inches" in message


def test_a_part_in_metres_among_millimetres_warns_on_load(tmp_path):
    b = shapes.box_between
    folder = tmp_path / "mixed"
    folder.mkdir()
    b((0, 0, 0), (40, 40, 10)).export(folder / "base.stl")
    b((0, 0, 10), (40, 40, 12)).export(folder / "lid.stl")
    b((0, 0, 0.012), (0.01, 0.01, 0.03)).export(folder / "pin.stl")  # metres
    from cad import load_assembly

    with pytest.warns(UserWarning, match=r"part 'pin' is about \d+ times smaller .*metres"):
        load_assembly(folder)


def test_no_unit_hint_between_parts_of_one_scene_file(tmp_path):
    """A clutch's STEP: a disc spring 8 times the size of the others overlaps its neighbour
    deeply; one file has one unit, so the error names no unit (it said "the others may be
    in centimetres")."""
    b = shapes.box_between
    scene = trimesh.Scene()
    meshes = {
        "spring_1": b((0, 0, 0), (100, 100, 8)),
        "spring_2": b((0, 0, 4), (100, 100, 12)),  # 4 mm into spring_1
        **{f"pin_{k}": b((20 * k, 0, 12), (20 * k + 8, 8, 20)) for k in range(4)},
    }
    for name, mesh in meshes.items():
        scene.add_geometry(mesh.apply_scale(0.001), node_name=name, geom_name=name)
    path = tmp_path / "clutch.glb"
    scene.export(path)
    from cad import load_assembly

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ValueError, match="interpenetrate") as info:
            compute_relations(load_assembly(path))
    assert "may be in" not in str(info.value)
