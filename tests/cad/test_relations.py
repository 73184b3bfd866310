"""Contact and translational freedom on small assemblies built in code."""

from __future__ import annotations

import numpy as np
import pytest

from cad import DIRECTIONS, Assembly, compute_relations, rtc, rtt, tt_set
from cad.relations import with_nearest
from tests.cad import shapes


def dirs(row: np.ndarray) -> set[str]:
    """Direction labels where a (6,) bool row is true."""
    return {d for d, v in zip(DIRECTIONS, row, strict=True) if v}


def pair(rel, i: str, j: str) -> tuple[set[str], set[str]]:
    """(contact directions, free directions) of the ordered pair (i, j)."""
    a, b = rel.index(i), rel.index(j)
    return dirs(rel.tc[a, b]), dirs(rel.tt[a, b])


ALL = set(DIRECTIONS)
SIDE = {"+x", "-x", "+y", "-y"}

CASES = [
    # (builder, i, j, expected TC_d(i, j) directions, expected TT_d(i, j) directions)
    ("stacked", lambda: shapes.stacked_cubes(), "top", "bottom", {"-z"}, ALL - {"-z"}),
    ("stacked", lambda: shapes.stacked_cubes(), "bottom", "top", {"+z"}, ALL - {"+z"}),
    ("through hole", lambda: shapes.peg_in_plate(), "peg", "plate", SIDE, {"+z", "-z"}),
    ("through hole", lambda: shapes.peg_in_plate(), "plate", "peg", SIDE, {"+z", "-z"}),
    ("blind hole", lambda: shapes.peg_in_plate(blind=True), "peg", "plate", SIDE | {"-z"}, {"+z"}),
    ("blind hole", lambda: shapes.peg_in_plate(blind=True), "plate", "peg", SIDE | {"+z"}, {"-z"}),
    ("thin plate", lambda: shapes.thin_plate_on_path(), "block", "sheet", set(), ALL - {"+x"}),
    ("thin plate", lambda: shapes.thin_plate_on_path(), "sheet", "block", set(), ALL - {"-x"}),
    ("container", lambda: shapes.boxed_container(), "item", "tray", {"-z"}, {"+z"}),
    ("container", lambda: shapes.boxed_container(), "item", "lid", set(), ALL - {"+z"}),
    ("container", lambda: shapes.boxed_container(), "lid", "tray", {"-z"}, ALL - {"-z"}),
    ("far apart", lambda: shapes.far_apart(), "a", "b", set(), ALL),
    ("far apart", lambda: shapes.far_apart(), "c", "a", set(), ALL),
    ("overlap 0.02", lambda: shapes.stacked_cubes(0.02), "top", "bottom", {"-z"}, ALL - {"-z"}),
    ("overlap 0.02", lambda: shapes.stacked_cubes(0.02), "bottom", "top", {"+z"}, ALL - {"+z"}),
]


@pytest.mark.parametrize(
    ("build", "i", "j", "contact", "free"),
    [c[1:] for c in CASES],
    ids=[f"{c[0]}:{c[2]}-{c[3]}" for c in CASES],
)
def test_pair_relations(build, i, j, contact, free):
    rel = compute_relations(build())
    assert pair(rel, i, j) == (contact, free)


def test_diagonal_false_and_contact_symmetry():
    rel = compute_relations(shapes.boxed_container())
    n = len(rel.parts)
    assert not rel.tc[np.arange(n), np.arange(n)].any()
    assert not rel.tt[np.arange(n), np.arange(n)].any()
    assert np.array_equal(rel.tc, rel.tc.transpose(1, 0, 2)[:, :, [1, 0, 3, 2, 5, 4]])


def test_container_blocked_until_lid_removed():
    rel = compute_relations(shapes.boxed_container())
    assert not tt_set(rel, "item", {"tray", "lid"}).any()
    assert not rtt(rel, "item", {"tray", "lid"})
    assert dirs(tt_set(rel, "item", {"tray"})) == {"+z"}
    assert rtt(rel, "item", {"tray"})
    assert rtc(rel, "item", {"tray"})
    assert not rtc(rel, "item", {"lid"})


