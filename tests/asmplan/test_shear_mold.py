"""A shear die set planned the way a toolmaker builds one, with default settings.

The lower half stands on the bench; the upper half is built as a unit in its own
workspace, upside down (its top plate on the bench: right side up its bushings and screws
fall out), then turned over and lowered onto the guide pins. Drawn open, the upper half
rests on nothing of the lower half when it arrives (the bushings slide on the pins), so by
the support test its insertion is held. The plan says all of it (``workspaces[].gravity``)
and both checkers accept it: the relations checker and the mesh replay.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from asmplan import pipeline
from asmplan.cli import app
from asp.fromcad.orientation import opposite, orient_units, unit_orientation
from asp.graph.checker import PlanCheckError, check_line, plan_operations
from asp.spec import with_subassemblies
from tests.asmplan.checked import plan_and_check
from tests.asmplan.mesh_replay import replayed
from tests.cad.real_shapes import die_set
from tests.cad.test_subassemblies import write_glb

UPPER = ("top_", "bushing", "punch", "stripper")


def die_set_glb(folder: Path) -> Path:
    """The die set as a Y-up glTF with the product tree a CAD export has."""
    parts = die_set()
    upper = [p for p in parts if p.startswith(UPPER)]
    lower = [p for p in parts if p not in upper]
    tree = {
        "Product": ["lower_die_set", "upper_die_set"],
        "lower_die_set": lower,
        "upper_die_set": upper,
    }
    path = folder / "die_set.glb"
    write_glb(path, parts, tree)
    return path


@pytest.fixture(scope="module")
def die_set_plan(tmp_path_factory):
    folder = tmp_path_factory.mktemp("die_set")
    source = die_set_glb(folder)
    return source, plan_and_check(source, folder / "out", "--time-limit", "5")


def test_the_upper_half_is_built_upside_down_and_lowered_onto_the_pins(die_set_plan):
    _, plan = die_set_plan
    assert plan["gravity"] == "-y"  # glTF: y up
    spaces = {w["id"]: w for w in plan["workspaces"]}
    assert spaces["main"]["gravity"] == "-y"
    upper = spaces["upper_die_set"]
    assert upper["gravity"] == "+y"  # upside down in its own workspace
    assert sorted(upper["parts"]) == sorted(p for p in die_set() if p.startswith(UPPER))
    assert upper["parts"][0] == "top_plate"  # on the bench first
    steps = [i for s in plan["robust_plan"] for i in s["insertions"]]
    members = [i for i in steps if i["workspace"] == "upper_die_set"]
    assert not any(i["held"] for i in members)  # upside down every part rests on another
    into = next(i for i in steps if i["unit"] == "upper_die_set")
    assert into["workspace"] == "main" and into["insert_along"] == "-y"  # down the pins
    assert into["held"]  # drawn open: nothing of the lower half under it
    lower = [p for p in spaces["main"]["parts"] if p not in upper["parts"]]
    assert lower[0] == "bottom_plate"
    assert plan["line_check"] == {"robust_plan": None, "worst_line": None}


def test_the_mesh_replay_accepts_the_upside_down_build(die_set_plan):
    _, plan = die_set_plan
    replayed(plan)


def test_the_line_fails_when_the_unit_is_checked_right_side_up(die_set_plan):
    source, plan = die_set_plan
    assembly = pipeline.load(source, on_step=lambda _: None)
    spec = with_subassemblies(assembly.spec, plan["subassemblies"].items())
    with pytest.raises(PlanCheckError, match="not supported"):
        check_line(spec, assembly.relations, plan_operations(plan))


def test_the_plan_text_says_how_the_unit_is_built(tmp_path):
    source = die_set_glb(tmp_path)
    result = CliRunner().invoke(app, ["plan", str(source), "-o", str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    assert "built upside down (gravity +y in its workspace" in result.output


def test_orientation_rule_on_the_relations(tmp_path):
    source = die_set_glb(tmp_path)
    assembly = pipeline.load(source, on_step=lambda _: None)
    upper = tuple(p for p in die_set() if p.startswith(UPPER))
    spec = with_subassemblies(assembly.spec, [("upper", upper)])
    o = unit_orientation(spec, assembly.relations, "upper")
    assert (o.gravity, o.upside_down, o.held, o.base) == ("+y", True, (), "top_plate")
    assert o.held_other > 0  # right side up, bushings and screws would need holding
    turned = orient_units(spec, assembly.relations)
    assert turned.unit_gravity == (("upper", "+y"),)
    assert not any(op.held for op in turned.operations if set(op.parts) <= set(upper))
    first = next(op.id for op in turned.operations if op.parts == ("top_plate",))
    others = [op for op in turned.operations if op.parts and op.parts[0] in upper]
    assert all(first in op.after for op in others if op.id != first)
    assert opposite("-y") == "+y" and opposite("+z") == "-z"


def test_a_spec_says_a_unit_is_built_upside_down(tmp_path):
    from asp.spec import load_spec

    yaml = """
