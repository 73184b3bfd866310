"""The build frame (cad.frame): the spec key's forms, candidate frames from the parts' own
axes, and the pairs no sequence can assemble in a frame. Geometry built here."""

from __future__ import annotations

import numpy as np
import pytest

import cad
from cad.assembly import Assembly
from cad.frame import (
    axis_degrees,
    candidate_frames,
    canonical,
    frame_record,
    interlocked,
    parse_frame,
    rotated,
    rotation_matrix,
)
from tests.cad.real_shapes import tilted_pins

S3 = np.sqrt(3.0) / 2.0


@pytest.mark.parametrize(
    ("value", "takes_to"),
    [
        ({"axis": [0, -1, 0], "degrees": 30}, ([0.5, 0.0, S3], [0.0, 0.0, 1.0])),
        ({"axis": "-y", "degrees": "30"}, ([0.5, 0.0, S3], [0.0, 0.0, 1.0])),
        ({"axis": "x", "degrees": 90}, ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0])),
        ([[0, -1, 0], [1, 0, 0], [0, 0, 1]], ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0])),
        (
            [["0.8660254", "0", "-0.5"], ["0", "1", "0"], ["0.5", "0", "0.8660254"]],
            ([0.5, 0.0, S3], [0.0, 0.0, 1.0]),
        ),
    ],
)
def test_a_frame_is_a_rotation_taking_file_coordinates_to_build_ones(value, takes_to):
    rotation = np.asarray(parse_frame(value))
    assert np.allclose(rotation @ rotation.T, np.eye(3))
    assert np.linalg.det(rotation) == pytest.approx(1.0)
    source, target = takes_to
    assert np.allclose(rotation @ source, target, atol=1e-6)


@pytest.mark.parametrize("value", [None, "file", "FILE", {"axis": "z", "degrees": 0}, np.eye(3)])
def test_the_files_own_frame_is_none(value):
    value = value.tolist() if isinstance(value, np.ndarray) else value
    assert parse_frame(value) is None


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ({"axis": [0, 0, 0], "degrees": 10}, "zero vector"),
        ({"axis": [0, 0, 1]}, "expected {axis"),
        ({"axis": [0, 0, 1], "degrees": 5, "angle": 3}, "expected {axis"),
        ({"axis": "w", "degrees": 5}, "axis: expected x, y, z"),
        ({"axis": [1, 0], "degrees": 5}, "axis: expected [x, y, z]"),
        ({"axis": [1, 0, 0], "degrees": "a lot"}, "degrees: expected a number"),
        ([[1, 0, 0], [0, 1, 0], [0, 0, -1]], "reflection"),
        ([[1, 0, 0], [0, 2, 0], [0, 0, 1]], "not a rotation"),
        ([[1, 0, 0], [0, 1, 0]], "expected 'file'"),
        ("upright", "expected 'file'"),
    ],
)
def test_a_bad_frame_says_what_is_wrong(value, message):
    with pytest.raises(ValueError, match=message.replace("[", r"\[").replace("{", r"\{")):
        parse_frame(value)


def test_the_record_reads_back_as_the_same_rotation():
    rotation = canonical(rotation_matrix([0.3, -0.2, 0.9], 41.23456))
    record = frame_record(rotation)
    assert record["degrees"] == pytest.approx(41.235)
    assert parse_frame(record) == rotation  # exactly: what a spec says is what was planned
    axis, degrees = axis_degrees(rotation)
    assert np.allclose(rotation_matrix(axis, degrees), rotation)


def test_a_rotated_assembly_keeps_its_parts_and_records_the_frame():
    assembly = Assembly.from_meshes(tilted_pins())
    rotation = parse_frame({"axis": "z", "degrees": 90})
    turned = rotated(assembly, rotation)
    assert turned.ids == assembly.ids and turned.frame == rotation
    for before, after in zip(assembly.parts, turned.parts, strict=True):
        assert np.allclose(after.mesh.vertices, before.mesh.vertices @ np.asarray(rotation).T)
        assert after.mesh.is_watertight and after.source == before.source
    assert rotated(assembly, None) is assembly


def test_the_candidate_frame_turns_the_pins_upright_and_frees_them():
    axis, degrees = (1.0, 1.0, 0.0), 25.0
    assembly = Assembly.from_meshes(tilted_pins(axis, degrees))
    pins_axis = rotation_matrix(axis, degrees) @ [0.0, 0.0, 1.0]
    relations = cad.compute_relations(assembly)
    stuck = interlocked(relations, "base")
    assert ("pin_1", "base") in stuck and ("pin_2", "base") in stuck
    first = candidate_frames(assembly)[0]
    assert set(first.parts) == {"plate", "pin_1", "pin_2"}
    assert np.allclose(np.asarray(first.rotation) @ pins_axis, [0.0, 0.0, 1.0], atol=1e-4)
    upright = cad.compute_relations(rotated(assembly, first.rotation))
    assert interlocked(upright, "base") == []
    k = upright.parts.index("pin_1")
    others = [j for j in range(len(upright.parts)) if j != k]
    assert upright.tt[k, others, 4].all()  # free along +z of every part: in along -z


def test_an_upright_product_has_no_interlock_and_its_aligned_parts_no_candidate():
    assembly = Assembly.from_meshes(tilted_pins(upright=True))
    assert interlocked(cad.compute_relations(assembly), "base") == []
    # only the base, whose underside is slanted, has axes off the coordinate axes
    assert {p for c in candidate_frames(assembly) for p in c.parts} == {"base"}


def test_a_shared_axis_across_the_first_is_turned_onto_an_axis_as_well():
    """Turned about (1, 0, 1), the plate's edges leave the coordinate axes as well as its
    normal: the first candidate turns both back (the product as drawn upright, up to a
    quarter turn), not only the pins."""
    turn = rotation_matrix((1.0, 0.0, 1.0), 40.0)
    assembly = Assembly.from_meshes(tilted_pins((1.0, 0.0, 1.0), 40.0))
    first = candidate_frames(assembly)[0]
    assert first.across is not None and "plate" in first.across_parts
    back = np.asarray(first.rotation) @ turn
    assert np.allclose(np.abs(back).max(axis=1), 1.0, atol=1e-4)  # a signed permutation
    assert np.allclose(back[:, 2], [0.0, 0.0, 1.0], atol=1e-4)  # the pins upright