@pytest.mark.parametrize("length", [50.0, 200.0, 2000.0])
def test_thin_plate_blocks_at_any_distance(length):
    rel = compute_relations(shapes.thin_plate_on_path(length))
    assert not rel.tt[rel.index("block"), rel.index("sheet"), 0]
    assert rel.tt[rel.index("block"), rel.index("far")].all()


@pytest.mark.parametrize(
    ("bump", "tol", "slides"),
    [(0.03, None, True), (0.6, None, False), (0.03, 0.05, True), (0.1, 0.05, False)],
    ids=[
        "bump within default tolerance",
        "bump deeper than default tolerance",
        "bump within explicit tolerance",
        "bump deeper than explicit tolerance",
    ],
)
def test_slide_over_bump(bump, tol, slides):
    """Default pair tolerance here: ground 0.25 + slider 0.052 mm (cad.tolerances)."""
    ground = shapes.box_between((0, 0, 0), (100, 10, 10))
    ridge = shapes.box_between((60, 0, 9), (70, 10, 10 + bump))
    import trimesh

    ground = trimesh.boolean.union([ground, ridge], engine="manifold")
    slider = shapes.box_between((0, 0, 10), (10, 10, 20))
    assembly = Assembly.from_meshes({"ground": ground, "slider": slider})
    rel = compute_relations(assembly, penetration_tol=tol)
    assert bool(rel.tt[rel.index("slider"), rel.index("ground"), 0]) is slides
    assert rel.tt[rel.index("slider"), rel.index("ground"), 1]


def test_tolerated_overlap_is_contact_and_sliding_free():
    rel = compute_relations(shapes.stacked_cubes(0.02))
    top, bottom = rel.index("top"), rel.index("bottom")
    assert rel.tt[top, bottom, :4].all()
    assert rel.tc[top, bottom, 5]


def test_deep_overlap_names_pair_and_depth():
    with pytest.raises(ValueError, match=r"'bottom' and 'top' interpenetrate by about 0\.5"):
        compute_relations(shapes.stacked_cubes(0.5))


def test_larger_tolerance_accepts_press_fit():
    rel = compute_relations(shapes.stacked_cubes(0.3), penetration_tol=0.4)
    assert pair(rel, "top", "bottom") == ({"-z"}, ALL - {"-z"})


def test_inclined_contact_gives_both_leaning_axes():
    import trimesh

    turn = trimesh.transformations.rotation_matrix(np.pi / 4, (0, 1, 0))
    lower = shapes.box((10, 10, 10))
    lower.apply_transform(turn)
    upper = shapes.box((10, 10, 10), (0, 0, 10))
    upper.apply_transform(turn)  # stacked along the tilted normal (0.707, 0, 0.707)
    rel = compute_relations(Assembly.from_meshes({"lower": lower, "upper": upper}))
    contact, free = pair(rel, "lower", "upper")
    assert contact == {"+x", "+z"}
    assert free == {"-x", "+y", "-y", "-z"}


def test_rotated_cube_on_plate():
    import trimesh

    cube = shapes.box((10, 10, 10), (0, 0, 5))
    cube.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 5, (0, 0, 1)))
    plate = shapes.box_between((-20, -20, -3), (20, 20, 0))
    rel = compute_relations(Assembly.from_meshes({"cube": cube, "plate": plate}))
    assert pair(rel, "cube", "plate") == ({"-z"}, ALL - {"-z"})


def test_subassembly_arguments_checked():
    rel = compute_relations(shapes.boxed_container())
    with pytest.raises(ValueError, match="must not be empty"):
        rtt(rel, "item", set())
    with pytest.raises(ValueError, match="already in S"):
        rtc(rel, "item", {"item", "tray"})
    with pytest.raises(ValueError, match="unknown part"):
        tt_set(rel, "nope", {"tray"})


