"""A generated spec holds what nothing can keep from falling (DESIGN.md "Support").

A loose dowel in a plate's through hole would slide out: no part of the assembly can stop
its fall, so the spec generated from the meshes marks its placement ``held: true`` (an agent
holds it), ``asmplan init`` says why, ``asmplan plan`` names it on stderr, and the plan
comes out and passes the independent checker. Geometry built here.
"""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from asmplan import pipeline
from asmplan.cli import app
from asp.fromcad.generate import generated_spec, hold_unsupported
from asp.graph.checker import PlanCheckError, check_line, plan_operations
from asp.spec import load_spec
from tests.asmplan.checked import plan_and_check
from tests.cad.real_shapes import box, cylinder, difference


def plate_with_dowel(folder: Path) -> Path:
    """A 40x40x5 plate with a radius-3.1 through hole, a radius-3 dowel loose in it (20 mm,
    sticking out 5 mm below and 10 mm above) and a block lying on the plate, as STL files."""
    folder.mkdir()
    plate = difference(box((0, 0, 0), (40, 40, 5)), cylinder(3.1, -1, 6, 48, xy=(20, 20)))
    meshes = {
        "plate": plate,
        "dowel": cylinder(3.0, -5, 15, 32, xy=(20, 20)),
        "block": box((2, 2, 5), (12, 12, 15)),
    }
    for name, mesh in meshes.items():
        mesh.export(folder / f"{name}.stl")
    return folder


def held_parts(spec) -> set[str]:
    return {p for op in spec.operations if op.held for p in op.parts}


def test_the_loose_dowel_is_held_and_the_plan_passes_the_checker(tmp_path):
    source = plate_with_dowel(tmp_path / "meshes")
    assembly = pipeline.load(source, on_step=lambda _: None)
    assert assembly.spec.generated and assembly.spec.base_part == "plate"
    assert held_parts(assembly.spec) == {"dowel"}  # the block rests on the plate
    assert held_parts(generated_spec(source)) == set()  # held needs the relations

    notes: list[str] = []
    doc = plan_and_check(source, tmp_path / "out", stderr=notes)
    assert "generated spec: held: true for dowel (nothing below" in notes[0]
    ops = plan_operations(doc)
    # without held the dowel would fall: the checker rejects the same line
    with pytest.raises(PlanCheckError, match="dowel is not supported"):
        check_line(generated_spec(source), assembly.relations, ops, units=doc["subassemblies"])


def test_init_writes_held_with_its_reason_and_reads_back(tmp_path):
    source = plate_with_dowel(tmp_path / "meshes")
    spec_file = tmp_path / "assembly.yaml"
    result = CliRunner().invoke(app, ["init", str(source), "-o", str(spec_file)])
    assert result.exit_code == 0, result.output
    text = spec_file.read_text()
    lines = text.splitlines()
    k = next(i for i, line in enumerate(lines) if "part: dowel" in line)
    assert lines[k].endswith("part: dowel, held: true}")
    assert lines[k - 1].strip().startswith("# held: nothing below can stop it falling")
    assert sum("held: true}" in line for line in lines) == 1
    assert yaml.safe_load(text)["operations"]
    assert held_parts(load_spec(spec_file)) == {"dowel"}


def test_a_users_spec_is_never_changed(tmp_path):
    source = plate_with_dowel(tmp_path / "meshes")
    spec_file = source / "assembly.yaml"
    CliRunner().invoke(app, ["init", str(source), "-o", str(spec_file)])
    spec_file.write_text(spec_file.read_text().replace(", held: true}", "}"))
    assembly = pipeline.load(source, on_step=lambda _: None)
    assert not assembly.spec.generated and held_parts(assembly.spec) == set()
    assert hold_unsupported(assembly.spec, assembly.relations) == (assembly.spec, ())
