"""Support (DESIGN.md "Support"): a part is supported iff a short fall would drive it into
the parts already there, or it is threaded on one of them; geometry built here."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from asp.graph.checker import check_line
from asp.graph.state_graph import build_state_graph
from asp.spec import spec_from_dict
from cad import Assembly, compute_relations
from tests.cad.real_shapes import annulus, bolted_bracket, box, cylinder, difference, union

DOWN = 5  # -z


def along_x(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """A mesh built along z, turned to lie along x."""
    turn = trimesh.transformations.rotation_matrix(np.pi / 2, (0, 1, 0))
    return mesh.copy().apply_transform(turn)


def supported_by(rel, part: str) -> set[str]:
    i = rel.parts.index(part)
    return {rel.parts[j] for j in np.flatnonzero(rel.sp[i, :, DOWN])}


def resting_on(rel, part: str) -> set[str]:
    i = rel.parts.index(part)
    return {rel.parts[j] for j in np.flatnonzero(rel.tc[i, :, DOWN])}


def spec_for(rel, base: str, held=()):
    parts = [{"id": p, "file": f"{p}.stl"} for p in rel.parts]
    ops = [
        {"id": p, "agents": {"R": 1}, "part": p, "held": p in held} for p in rel.parts if p != base
    ]
    data = {"parts": parts, "agents": {"R": {"side": "robot"}}, "base_part": base}
    return spec_from_dict({**data, "operations": ops}, source="support.yaml")


def finger_side(gap: float = 0.05, kerf: float = 0.2) -> dict[str, trimesh.Trimesh]:
    """A 60x40x6 base with two edge notches; a side wall standing ``gap`` above it with two
    tabs through the notches, each ``kerf`` wider than its notch: no face lies on the base."""
    notches = [box((x0, -1, -1), (x0 + 10, 6, 7)) for x0 in (10.0, 40.0)]
    base = difference(box((0, 0, 0), (60, 40, 6)), *notches)
    tabs = [box((x0 - kerf / 2, 0, gap), (x0 + 10 + kerf / 2, 6, 6 + gap)) for x0 in (10.0, 40.0)]
    side = union(box((0, 0, 6 + gap), (60, 6, 46)), *tabs)
    return {"base": base, "side": side}


def shaft_in_bearing(horizontal: bool, shoulder: bool, clearance: float = 0.05):
    """A 40 mm pillow block with a bore of radius 10 + ``clearance`` and a radius-10 shaft
    (100 mm) through it, lying (along x) or standing (along z, optionally with a collar
    resting on the block)."""
    bore = cylinder(10 + clearance, -30, 30, 64)
    shaft = cylinder(10, -50, 50, 48)
    if shoulder:
        shaft = union(shaft, cylinder(14, 20, 24, 48))
    if horizontal:
        bore, shaft = along_x(bore), along_x(shaft)
    block = difference(box((-20, -20, -20), (20, 20, 20)), bore)
    return {"block": block, "shaft": shaft}


def test_nut_waits_for_its_bolt():
    rel = compute_relations(Assembly.from_meshes(bolted_bracket()))
    # The nut hangs under the base: nothing below it, it is threaded on the bolt.
    assert resting_on(rel, "nut_1") == set()
    assert supported_by(rel, "nut_1") == {"bolt_1"}
    # The bolt's head stands on its washer; the bolt is not threaded on the plates, but it
    # is captured in their holes: without the washer it would slide down onto them.
    assert supported_by(rel, "bolt_1") == {"washer_1", "bracket", "base"}
    graph = build_state_graph(spec_for(rel, "base"), rel)
    seqs = graph.sequences(limit=200)
    assert seqs
    for seq in seqs:
        check_line(graph.spec, rel, seq)
        assert seq.index("bolt_1") < seq.index("nut_1")
        assert seq.index("bolt_2") < seq.index("nut_2")


def test_finger_jointed_side_stands_in_the_base_without_held():
    # With a 0.01 mm contact tolerance no face lies on the base (0.05 mm gap); the default
    # contact rule would call that gap a clearance contact, support must not need one.
    rel = compute_relations(Assembly.from_meshes(finger_side()), contact_tol=0.01)
    assert resting_on(rel, "side") == set()
    assert supported_by(rel, "side") == {"base"}
    graph = build_state_graph(spec_for(rel, "base"), rel)
    assert graph.count_sequences() == 1
    check_line(graph.spec, rel, graph.sequences()[0])
    # 3 mm above the base it would fall: the support travel is a few tolerances.
    far = compute_relations(Assembly.from_meshes(finger_side(gap=3.0, kerf=0.0)))
    assert supported_by(far, "side") == set()


@pytest.mark.parametrize(
    ("horizontal", "shoulder", "clearance", "supported"),
    [
        (True, False, 0.05, True),  # lies in the bore across the clearance
        (False, False, 0.0, False),  # touches the bore all round, yet falls through it
        (False, True, 0.05, True),  # its collar stands on the block
    ],
)
def test_shaft_in_bearing_with_clearance(horizontal, shoulder, clearance, supported):
    parts = shaft_in_bearing(horizontal, shoulder, clearance)
    rel = compute_relations(Assembly.from_meshes(parts))
    assert supported_by(rel, "shaft") == ({"block"} if supported else set())
    spec = spec_for(rel, "block")
    if supported:
        graph = build_state_graph(spec, rel)
        assert graph.count_sequences() == 1
        check_line(spec, rel, graph.sequences()[0])
    else:
        with pytest.raises(ValueError, match="shaft.*nothing to rest on"):
            build_state_graph(spec, rel)
        held = spec_for(rel, "block", held=("shaft",))
        assert build_state_graph(held, rel).count_sequences() == 1


def test_support_is_mirrored_and_never_reflexive():
    rel = compute_relations(Assembly.from_meshes(finger_side()))
    drop = rel.sp.copy()
    assert not drop[np.arange(2), np.arange(2)].any()
    i, j = rel.parts.index("side"), rel.parts.index("base")
    assert drop[i, j, DOWN] and drop[j, i, DOWN - 1]  # the base "falls" up into the side


def test_ring_bearing_threaded_on_its_shaft():
    parts = {
        "shaft": cylinder(10, -20, 40, 64),
        "ring": annulus(10, 16, 0, 10, 48, 64),
    }
    rel = compute_relations(Assembly.from_meshes(parts))
    assert supported_by(rel, "ring") == {"shaft"}
    assert supported_by(rel, "shaft") == set()