@pytest.mark.parametrize(
    ("size", "gap", "contact_tol", "touching"),
    [
        (10, 0.0, 0.01, True),
        (10, 0.005, 0.01, True),
        (10, 0.02, 0.01, False),  # an explicit tolerance is used as given
        (10, 0.02, None, True),  # default for 10 mm cubes: min(0.02 x 17.3, 0.2) = 0.2 mm
        (10, 0.19, None, True),
        (10, 0.25, None, False),  # beyond the 0.2 mm cap: near, not touching
        (1, 0.03, None, True),  # 1 mm cubes: 0.02 x 1.73 = 0.035 mm
        (1, 0.05, None, False),
    ],
)
def test_contact_tolerance_on_gap(size, gap, contact_tol, touching):
    lower = shapes.box_between((0, 0, 0), (size, size, size))
    upper = shapes.box_between((0, 0, size + gap), (size, size, 2 * size + gap))
    assembly = Assembly.from_meshes({"lower": lower, "upper": upper})
    rel = compute_relations(assembly, contact_tol=contact_tol)
    assert pair(rel, "upper", "lower")[0] == ({"-z"} if touching else set())
    assert pair(rel, "upper", "lower")[1] == ALL - {"-z"}


def test_default_contact_tolerance_follows_the_smaller_part():
    """A 1 mm cube 0.1 mm above a 100 mm slab: the cube's reach (0.035 mm) decides."""
    slab = shapes.box_between((-50, -50, -10), (50, 50, 0))
    near = shapes.box_between((0, 0, 0.03), (1, 1, 1.03))
    far = shapes.box_between((5, 5, 0.1), (6, 6, 1.1))
    rel = compute_relations(Assembly.from_meshes({"slab": slab, "near": near, "far": far}))
    assert pair(rel, "near", "slab")[0] == {"-z"}
    assert pair(rel, "far", "slab")[0] == set()


@pytest.mark.parametrize(("clearance", "touching"), [(0.1, True), (0.3, False)])
def test_pin_with_radial_clearance_touches_its_hole_sideways(clearance, touching):
    """A 6 mm pin in a blind hole 0.1 mm wider in radius: a clearance fit is a contact on
    the four sideways directions (and the hole bottom below); 0.3 mm is beyond the cap."""
    block = shapes.box_between((-10, -10, 0), (10, 10, 10))
    plate = shapes.difference(block, shapes.cylinder(3 + clearance, 4, 11, 64))
    pin = shapes.cylinder(3, 4, 12, 64)
    rel = compute_relations(Assembly.from_meshes({"plate": plate, "pin": pin}))
    assert pair(rel, "pin", "plate")[0] == (SIDE | {"-z"} if touching else {"-z"})
    assert pair(rel, "pin", "plate")[1] == {"+z"}


def test_small_part_inside_the_sweep_of_a_large_face_blocks():
    plate = shapes.box_between((-50, -50, 100), (50, 50, 101))  # two triangles per face
    pebble = shapes.box_between((0, 0, 0), (1, 1, 1))
    rel = compute_relations(Assembly.from_meshes({"plate": plate, "pebble": pebble}))
    assert pair(rel, "plate", "pebble")[1] == ALL - {"-z"}
    assert pair(rel, "pebble", "plate")[1] == ALL - {"+z"}


def test_part_buried_inside_another_is_an_error():
    block = shapes.box_between((0, 0, 0), (10, 10, 10))
    core = shapes.box_between((4, 4, 4), (6, 6, 6))
    with pytest.raises(ValueError, match="'block' and 'core' interpenetrate"):
        compute_relations(Assembly.from_meshes({"block": block, "core": core}))


def test_progress_bar(capsys):
    compute_relations(shapes.stacked_cubes(), progress=True)
    assert "pair" in capsys.readouterr().err


