"""Products of the unseen kinds, built in code (tests/cad/products.py): a ballpoint pen, a
gearbox with meshing spur gears and a shear mold. Each must give the free directions an
engineer expects and plan with default settings from a folder of meshes or a glTF scene
into a plan the independent checker accepts."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from cad import DIRECTIONS, Assembly, compute_relations
from tests.asmplan.checked import plan_and_check
from tests.cad import products
from tests.cad.test_loading import write_folder, write_scene

BUILDERS = {
    "pen": products.ballpoint_pen,
    "pen_lying": functools.partial(products.ballpoint_pen, axis="x"),
    "gearbox": products.gearbox,
    "gearbox_tight": functools.partial(products.gearbox, backlash=-0.1),
    "shear_mold": products.shear_mold,
}
SIDE = {"+x", "-x", "+y", "-y"}
DOWN = DIRECTIONS.index("-z")


@functools.cache
def relations(name: str):
    return compute_relations(Assembly.from_meshes(BUILDERS[name]()))


def dirs(row) -> set[str]:
    return {d for d, v in zip(DIRECTIONS, row, strict=True) if v}


# (product, i, j, TT_d(i, j): directions in which i leaves past j)
FREE = [
    ("pen", "refill", "barrel", {"+z"}),
    ("pen", "spring", "barrel", {"+z"}),
    ("pen", "refill", "spring", {"+z"}),
    ("pen", "plug", "barrel", {"+z"}),
    ("pen", "barrel", "cap", {"+z"}),
    ("pen", "clip", "cap", {"+z"}),
    ("pen_lying", "refill", "barrel", {"+x"}),
    ("pen_lying", "clip", "cap", {"+x"}),
    ("gearbox", "gear_a", "shaft_a", {"+z"}),  # along its shaft only, off the collar
    ("gearbox", "gear_a", "gear_b", {"-x", "+z", "-z"}),  # teeth: along z or apart
    ("gearbox", "gear_b", "gear_a", {"+x", "+z", "-z"}),
    ("gearbox", "shaft_a", "housing", {"+z"}),
    ("gearbox", "lid", "shaft_b", {"+z"}),
    ("gearbox_tight", "gear_a", "gear_b", {"-x", "+z", "-z"}),
    ("shear_mold", "guide_pin_1", "lower_shoe", {"+z"}),
    ("shear_mold", "guide_pin_1", "bushing_1", {"+z", "-z"}),  # slides in its bushing
    ("shear_mold", "dowel_1", "die_plate", {"+z", "-z"}),
    ("shear_mold", "die_plate", "lower_shoe", set(DIRECTIONS) - {"-z"}),
    ("shear_mold", "punch", "die_plate", {"+z"}),
    ("shear_mold", "bushing_2", "upper_shoe", {"+z"}),
]

# (product, part, the parts that stop it falling)
SUPPORT = [
    ("pen", "spring", {"barrel"}),
    ("pen", "refill", {"barrel", "spring"}),
    ("pen", "clip", {"cap"}),
    ("gearbox", "gear_a", {"shaft_a"}),
    ("gearbox", "shaft_b", {"housing"}),
    ("shear_mold", "guide_pin_2", {"lower_shoe"}),
    ("shear_mold", "dowel_2", {"lower_shoe"}),
    ("shear_mold", "die_plate", {"lower_shoe", "dowel_1", "dowel_2"}),
    ("shear_mold", "punch", set()),  # screwed to the upper shoe in a real die: held
]


@pytest.mark.parametrize(
    ("name", "i", "j", "free"), FREE, ids=[f"{f[0]}:{f[1]}-{f[2]}" for f in FREE]
)
def test_free_directions(name, i, j, free):
    rel = relations(name)
    assert dirs(rel.tt[rel.index(i), rel.index(j)]) == free


@pytest.mark.parametrize(("name", "part", "by"), SUPPORT, ids=[f"{s[0]}:{s[1]}" for s in SUPPORT])
def test_support(name, part, by):
    rel = relations(name)
    assert {rel.parts[j] for j in np.flatnonzero(rel.sp[rel.index(part), :, DOWN])} == by


def test_meshing_gears_touch_without_interfering():
    for name in ("gearbox", "gearbox_tight"):
        rel = relations(name)
        a, b = rel.index("gear_a"), rel.index("gear_b")
        assert {"+x", "+y", "-y"} == dirs(rel.tc[a, b])
        assert dirs(rel.tc[a, rel.index("shaft_a")]) - {"-z"} == SIDE


@pytest.mark.slow
@pytest.mark.parametrize(
    ("name", "kind"),
    [("pen", "folder"), ("pen_lying", "glb"), ("gearbox", "glb"), ("gearbox_tight", "folder"),
     ("shear_mold", "folder")],
)  # fmt: skip
def test_product_plans_with_defaults_and_the_checker_accepts(tmp_path, name, kind):
    assembly = Assembly.from_meshes(BUILDERS[name]())
    if kind == "folder":
        source = write_folder(tmp_path / name, assembly)
    else:
        source = write_scene(tmp_path / f"{name}.glb", assembly, scale=0.001)
    plan_and_check(source, tmp_path / "out", "--time-limit", "5")
