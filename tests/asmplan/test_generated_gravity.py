"""A generated spec's gravity: the file's own down unless another is clearly better.

A Pro/E (Creo) or SolidWorks STEP export is often Y-up: with gravity ``-z`` the bracket of
a bolted joint needs a bolt beside it to "rest" on and the bolts need the bracket, so no
order exists. The generated spec chooses ``-y`` there (:mod:`asp.fromcad.gravity`), says so on
stderr and in ``asmplan init``'s comment, and plans; Z-up files keep ``-z``, glTF keeps
its ``-y`` unless its content is Z-up; a user's spec is never changed. Geometry built here.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import trimesh
import yaml
from typer.testing import CliRunner

import cad
from asmplan import pipeline
from asmplan.cli import app
from asp.fromcad.generate import gravity_choice
from asp.fromcad.gravity import base_index, one_sequence
from cad.assembly import prepare_part
from tests.asmplan.checked import plan_and_check
from tests.cad.real_shapes import bolted_bracket, box

Y_UP = trimesh.transformations.rotation_matrix(-np.pi / 2, (1, 0, 0))
"""Turns a Z-up model Y-up (+z -> +y), as a Y-up exporter writes it."""


def bracket(turn: np.ndarray) -> cad.Assembly:
    parts = tuple(
        prepare_part(k, m.copy().apply_transform(turn), scale=1.0, source=k)
        for k, m in bolted_bracket(0.5).items()
    )
    return cad.Assembly(parts=parts, units="mm", source="built")


@pytest.fixture(scope="module")
def brackets():
    out = {}
    for name, turn in (("z-up", np.eye(4)), ("y-up", Y_UP)):
        assembly = bracket(turn)
        out[name] = (assembly, cad.compute_relations(assembly))
    return out


@pytest.mark.parametrize(
    ("model", "default", "chosen"),
    [("z-up", "-z", "-z"), ("y-up", "-z", "-y"), ("y-up", "-y", "-y"), ("z-up", "-y", "-z")],
)
def test_the_bolted_bracket_gets_its_true_gravity(brackets, model, default, chosen):
    assembly, relations = brackets[model]
    choice = gravity_choice(relations, assembly, default)
    assert choice.gravity == chosen
    assert choice.feasible[chosen] is True
    wrong = "-z" if chosen == "-y" else "-y"
    assert choice.feasible[wrong] is False  # sideways gravity: the bracket needs a bolt
    assert ("not the default" in choice.reason) == (chosen != default)


def pin_plate() -> dict[str, trimesh.Trimesh]:
    """A plate 60 x 20 x 5 mm lying flat in z with three pins standing in its through holes."""
    from tests.cad.real_shapes import cylinder, difference

    xs = (-20.0, 0.0, 20.0)
    plate = difference(
        box((-30, -10, 0), (30, 10, 5)), *(cylinder(3.1, -1, 6, 32, (x, 0)) for x in xs)
    )
    pins = {f"pin_{k}": cylinder(3.0, -5, 15, 24, (x, 0)) for k, x in enumerate(xs)}
    return {"plate": plate, **pins}


def pin_plate_assembly() -> cad.Assembly:
    parts = tuple(prepare_part(k, m, scale=1.0, source=k) for k, m in pin_plate().items())
    return cad.Assembly(parts=parts, units="mm", source="built")


def test_fewer_held_parts_alone_never_turn_gravity_sideways():
    """Pins in through holes are "supported" by the hole walls under a sideways gravity;
    a Z-up plate with loose pins keeps -z (the pins held), though +-x holds none."""
    assembly = pin_plate_assembly()
    choice = gravity_choice(cad.compute_relations(assembly), assembly, "-z")
    assert choice.held["-z"] == 3 and choice.held["+x"] == 0
    assert choice.gravity == "-z"


def test_a_base_standing_on_edge_turns_a_gltf_z_up():
    """The same plate in a glTF file (default -y): along -y it stands on its long edge and
    holds no pin (the hole walls "support" them), along -z it lies flat with the pins held;
    the base lying flat wins, as for trimesh's glTF export of the Z-up cycloidal drive."""
    assembly = pin_plate_assembly()
    choice = gravity_choice(cad.compute_relations(assembly), assembly, "-y")
    assert choice.held["-y"] == 0 and choice.held["-z"] == 3
    assert choice.footprint["-y"] == pytest.approx(0.25) and choice.footprint["-z"] == 1.0
    assert choice.gravity == "-z"
    assert "the base part plate stands on edge" in choice.reason
    assert "the file is likely Z up" in choice.reason


