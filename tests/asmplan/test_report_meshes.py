"""The part meshes of a plan, found again from ``parts[].source`` (pictures and 3D view)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

from asmplan.report.html import assembly_steps
from asmplan.report.meshes import clustered, part_meshes
from asmplan.serve.meshes import plan_meshes
from tests.cad.real_shapes import box, cylinder
from tests.cad.test_subassemblies import write_glb

PARTS = {
    "block": box((0, 0, 0), (40, 20, 10)),
    "peg": cylinder(3.0, 10, 30, 48, xy=(10, 10)),
}
STEPS = [
    {"step": 1, "operation": "1", "agent": "R1", "parts": ["peg"], "description": "place peg"},
]


def _doc(source, parts, rotation=None) -> dict:
    geometry = {"scale": 1.0}
    if rotation is not None:
        geometry["build_rotation"] = rotation
    return {
        "source": str(source),
        "parts": parts,
        "operations": {"1": {"parts": ["peg"]}},
        "robust_plan": STEPS,
        "geometry": geometry,
    }


def test_a_folder_of_part_files_is_found_from_each_parts_source(tmp_path):
    for name, mesh in PARTS.items():
        mesh.export(tmp_path / f"{name}.stl")
    parts = [
        {"id": n, "file": f"{n}.stl", "source": {"path": str(tmp_path / f"{n}.stl"), "scale": 1.0}}
        for n in PARTS
    ]
    meshes = part_meshes(_doc(tmp_path, parts))
    assert set(meshes) == {"block", "peg"}
    assert np.allclose(np.ptp(meshes["block"][0], axis=0), [40, 20, 10])
    # a plan written before parts[].source: files relative to the source folder
    old = [{"id": n, "file": f"{n}.stl"} for n in PARTS]
    assert set(part_meshes(_doc(tmp_path, old))) == {"block", "peg"}
    assert len(assembly_steps(_doc(tmp_path, parts))) == 1


def test_parts_of_a_scene_file_are_found_by_node_in_mm_and_turned(tmp_path):
    glb = tmp_path / "model.glb"
    write_glb(glb, PARTS, {"Product": ["block", "peg"]})  # metres, y up
    parts = [
        {
            "id": f"my_{n}",  # ids need not be the file's: the node finds the part
            "file": f"model.glb#{n}",
            "source": {"path": str(glb), "node": n, "scale": 1000.0},
        }
        for n in PARTS
    ]
    meshes = part_meshes(_doc(glb, parts))
    assert np.allclose(np.ptp(meshes["my_block"][0], axis=0), [40, 10, 20], atol=1e-6)
    # the build frame turns the meshes: +y of the file onto +z
    turn = [[1, 0, 0], [0, 0, -1], [0, 1, 0]]
    upright = part_meshes(_doc(glb, parts, rotation=turn))
    assert np.allclose(np.ptp(upright["my_block"][0], axis=0), [40, 20, 10], atol=1e-6)
    assert len(assembly_steps(_doc(glb, parts))) == 1


def test_a_part_without_a_readable_file_is_left_out(tmp_path):
    parts = [{"id": "ghost", "file": "ghost.stl", "source": {"path": str(tmp_path / "no.stl")}}]
    assert part_meshes(_doc(tmp_path, parts)) == {}
    assert assembly_steps(_doc(tmp_path, parts)) == []


def test_the_page_gets_thinned_meshes(tmp_path):
    fine = trimesh.creation.icosphere(subdivisions=5, radius=20.0)  # 20,480 faces
    fine.export(tmp_path / "peg.stl")
    parts = [{"id": "peg", "file": "peg.stl", "source": {"path": str(tmp_path / "peg.stl")}}]
    page = plan_meshes(_doc(tmp_path, parts), max_faces=2_000)
    assert 0 < len(page["peg"]["i"]) <= 2_000
    assert max(page["peg"]["i"] + page["peg"]["j"] + page["peg"]["k"]) < len(page["peg"]["x"])


def test_clustered_rejects_a_budget_below_one():
    with pytest.raises(ValueError, match="max_faces must be at least 1, got 0"):
        clustered(np.zeros((3, 3)), np.array([[0, 1, 2]]), 0)


@settings(max_examples=25, deadline=None)
@given(
    subdivisions=st.integers(2, 5),
    budget=st.integers(20, 3_000),
    scale=st.tuples(*[st.floats(0.5, 50.0)] * 3),
)
def test_clustered_keeps_the_budget_and_the_outline(subdivisions, budget, scale):
    mesh = trimesh.creation.icosphere(subdivisions=subdivisions).apply_scale(scale)
    vertices, faces = clustered(mesh.vertices, mesh.faces, budget)
    assert len(faces) <= budget
    assert faces.min() >= 0 and faces.max() < len(vertices)
    if len(mesh.faces) <= budget:
        assert np.array_equal(faces, mesh.faces)
    # every vertex is a mean of vertices of one grid cell: inside the original box
    lo, hi = mesh.bounds
    used = vertices[np.unique(faces)]
    assert np.all(used >= lo - 1e-9) and np.all(used <= hi + 1e-9)
    # the outline stays: the thinned part spans most of the original (cells are 1/64 .. 1/2)
    assert np.all(np.ptp(used, axis=0) >= 0.3 * np.ptp(mesh.vertices, axis=0))