name: two plates
parts: [a, b, c]
agents: {H: {side: human}}
base_part: a
subassemblies:
  top: {parts: [b, c], gravity: +z}
operations:
  - {id: "1", agents: {H: 1}, part: a}
  - {id: "2", agents: {H: 1}, part: b}
  - {id: "3", agents: {H: 1}, part: c}
"""
    path = tmp_path / "assembly.yaml"
    path.write_text(yaml)
    spec = load_spec(path)
    assert spec.unit_gravity == (("top", "+z"),)
    assert spec.build_gravity("top") == "+z" and spec.build_gravity("") == "-z"
    path.write_text(yaml.replace("gravity: +z}", "gravity: +z, side: 1}"))
    with pytest.raises(Exception, match="side"):
        load_spec(path)


def test_a_die_set_without_product_tree_finds_its_upper_half(tmp_path):
    """From a folder of STL parts (no hierarchy) the upper half is found automatically: its
    parts can never go in one by one (the screws driven up into the top plate would have
    to pass through the die block); the groups of the stuck parts that span both first
    guesses merge into one unit, which is built upside down. The guide bushings, pressed
    into the top plate from below, join it (:func:`asp.subassemblies.hung_on_units`): upside down
    they rest on the top plate, where otherwise each would be held on its guide pin until
    the upper half comes down."""
    from cad import Assembly
    from tests.cad.test_loading import write_folder

    source = write_folder(tmp_path / "die_set", Assembly.from_meshes(die_set()))
    plan = plan_and_check(source, tmp_path / "out", "--time-limit", "5")
    (uid, members), *others = plan["subassemblies"].items()
    assert not others
    assert {"top_plate", "punch_holder", "punch", "stripper_plate", "top_screw_1"} <= set(members)
    assert {"bushing_1", "bushing_2"} <= set(members)
    steps = [i for s in plan["robust_plan"] for i in s["insertions"]]
    assert [i["parts"] for i in steps if i["held"]] == [list(members)]  # only the half
    spaces = {w["id"]: w for w in plan["workspaces"]}
    assert spaces[uid]["gravity"] == "+z" and spaces[uid]["parts"][0] == "top_plate"
    assert plan["line_check"] == {"robust_plan": None, "worst_line": None}


def test_a_half_that_stands_right_side_up_is_not_turned(tmp_path):
    """The die block with its screws from above needs no hold right side up (the heads
    rest in the counterbores); upside down a screw would fall out: it stays."""
    from cad import Assembly
    from tests.cad.test_loading import write_folder

    source = write_folder(tmp_path / "die_set", Assembly.from_meshes(die_set()))
    assembly = pipeline.load(source, on_step=lambda _: None)
    lower = ("die_block", "screw_1", "screw_2")
    spec = with_subassemblies(assembly.spec, [("lower", lower)])
    o = unit_orientation(spec, assembly.relations, "lower")
    assert (o.gravity, o.upside_down, o.held) == ("-z", False, ())
    assert o.held_other == 1
    assert orient_units(spec, assembly.relations) == spec


def test_init_writes_the_upside_down_build_and_the_spec_reads_it(tmp_path):
    from asp.spec import load_spec

    source = die_set_glb(tmp_path)
    spec_path = tmp_path / "assembly.yaml"
    result = CliRunner().invoke(app, ["init", str(source), "-o", str(spec_path)])
    assert result.exit_code == 0, result.output
    text = spec_path.read_text()
    assert "upper_die_set: {parts: [" in text and "gravity: +y, held: true}" in text
    spec = load_spec(spec_path)
    assert spec.unit_gravity == (("upper_die_set", "+y"),)
    assert spec.operation("upper_die_set").held
    plan = plan_and_check(spec_path, tmp_path / "out", "--time-limit", "5")
    assert {w["id"]: w["gravity"] for w in plan["workspaces"]}["upper_die_set"] == "+y"
