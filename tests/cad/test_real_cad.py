"""Realistic CAD assemblies (tests/cad/real_shapes.py) with the default tolerances.

Each row is what a mechanical engineer expects of one ordered pair: the sides where j
touches i (TC) and the directions in which i can leave past j (TT). The same tables must
come out of the parts in memory, of a GLB scene in metres and of a 3MF file.
"""

from __future__ import annotations

import functools
import warnings
from pathlib import Path

import numpy as np
import pytest
import trimesh

from cad import DIRECTIONS, Assembly, compute_relations, load_assembly, tt_set
from cad.tolerances import part_shrink, part_thickness
from tests.cad import real_shapes
from tests.cad.test_loading import write_scene

ALL = set(DIRECTIONS)
SIDE = {"+x", "-x", "+y", "-y"}
AXIAL = {"+z", "-z"}

# (assembly, i, j, TC_d(i, j) directions, TT_d(i, j) directions)
PAIRS = [
    # finger-jointed box: fingers and tabs interfere by 0.2 mm, yet all are contacts
    ("finger_box", "lid", "front", {"+x", "-x", "-y", "-z"}, {"+y", "+z"}),
    ("finger_box", "lid", "left", {"-x", "+y", "-y", "-z"}, {"+x", "+z"}),
    ("finger_box", "lid", "bottom", set(), ALL - {"-z"}),
    ("finger_box", "bottom", "front", {"+x", "-x", "-y", "+z"}, {"+y", "-z"}),
    ("finger_box", "front", "bottom", {"+x", "-x", "+y", "-z"}, {"-y", "+z"}),
    ("finger_box", "front", "left", {"-x", "+y", "+z", "-z"}, {"+x", "-y"}),
    ("finger_box", "front", "right", {"+x", "+y", "+z", "-z"}, {"-x", "-y"}),
    ("finger_box", "front", "back", set(), ALL - {"+y"}),
    ("finger_box", "left", "back", {"+x", "+y", "+z", "-z"}, {"-x", "-y"}),
    # bearing stack: zero clearance at every shared diameter, other tessellations
    ("bearing_stack", "shaft", "inner_ring", SIDE, AXIAL),
    ("bearing_stack", "shaft", "outer_ring", set(), AXIAL),
    ("bearing_stack", "shaft", "housing", set(), AXIAL),
    ("bearing_stack", "shaft", "collar", SIDE, AXIAL),
    ("bearing_stack", "inner_ring", "outer_ring", SIDE, AXIAL),
    ("bearing_stack", "inner_ring", "collar", {"+z"}, ALL - {"+z"}),
    ("bearing_stack", "outer_ring", "housing", SIDE | {"-z"}, {"+z"}),
    ("bearing_stack", "housing", "outer_ring", SIDE | {"+z"}, {"-z"}),
    ("bearing_stack", "collar", "inner_ring", {"-z"}, ALL - {"-z"}),
    ("bearing_stack", "collar", "housing", set(), AXIAL),
    # bolted L-bracket: bolts drawn at the hole diameter, heads on washers, nuts below
    ("bolted_bracket", "bolt_1", "bracket", SIDE, {"+z"}),
    ("bolted_bracket", "bolt_1", "base", SIDE, {"+z"}),
    ("bolted_bracket", "bolt_1", "washer_1", SIDE | {"-z"}, {"+z"}),
    ("bolted_bracket", "bolt_1", "nut_1", SIDE, {"+z"}),
    ("bolted_bracket", "bolt_1", "bolt_2", set(), ALL - {"+x"}),
    ("bolted_bracket", "nut_1", "bolt_1", SIDE, {"-z"}),
    ("bolted_bracket", "nut_1", "washer_1b", {"+z"}, ALL - {"+z"}),
    ("bolted_bracket", "washer_1b", "base", {"+z"}, ALL - {"+z"}),
    ("bolted_bracket", "bracket", "base", {"-z"}, ALL - {"-z"}),
    ("bolted_bracket", "bracket", "bolt_2", SIDE, {"-z"}),
    ("bolted_bracket", "washer_2", "bracket", {"-z"}, ALL - {"+y", "-z"}),
    # spur gears: teeth overlap by about 0.2 mm, each gear on its own shaft
    ("gear_pair", "gear_a", "gear_b", {"+x", "+y", "-y"}, {"-x"} | AXIAL),
    ("gear_pair", "gear_b", "gear_a", {"-x", "+y", "-y"}, {"+x"} | AXIAL),
    ("gear_pair", "gear_a", "shaft_a", SIDE, AXIAL),
    ("gear_pair", "gear_b", "shaft_b", SIDE, AXIAL),
    ("gear_pair", "gear_a", "shaft_b", set(), ALL - {"+x"}),
    ("gear_pair", "gear_a", "plate", set(), ALL - {"-z"}),
    ("gear_pair", "shaft_a", "plate", SIDE | {"-z"}, {"+z"}),
]

