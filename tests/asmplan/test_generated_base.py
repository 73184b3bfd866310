"""A generated spec takes a base part from which the assembly can be built.

The geometric rule (the lowest of the large parts) looks at bounding boxes only. A plate
carried by a post that stands on a small foot, drawn as a drive often is (upside down for
its assembly), makes the plate the base; but then the post must go under it, resting on the
foot, which touches nothing but the post: neither can come first. The derived precedences
prove it, and another base is taken. Geometry built here.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from asmplan import pipeline
from asp.fromcad.generate import spec_text, workable_base
from asp.graph.checker import check_line, plan_operations
from asp.graph.precedences import infeasibility
from tests.cad.real_shapes import box


def plate_on_post(folder: Path) -> Path:
    folder.mkdir()
    meshes = {
        "plate": box((-30, -30, 20), (30, 30, 25)),
        "post": box((-5, -5, 5), (5, 5, 20)),
        "foot": box((-8, -8, 0), (8, 8, 5)),
    }
    for name, mesh in meshes.items():
        mesh.export(folder / f"{name}.stl")
    return folder


def test_no_sequence_from_the_lowest_large_part(tmp_path):
    folder = plate_on_post(tmp_path / "post")
    with pytest.warns(UserWarning):
        assembly = pipeline.load(folder)
    # The gravity choice (asp.fromcad.gravity) sees the drawing is upside down and turns gravity
    # to +z, where the plate is a workable base; with gravity kept at -z, workable_base
    # must move the base to the post.
    assert (assembly.spec.gravity, assembly.spec.base_part) in {("+z", "plate"), ("-z", "post")}
    assert assembly.spec.operations[0].parts == (assembly.spec.base_part,)
    plate_based = pipeline.load_assembly(folder)
    assert plate_based.base_part == "plate" and plate_based.gravity == "-z"
    kept, note = workable_base(plate_based, assembly.relations)
    assert kept.base_part == "post" and "plate" in note
    assert "foot" in infeasibility(plate_based, assembly.relations) or infeasibility(
        plate_based, assembly.relations
    )
    result = pipeline.plan(assembly, time_limit=5)
    check_line(result.graph.spec, assembly.relations, plan_operations(result.to_dict()))


def test_init_writes_the_same_base(tmp_path):
    folder = plate_on_post(tmp_path / "post")
    text = spec_text(folder)
    with pytest.warns(UserWarning):
        base = pipeline.load(folder).spec.base_part
    assert f"base_part: {base}" in text
    first_op = next(line for line in text.splitlines() if "agents:" in line and "{id:" in line)
    assert f"part: {base}" in first_op


def test_a_workable_base_is_kept(tmp_path):
    folder = tmp_path / "upright"
    folder.mkdir()
    box((-30, -30, 0), (30, 30, 5)).export(folder / "plate.stl")
    box((-5, -5, 5), (5, 5, 20)).export(folder / "post.stl")
    with pytest.warns(UserWarning):
        assembly = pipeline.load(folder)
    assert assembly.spec.base_part == "plate"