@pytest.mark.parametrize(("hole_sections", "peg_sections"), [(64, 48), (32, 100), (100, 32)])
def test_pin_drawn_at_hole_diameter_with_other_tessellation(hole_sections, peg_sections):
    """Polygons of different counts overlap by up to R (1 - cos(pi / n)): still a fit."""
    block = shapes.box_between((-20, -20, 0), (20, 20, 10))
    plate = shapes.difference(block, shapes.cylinder(5, -1, 11, hole_sections))
    peg = shapes.cylinder(5, 0, 15, peg_sections)
    rel = compute_relations(Assembly.from_meshes({"plate": plate, "peg": peg}))
    assert pair(rel, "peg", "plate") == (SIDE, {"+z", "-z"})


def test_coarse_tessellation_overlap_beyond_tolerance_is_an_error():
    """17-gon hole, 23-gon peg: 0.08 mm overlap, beyond an explicit 0.05 mm tolerance
    (the default pair tolerance here, 0.17 + 0.054 mm, accepts it as a fit)."""
    block = shapes.box_between((-20, -20, 0), (20, 20, 10))
    plate = shapes.difference(block, shapes.cylinder(5, -1, 11, 17))
    peg = shapes.cylinder(5, 0, 15, 23)
    assembly = Assembly.from_meshes({"plate": plate, "peg": peg})
    with pytest.raises(ValueError, match=r"'plate' and 'peg' interpenetrate by about 0\.08"):
        compute_relations(assembly, penetration_tol=0.05)
    assert pair(compute_relations(assembly), "peg", "plate") == (SIDE, {"+z", "-z"})


@pytest.mark.filterwarnings("ignore:part .* is not watertight")
def test_open_disc_springs_touching_along_free_edges_are_not_interpenetrating():
    """Open meshes (faces lost in tessellation) of two stacked disc springs: their rim bands
    lie on one cylinder and meet along free edges; eroding the faces along their normals only
    never parts them (the APLAN multiplate clutch), eroding the free edges too does."""
    assembly = shapes.open_disc_springs()
    assert not any(p.mesh.is_watertight for p in assembly.parts)
    rel = compute_relations(assembly)
    assert rel.tt[rel.index("upper"), rel.index("lower")].any()


@pytest.mark.filterwarnings("ignore:part .* is not watertight")
def test_open_disc_springs_sunk_into_each_other_are_an_error():
    with pytest.raises(ValueError, match="'lower' and 'upper' interpenetrate"):
        compute_relations(shapes.open_disc_springs(sink=1.5))


def test_pieces_of_the_contact_graph_are_joined_by_their_nearest_parts():
    """A lid floating 1 mm over a box on its foot (a visual model's gap) could never be
    inserted: the contact graph's pieces are joined by their nearest parts, the lid
    touching the box from above; a block far off, 30 mm from everything (over half its
    own diagonal), is left alone; one warning names them. Where no two parts touch at all
    nothing is added (the gap tests above)."""
    import warnings

    meshes = {
        "foot": shapes.box_between((10, 10, -5), (30, 30, 0)),
        "box": shapes.box_between((0, 0, 0), (40, 40, 20)),
        "lid": shapes.box_between((0, 0, 21), (40, 40, 25)),
        "far": shapes.box_between((70, 0, 0), (80, 10, 10)),
    }
    raw = compute_relations(Assembly.from_meshes(meshes))
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        rel = with_nearest(raw)
    box, lid, far = (rel.parts.index(p) for p in ("box", "lid", "far"))
    assert raw.nearest == (("box", "lid", 4, 1.0),) and not raw.tc[lid].any()
    assert rel.tc[lid, box].tolist() == [False] * 5 + [True]  # the box is below it (-z)
    assert rel.tc[box, lid, 4] and rel.sp[lid, box, 5]
    assert not rel.tc[far].any() and not rel.tc[:, far].any()
    told = [str(w.message) for w in said if "joined by the nearest parts" in str(w.message)]
    assert len(told) == 1 and "box to lid (1 mm)" in told[0]