# (assembly, part, subassembly, expected TT_d(part, S))
SUBSETS = [
    ("finger_box", "lid", {"front", "back", "left", "right", "bottom"}, {"+z"}),
    ("finger_box", "bottom", {"front", "back", "left", "right", "lid"}, {"-z"}),
    ("finger_box", "front", {"back", "left", "right", "bottom", "lid"}, {"-y"}),
    ("bearing_stack", "shaft", {"inner_ring", "outer_ring", "housing", "collar"}, AXIAL),
    ("bearing_stack", "outer_ring", {"housing", "inner_ring"}, {"+z"}),
    ("bolted_bracket", "bolt_1", {"base", "bracket", "washer_1", "washer_1b", "nut_1"}, {"+z"}),
    ("bolted_bracket", "bolt_1", {"base", "bracket", "washer_1"}, {"+z"}),
    ("bolted_bracket", "bracket", {"base", "bolt_1", "bolt_2"}, set()),
    ("gear_pair", "gear_a", {"plate", "shaft_a", "shaft_b", "gear_b"}, {"+z"}),
    ("gear_pair", "gear_b", {"shaft_b"}, AXIAL),
]


def dirs(row) -> set[str]:
    return {d for d, v in zip(DIRECTIONS, row, strict=True) if v}


@functools.cache
def meshes(name: str) -> dict[str, trimesh.Trimesh]:
    return real_shapes.BUILDERS[name]()


@functools.cache
def relations(name: str, source: str = "memory"):
    """Relations of assembly ``name`` built in memory or read back from a file."""
    if source == "memory":
        return compute_relations(Assembly.from_meshes(meshes(name)))
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        assembly = Assembly.from_meshes(meshes(name))
        if source == "glb":
            path = write_scene(Path(tmp) / f"{name}.glb", assembly, scale=0.001)
        else:
            path = write_scene(Path(tmp) / f"{name}.3mf", assembly)
        loaded = load_assembly(path)
        assert loaded.units == ("m" if source == "glb" else "mm")
        return compute_relations(loaded)


SOURCES = ["memory", "glb", "3mf"]


@pytest.mark.parametrize("source", SOURCES)
@pytest.mark.parametrize(
    ("name", "i", "j", "contact", "free"),
    PAIRS,
    ids=[f"{p[0]}:{p[1]}-{p[2]}" for p in PAIRS],
)
def test_pair_relations(source, name, i, j, contact, free):
    rel = relations(name, source)
    a, b = rel.index(i), rel.index(j)
    assert (dirs(rel.tc[a, b]), dirs(rel.tt[a, b])) == (contact, free)


@pytest.mark.parametrize("source", SOURCES)
@pytest.mark.parametrize(
    ("name", "part", "subset", "free"),
    SUBSETS,
    ids=[f"{s[0]}:{s[1]}" for s in SUBSETS],
)
def test_subassembly_freedom(source, name, part, subset, free):
    assert dirs(tt_set(relations(name, source), part, subset)) == free


@pytest.mark.parametrize("name", sorted(real_shapes.BUILDERS))
@pytest.mark.parametrize("source", ["glb", "3mf"])
def test_file_round_trip_gives_identical_tables(name, source):
    ref, rel = relations(name), relations(name, source)
    order = [rel.index(p) for p in ref.parts]
    assert np.array_equal(rel.tc[np.ix_(order, order)], ref.tc)
    assert np.array_equal(rel.tt[np.ix_(order, order)], ref.tt)


