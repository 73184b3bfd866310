"""The build frame end to end: a product whose pins lie off every axis of its file.

A plate pinned onto the slanted face of a base (:func:`tests.cad.real_shapes.tilted_pins`,
pins 25 degrees off ``z``): in the file's frame no pin has a free axis direction. A spec
generated from the file turns the product so the pins stand upright (said on stderr,
recorded in ``plan.json``, written by ``asmplan init``); a user's spec says it with
``frame:``; the same product drawn upright plans in its file's frame as before, to the same
figures. Every plan goes through both checkers (:func:`tests.asmplan.checked.plan_and_check`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from asmplan.cli import app
from asmplan.report.meshes import part_meshes
from asp.spec import spec_from_dict
from cad.frame import rotation_matrix
from tests.asmplan.checked import plan_and_check
from tests.cad.real_shapes import tilted_pins

AXIS, DEGREES = (1.0, 1.0, 0.0), 25.0
PINS = rotation_matrix(AXIS, DEGREES) @ [0.0, 0.0, 1.0]
"""The pins' axis in the file (upwards)."""


def product(folder: Path, upright: bool = False) -> Path:
    folder.mkdir(parents=True)
    for pid, mesh in tilted_pins(AXIS, DEGREES, upright=upright).items():
        mesh.export(folder / f"{pid}.stl")
    return folder


def figures(doc: dict) -> tuple:
    return doc["tct"], doc["minimax"], doc["states"], doc["sequences"], doc["base_part"]


@pytest.fixture(scope="module")
def planned(tmp_path_factory) -> dict:
    """The tilted product planned from its files with defaults, and its stderr."""
    root = tmp_path_factory.mktemp("tilted")
    stderr: list[str] = []
    stdout: list[str] = []
    doc = plan_and_check(product(root / "cad"), root / "plan", stderr=stderr, stdout=stdout)
    return {"doc": doc, "stderr": stderr[0], "stdout": stdout[0], "root": root}


@pytest.mark.slow
def test_a_generated_spec_turns_the_product_so_its_pins_go_in_along_an_axis(planned):
    doc = planned["doc"]
    assert "generated spec: frame: the file's frame turned 25 degrees about" in planned["stderr"]
    assert "pin_1-base" in planned["stderr"]  # why: the pairs stuck in the file's frame
    assert "build frame: the file's frame turned 25 degrees" in planned["stdout"]
    geometry = doc["geometry"]
    assert geometry["frame"] == "build"
    rotation = np.asarray(geometry["build_rotation"])
    assert np.allclose(rotation @ PINS, [0.0, 0.0, 1.0], atol=1e-4)
    pins = [ins for s in doc["robust_plan"] for ins in s["insertions"] if "pin" in ins["parts"][0]]
    assert len(pins) == 2
    for ins in pins:
        assert ins["insert_along"] == "-z"
        assert np.allclose(ins["insert_vector_file"], -PINS, atol=1e-4)


@pytest.mark.slow
def test_the_pictures_show_the_product_as_fixtured(planned):
    doc = {**planned["doc"], "source": str(planned["root"] / "cad" / "assembly.yaml")}
    meshes = part_meshes(doc)  # files beside the spec
    assert set(meshes) == {"base", "plate", "pin_1", "pin_2"}
    vertices, _ = meshes["pin_1"]
    extent = np.ptp(vertices, axis=0)
    assert extent[2] == pytest.approx(16.0, abs=0.01)  # upright: its length along z
    assert extent[:2].max() < 4.1


@pytest.mark.slow
def test_the_same_product_drawn_upright_plans_alike_in_its_files_frame(planned, tmp_path):
    stderr: list[str] = []
    doc = plan_and_check(product(tmp_path / "cad", upright=True), tmp_path / "plan", stderr=stderr)
    assert "frame" not in stderr[0]
    assert doc["geometry"]["frame"] == "file"
    assert np.allclose(doc["geometry"]["build_rotation"], np.eye(3))
    assert figures(doc) == figures(planned["doc"])


@pytest.mark.slow
def test_init_writes_the_frame_and_the_written_spec_plans_the_same(planned, tmp_path):
    folder = product(tmp_path / "cad")
    result = CliRunner().invoke(app, ["init", str(folder), "-o", str(folder / "assembly.yaml")])
    assert result.exit_code == 0, result.output
    text = (folder / "assembly.yaml").read_text()
    assert "\nframe: {axis: [-0.7071, -0.7071, 0], degrees: 25}" in text
    doc = plan_and_check(folder, tmp_path / "plan")  # now read through assembly.yaml
    assert doc["geometry"]["build_rotation"] == planned["doc"]["geometry"]["build_rotation"]
    assert figures(doc) == figures(planned["doc"])


def users_spec(folder: Path, frame=None) -> Path:
    """A hand-written spec of the tilted product (in the build frame: gravity -z)."""
    import yaml

    data = {
        "name": "pinned plate",
        "parts": [{"id": p, "file": f"{p}.stl"} for p in ("base", "plate", "pin_1", "pin_2")],
        "agents": {"H": {"side": "human"}, "R1": {"side": "robot"}},
        "base_part": "base",
        "cost": "time",
        "operations": [
            {"id": str(k), "agents": {"H": 4, "R1": 6}, "part": p}
            for k, p in enumerate(("base", "plate", "pin_1", "pin_2"), 1)
        ],
    }
    if frame is not None:
        data["frame"] = frame
    (folder / "assembly.yaml").write_text(yaml.safe_dump(data, sort_keys=False))
    return folder


@pytest.mark.slow
@pytest.mark.parametrize(
    "frame",
    [
        {"axis": [1, 1, 0], "degrees": -25},
        rotation_matrix(AXIS, -DEGREES).round(9).tolist(),
    ],
)
def test_a_users_spec_says_the_frame(tmp_path, frame):
    folder = users_spec(product(tmp_path / "cad"), frame)
    doc = plan_and_check(folder, tmp_path / "plan")
    assert doc["geometry"]["frame"] == "build"
    assert np.allclose(np.asarray(doc["geometry"]["build_rotation"]) @ PINS, [0, 0, 1], atol=1e-6)
    assert doc["tct"] == 20


def test_a_users_spec_without_the_frame_is_not_turned(tmp_path):
    folder = users_spec(product(tmp_path / "cad"))
    result = CliRunner().invoke(app, ["plan", str(folder), "-o", str(tmp_path / "plan")])
    assert result.exit_code == 2
    assert "can never be inserted" in result.output
    assert "frame" not in result.output


def test_a_bad_frame_names_the_spec_and_the_key():
    data = {
        "agents": {"H": "human"},
        "operations": [{"id": "1", "agents": {"H": 1}}],
        "frame": {"axis": [0, 0, 0], "degrees": 30},
    }
    with pytest.raises(ValueError, match=r"^spec\.yaml: frame: axis: the zero vector"):
        spec_from_dict(data, source="spec.yaml")
