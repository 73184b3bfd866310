"""Fasteners and pins as CAD draws them: a socket-head screw in a counterbored blind hole,
dowels in blind and through holes with clearance, at zero clearance and pressed in. The
relations, the support and a plan the checker accepts must come out with the defaults."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from asp.graph.checker import check_line
from asp.graph.state_graph import build_state_graph
from asp.spec import spec_from_dict
from cad import DIRECTIONS, Assembly, compute_relations
from tests.cad.real_shapes import box, cylinder, difference, revolve

SIDE = {"+x", "-x", "+y", "-y"}
DOWN = DIRECTIONS.index("-z")


def dirs(row) -> set[str]:
    return {d for d, v in zip(DIRECTIONS, row, strict=True) if v}


def socket_screw(d: float, length: float, sections: int, z_head: float) -> trimesh.Trimesh:
    """ISO 4762-like screw of diameter ``d``: chamfered tip, head ``1.6 d`` wide and ``d``
    high with its underside at ``z_head``, a hex socket."""
    r, hr, c = d / 2, 0.8 * d, 0.1 * d
    profile = [
        (0, z_head - length), (r - c, z_head - length), (r, z_head - length + c), (r, z_head),
        (hr, z_head), (hr, z_head + d - c), (hr - c, z_head + d), (0, z_head + d),
    ]  # fmt: skip
    socket = trimesh.creation.cylinder(radius=0.45 * d, height=d, sections=6)
    return difference(revolve(profile, sections), socket.apply_translation((0, 0, z_head + d)))


def counterbored_block(
    d: float, clearance: float, depth: float, counterbore: float, sections: int
) -> trimesh.Trimesh:
    """A block (top at z = 0) with a blind hole of radius ``d/2 + clearance`` ending in a
    118-degree drill point ``depth`` below the top, under a counterbore ``counterbore``
    deep and ``clearance`` wider than the head."""
    hole, cb = d / 2 + clearance, 0.8 * d + clearance
    tip = hole / np.tan(np.radians(59))
    cutter = revolve(
        [(0, -depth - tip), (hole, -depth), (hole, -counterbore), (cb, -counterbore), (cb, 1),
         (0, 1)],
        sections,
    )  # fmt: skip
    return difference(box((-5 * d, -5 * d, -depth - 2 * d), (5 * d, 5 * d, 0)), cutter)


def screw_assembly(d=3.0, clearance=0.1, sections=(48, 64), sunk=0.3) -> dict:
    """An M``d`` screw, 3 d long, its head ``sunk`` below the top of a counterbored hole."""
    counterbore = d + sunk
    return {
        "block": counterbored_block(d, clearance, counterbore + 3.5 * d, counterbore, sections[1]),
        "screw": socket_screw(d, 3 * d, sections[0], -counterbore),
    }


def dowel_assembly(radial: float, gap: float, through: bool, r: float = 3.0) -> dict:
    """A radius ``r + radial`` dowel in a radius-``r`` hole of a 10 mm plate (top at z = 0),
    ``gap`` above the bottom of a 6 mm blind hole, or in a through hole."""
    hole = cylinder(r, -11 if through else -6, 1, 64)
    return {
        "plate": difference(box((-20, -20, -10), (20, 20, 0)), hole),
        "dowel": cylinder(r + radial, -6 + gap, 6 + gap, 48),
    }


def spec_for(rel, base: str):
    data = {
        "parts": [{"id": p, "file": f"{p}.stl"} for p in rel.parts],
        "agents": {"R": {"side": "robot"}},
        "base_part": base,
        "operations": [{"id": p, "agents": {"R": 1}, "part": p} for p in rel.parts if p != base],
    }
    return spec_from_dict(data, source="fits.yaml")


def planned(rel, base: str) -> None:
    """The assembly plans with every placement supported, and the checker agrees."""
    spec = spec_for(rel, base)
    graph = build_state_graph(spec, rel)
    assert graph.count_sequences() >= 1
    for seq in graph.sequences(limit=20):
        check_line(spec, rel, seq)


@pytest.mark.parametrize(
    ("d", "clearance", "sections", "sunk"),
    [
        (3.0, 0.1, (48, 64), 0.3),  # clearance hole, head below the top
        (3.0, 0.0, (48, 64), 0.3),  # drawn at the hole's diameter
        (3.0, 0.1, (12, 128), 0.0),  # coarse screw, fine hole, head flush with the top
        (8.0, 0.2, (36, 40), 1.0),
        (2.0, 0.05, (24, 100), 0.2),
    ],
)
def test_socket_screw_in_counterbored_blind_hole(d, clearance, sections, sunk):
    rel = compute_relations(Assembly.from_meshes(screw_assembly(d, clearance, sections, sunk)))
    s, b = rel.index("screw"), rel.index("block")
    # walls all round and the head on the counterbore's floor; out only the way it came in
    assert dirs(rel.tc[s, b]) == SIDE | {"-z"}
    assert dirs(rel.tt[s, b]) == {"+z"}
    assert rel.sp[s, b, DOWN]
    planned(rel, "block")


@pytest.mark.parametrize(
    ("radial", "gap", "through", "free", "supported"),
    [
        (-0.1, 0.0, False, {"+z"}, True),  # clearance, standing on the bottom
        (0.0, 0.0, False, {"+z"}, True),  # zero clearance
        (0.04, 0.0, False, {"+z"}, True),  # pressed in
        (-0.1, 0.3, False, {"+z"}, True),  # a little above the bottom
        (0.0, 1.0, False, {"+z"}, True),  # drawn 1 mm short of the bottom: slides onto it
        (0.04, 2.0, False, {"+z"}, True),
        (-0.1, 0.0, True, {"+z", "-z"}, False),  # through hole: it would fall through
        (0.0, 0.0, True, {"+z", "-z"}, False),
        (0.04, 0.0, True, {"+z", "-z"}, False),
    ],
)
def test_dowel_fits(radial, gap, through, free, supported):
    rel = compute_relations(Assembly.from_meshes(dowel_assembly(radial, gap, through)))
    p, b = rel.index("dowel"), rel.index("plate")
    assert dirs(rel.tc[p, b]) >= SIDE
    assert dirs(rel.tt[p, b]) == free
    assert bool(rel.sp[p, b, DOWN]) == supported
    if supported:
        planned(rel, "plate")


def test_dowel_beside_a_hole_is_not_captured():
    """A dowel standing 1 mm above a plate (not in a hole) falls: capture needs the walls."""
    parts = {"plate": box((-20, -20, -10), (20, 20, 0)), "dowel": cylinder(3, 1, 13, 48)}
    rel = compute_relations(Assembly.from_meshes(parts))
    assert not rel.sp[rel.index("dowel"), rel.index("plate"), DOWN]


def tapped_block(d: float, drill: float, width: float) -> dict:
    """A screw of diameter ``d`` in a blind hole drawn at the tap-drill diameter ``drill``
    (the thread is not drawn: the screw overlaps the wall all round), head on the top."""
    depth = 3 * d
    hole = revolve([(0, -depth - 0.6 * drill), (drill / 2, -depth), (drill / 2, 1), (0, 1)], 64)
    block = difference(
        box((-width / 2, -width / 2, -depth - 2 * d), (width / 2, width / 2, 0)), hole
    )
    return {"block": block, "screw": socket_screw(d, 2.5 * d, 48, 0.0)}


@pytest.mark.parametrize(
    ("d", "drill", "width"),
    [(2.0, 1.6, 20), (3.0, 2.5, 30), (3.0, 2.5, 12), (8.0, 6.8, 100), (12.0, 10.2, 120),
     (6.35, 5.1, 60)],  # M2, M3, M8, M12 and UNC 1/4-20 at their tap drills
)  # fmt: skip
def test_screw_in_a_tapped_hole_drawn_at_the_tap_drill_is_a_fit(d, drill, width):
    rel = compute_relations(Assembly.from_meshes(tapped_block(d, drill, width)))
    s, b = rel.index("screw"), rel.index("block")
    assert dirs(rel.tc[s, b]) == SIDE | {"-z"}
    assert dirs(rel.tt[s, b]) == {"+z"}
    assert dirs(rel.tt[b, s]) == {"-z"}
    assert rel.sp[s, b, DOWN]
    ((inner, outer, extra),) = rel.fits
    assert (inner, outer) == ("screw", "block") and 0 < extra < 0.1 * d
    planned(rel, "block")


@pytest.mark.parametrize(
    ("parts", "pair"),
    [
        (lambda: tapped_block(3.0, 2.0, 30), "'block' and 'screw'"),  # 0.5 mm: not a thread
        (lambda: dowel_assembly(1.2, 0.0, False), "'plate' and 'dowel'"),
        # a plate sunk 0.8 mm into another: deep, and no hole around it
        (lambda: {"a": box((0, 0, 0), (40, 40, 10)), "b": box((5, 5, 9.2), (35, 35, 14))},
         "'a' and 'b'"),
    ],
)  # fmt: skip
def test_overlap_that_is_not_a_fit_is_an_error(parts, pair):
    with pytest.raises(ValueError, match=f"{pair} interpenetrate by about"):
        compute_relations(Assembly.from_meshes(parts()))
