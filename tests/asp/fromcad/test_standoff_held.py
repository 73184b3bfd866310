"""A standoff holding up the bracket screwed to it, the product on its side, is ``held``.

The FM1 satellite's class (trimesh's ``FM1_satellite.3DXML``: hex standoffs on the back
plate under the speaker, planned with gravity along the plate): a plate with a wall, a
standoff standing on the plate, a bracket whose pocket takes the standoff's top (the hole
over its threaded bore) and a screw through the bracket into the standoff. With gravity
``+y`` only the bracket's pocket and the screw stop the standoff falling, and each, with
the plate, blocks it along every direction: it must go in before them, with nothing to
rest on, so a generated spec holds it (:func:`asp.fromcad.generate.unsupported_parts`).
Geometry built here with trimesh.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest
from typer.testing import CliRunner

from asmplan import pipeline
from asmplan.cli import app
from asp.errors import InfeasibleAssembly
from asp.fromcad.generate import unsupported_parts
from asp.graph.checker import check_line, plan_operations
from asp.graph.state_graph import build_state_graph
from tests.cad.real_shapes import box, cylinder, difference, union


def standoff_scene(folder: Path) -> Path:
    """Plate (60x40x4, a wall along its +y edge), a hex standoff (r 3, z 4..25, a bore
    r 1.5 from z 15), a bracket (z 24..28) against the wall, its pocket (r 3.05, 1 deep)
    on the standoff's top and a hole r 1.6 over the bore, and a screw (shank r 1.5 from
    z 15, head r 2.8 on the bracket), as STL files."""
    folder.mkdir()
    at = (20, 20)
    meshes = {
        "plate": union(box((0, 0, 0), (60, 40, 4)), box((0, 30, 4), (60, 34, 30))),
        "standoff": difference(cylinder(3.0, 4, 25, 6, xy=at), cylinder(1.5, 15, 26, 24, xy=at)),
        "bracket": difference(
            box((10, 10, 24), (50, 30, 28)),
            cylinder(3.05, 23, 25, 6, xy=at),
            cylinder(1.6, 23, 29, 24, xy=at),
        ),
        "screw": union(cylinder(1.5, 15, 28, 24, xy=at), cylinder(2.8, 28, 30, 24, xy=at)),
    }
    for name, mesh in meshes.items():
        mesh.export(folder / f"{name}.stl")
    return folder


def held_parts(spec) -> set[str]:
    return {p for op in spec.operations if op.held for p in op.parts}


@pytest.fixture(scope="module")
def on_its_side(tmp_path_factory):
    source = standoff_scene(tmp_path_factory.mktemp("standoff") / "meshes")
    return source, pipeline.load(source, gravity="+y", on_step=lambda _: None)


def test_the_standoff_rests_only_on_parts_that_must_come_after_it(on_its_side):
    _, assembly = on_its_side
    rel, ids = assembly.relations, [str(p) for p in assembly.relations.parts]
    s, b, k = ids.index("standoff"), ids.index("plate"), ids.index("bracket")
    # along +y (index 2) only the bracket and the screw keep it from falling ...
    assert {ids[j] for j in range(len(ids)) if rel.sp[s, j, 2]} == {"bracket", "screw"}
    # ... and the bracket with the plate leaves it no way in: it goes in before them
    assert not any(rel.tt[s, k, d] and rel.tt[s, b, d] for d in range(6))
    assert unsupported_parts(rel, "+y", "plate") == ("standoff",)
    assert unsupported_parts(rel, "-z", "plate") == ()  # standing: it rests on the plate
    assert held_parts(assembly.spec) == {"standoff"}


def test_held_it_plans_and_the_checker_accepts_it(on_its_side, tmp_path):
    source, assembly = on_its_side
    result = CliRunner().invoke(app, ["plan", str(source), "-o", str(tmp_path), "--gravity", "+y"])
    assert result.exit_code == 0, result.output
    doc = json.loads((tmp_path / "plan.json").read_text())
    ops = plan_operations(doc)
    check_line(assembly.spec, assembly.relations, ops, units=doc["subassemblies"])
    placed = [assembly.spec.operation(o).parts[0] for o in ops]
    assert placed.index("standoff") < placed.index("bracket") < placed.index("screw")
    assert doc["operations"][ops[placed.index("standoff")]].get("held")


def test_not_held_there_is_no_complete_sequence(on_its_side):
    _, assembly = on_its_side
    spec = assembly.spec
    loose = replace(spec, operations=tuple(replace(op, held=False) for op in spec.operations))
    build_state_graph(spec, assembly.relations)  # held: a complete sequence
    with pytest.raises(InfeasibleAssembly, match="standoff"):
        build_state_graph(loose, assembly.relations)