@pytest.mark.parametrize("name", sorted(real_shapes.BUILDERS))
def test_symmetries(name):
    rel = relations(name)
    flip = [1, 0, 3, 2, 5, 4]
    assert np.array_equal(rel.tc, rel.tc.transpose(1, 0, 2)[:, :, flip])
    assert np.array_equal(rel.tt, rel.tt.transpose(1, 0, 2)[:, :, flip])


@pytest.mark.parametrize(
    ("name", "pair", "depth"),
    [
        ("finger_box", r"'bottom' and 'front'", r"0\.2 mm"),
        ("gear_pair", r"'gear_a' and 'gear_b'", r"0\.2\d* mm"),
    ],
)
def test_fixtures_really_interfere_by_tenths(name, pair, depth):
    """With a tight explicit tolerance the same exports are rejected: the default rule
    is what accepts them. (Gear interference only shows once the pins are tolerated.)"""
    parts = meshes(name)
    if name == "gear_pair":
        parts = {k: v for k, v in parts.items() if k.startswith("gear")}
    with pytest.raises(ValueError, match=rf"{pair} (interpenetrate )?by about {depth}"):
        compute_relations(Assembly.from_meshes(parts), penetration_tol=0.1)


def test_overlap_deeper_than_tolerance_is_one_line_error_naming_pair_and_depth():
    parts = dict(meshes("bolted_bracket"))
    parts["bracket"] = parts["bracket"].copy().apply_translation((0, 0, -0.8))  # sunk
    with pytest.raises(ValueError) as info:
        compute_relations(Assembly.from_meshes(parts))
    message = str(info.value)
    assert "\n" not in message
    assert "'base' and 'bracket' interpenetrate by about 0.8 mm" in message
    assert "penetration tolerance of this pair 0.5 mm" in message


def test_non_watertight_part_warns_and_relations_still_come_out():
    parts = dict(meshes("bearing_stack"))
    collar = parts["collar"].copy()
    collar.update_faces(np.arange(len(collar.faces)) != 0)  # one missing triangle
    parts["collar"] = collar
    with pytest.warns(UserWarning, match="'collar' .*not watertight"):
        assembly = Assembly.from_meshes(parts)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rel = compute_relations(assembly)
    collar_i, inner = rel.index("collar"), rel.index("inner_ring")
    assert dirs(rel.tc[collar_i, inner]) == {"-z"}
    assert dirs(rel.tt[collar_i, inner]) == ALL - {"-z"}
    assert dirs(tt_set(rel, "shaft", {"inner_ring", "collar"})) == AXIAL


@pytest.mark.parametrize(
    ("mesh", "expected"),
    [
        (real_shapes.box((0, 0, 0), (10, 10, 10)), 0.052),  # 10 mm cube: by size
        (real_shapes.box((0, 0, 0), (200, 150, 6)), 0.25),  # big panel: capped
        (real_shapes.box((0, 0, 0), (100, 100, 0.5)), 0.0495),  # thin sheet: thickness
        (real_shapes.cylinder(1.5, 0, 8, 24), 0.027),  # M3 shank: by size, not eroded away
    ],
    ids=["cube", "panel", "sheet", "small screw"],
)
def test_default_shrink_rule(mesh, expected):
    diagonal = float(np.linalg.norm(np.ptp(mesh.bounds, axis=0)))
    assert part_shrink(diagonal, part_thickness(mesh)) == pytest.approx(expected, abs=1e-3)


def test_thin_sheet_between_parts_still_blocks():
    """A 0.5 mm sheet sandwiched between two big plates is not eroded away."""
    parts = {
        "low": real_shapes.box((0, 0, 0), (100, 100, 10)),
        "sheet": real_shapes.box((0, 0, 10), (100, 100, 10.5)),
        "high": real_shapes.box((0, 0, 10.5), (100, 100, 20.5)),
    }
    rel = compute_relations(Assembly.from_meshes(parts))
    low, high = rel.index("low"), rel.index("high")
    assert not rel.tt[low, high, 4] and not rel.tt[high, low, 5]
    assert dirs(rel.tc[rel.index("sheet"), low]) == {"-z"}