def test_a_z_up_glb_plans_lying_flat(tmp_path):
    """End to end: a Z-up scene written as GLB without turning its axes (trimesh's export)
    plans with gravity -z and says why; ``--gravity -y`` overrules it."""
    scene = trimesh.Scene()
    for name, mesh in pin_plate().items():
        scene.add_geometry(mesh, node_name=name, geom_name=name)
    source = tmp_path / "pins.glb"
    scene.export(source)
    stderr: list[str] = []
    doc = plan_and_check(source, tmp_path / "out", stderr=stderr)
    assert doc["gravity"] == "-z"
    assert "gravity -z: not the default -y" in stderr[0] and "stands on edge" in stderr[0]
    out = tmp_path / "given"
    result = CliRunner().invoke(app, ["plan", str(source), "-o", str(out), "--gravity", "-y"])
    assert result.exit_code == 0, result.output
    assert json.loads((out / "plan.json").read_text())["gravity"] == "-y"


def test_large_parts_held_along_the_default_turn_a_gltf_z_up():
    """Three stacked plates: along a glTF's -y every plate would need holding."""
    plates = [box((0, 0, 10 * k), (60, 40, 10 * k + 10)) for k in range(3)]
    assembly = cad.Assembly(
        parts=tuple(prepare_part(f"p{k}", m, scale=1.0, source="b") for k, m in enumerate(plates)),
        units="mm",
        source="built",
    )
    choice = gravity_choice(cad.compute_relations(assembly), assembly, "-y")
    assert choice.held_large["-y"] == 2 and choice.gravity == "-z"


def test_base_part_and_search_follow_gravity(brackets):
    assembly, relations = brackets["y-up"]
    bounds = np.array([p.bounds for p in assembly.parts])
    base = base_index(bounds, "-y")
    assert assembly.parts[base].id == "base"
    assert one_sequence(relations, "-y", base, set()) is True
    assert one_sequence(relations, "-z", base_index(bounds, "-z"), set()) is False


def write_folder(folder: Path, turn: np.ndarray) -> Path:
    folder.mkdir()
    for name, mesh in bolted_bracket(0.5).items():
        mesh.copy().apply_transform(turn).export(folder / f"{name}.stl")
    return folder


def test_a_y_up_export_plans_with_gravity_minus_y(tmp_path):
    source = write_folder(tmp_path / "yup", Y_UP)
    notes: list[str] = []
    assembly = pipeline.load(source, on_step=notes.append)
    spec = assembly.spec
    assert spec.gravity == "-y" and spec.base_part == "base"
    assert any(n.startswith("generated spec: gravity -y: not the default -z") for n in notes)
    assert spec.operations[0].parts == ("base",)

    stderr: list[str] = []
    doc = plan_and_check(source, tmp_path / "out", stderr=stderr)
    assert "gravity -y" in stderr[0] and doc["gravity"] == "-y"

    out = tmp_path / "spec" / "assembly.yaml"
    result = CliRunner().invoke(app, ["init", str(source), "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert "gravity -y: not the default -z" in result.stderr
    text = out.read_text()
    assert "gravity: -y" in text and "likely Y up (asp/fromcad/gravity.py)" in text
    assert yaml.safe_load(text)["gravity"] == "-y"


def test_a_users_gravity_is_never_changed(tmp_path):
    source = write_folder(tmp_path / "yup", Y_UP)
    out = source / "assembly.yaml"
    result = CliRunner().invoke(app, ["init", str(source), "-o", str(out)])
    assert result.exit_code == 0, result.output
    out.write_text(out.read_text().replace("gravity: -y", "gravity: -z", 1))
    notes: list[str] = []
    spec = pipeline.load(source, on_step=notes.append).spec
    assert not spec.generated and spec.gravity == "-z"
    assert not any("gravity" in n for n in notes)


def test_one_sequence_past_64_parts():
    """Bit masks of 70 parts (the cycloidal drive has 72): no int64 overflow."""
    from types import SimpleNamespace

    from cad.directions import DIRECTIONS

    n = 70
    down, up = DIRECTIONS.index("-z"), DIRECTIONS.index("+z")
    tc = np.zeros((n, n, 6), dtype=bool)
    tt = np.ones((n, n, 6), dtype=bool)
    for i in range(1, n):  # part i stands on part i - 1
        tc[i, i - 1, down] = tc[i - 1, i, up] = True
        tt[i, i - 1, down] = tt[i - 1, i, up] = False
    relations = SimpleNamespace(parts=[f"p{i}" for i in range(n)], tc=tc, tt=tt, sp=tc)
    assert one_sequence(relations, "-z", np.int64(0), set()) is True
    assert one_sequence(relations, "-z", np.int64(n - 1), set()) is False
