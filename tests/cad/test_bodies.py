"""One mesh that is several closed bodies: found, split into parts, kept whole on request."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import trimesh

from cad import compute_relations, load_assembly, load_parts
from cad.bodies import closed_bodies
from cad.bom import PartRecord
from cad.errors import GeometryError
from cad.scene import read_scene


def box(extents, at) -> trimesh.Trimesh:
    return trimesh.creation.box(extents=extents).apply_translation(at)


def faces_apart(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """``mesh`` with every face's vertices its own (how OCCT tessellates B-rep faces:
    faces share positions, never vertex indices)."""
    copy = mesh.copy()
    copy.unmerge_vertices()
    return copy


def fused(*meshes: trimesh.Trimesh) -> trimesh.Trimesh:
    return trimesh.util.concatenate(list(meshes))


def inside_out(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    return trimesh.Trimesh(mesh.vertices, np.asarray(mesh.faces)[:, ::-1])


def volumes(bodies) -> list[float]:
    return [round(float(b.volume), 6) for b in bodies]


@pytest.mark.parametrize("apart", [False, True])
def test_disjoint_boxes_are_bodies_in_the_file_order(apart):
    mesh = fused(box([1, 1, 1], [0, 0, 0]), box([2, 1, 1], [5, 0, 0]), box([1, 1, 3], [0, 5, 0]))
    bodies = closed_bodies(faces_apart(mesh) if apart else mesh)
    assert volumes(bodies) == [1.0, 2.0, 3.0]


def test_a_cylinder_of_separate_faces_is_one_body():
    cylinder = faces_apart(trimesh.creation.cylinder(radius=1.0, height=2.0, sections=24))
    assert closed_bodies(fused(cylinder, box([1, 1, 1], [5, 0, 0]))) is not None
    assert len(closed_bodies(fused(cylinder, box([1, 1, 1], [5, 0, 0])))) == 2
    assert closed_bodies(cylinder) is None


@pytest.mark.parametrize("apart", [False, True])
def test_bodies_resting_face_to_face_are_split_at_their_contact(apart):
    """Parts of one fused solid resting on each other share the positions (and edges) of
    their contact, as the APLAN toy truck's cabin, chassis and supports do: a stack of
    three blocks, one beside the stack on the bottom block, each its own body."""
    bottom, middle = box([4, 4, 1], [0, 0, 0.5]), box([4, 4, 1], [0, 0, 1.5])
    top, beside = box([2, 4, 2], [-1, 0, 3.0]), box([2, 4, 1], [1, 0, 2.5])
    mesh = fused(bottom, middle, top, beside)
    bodies = closed_bodies(faces_apart(mesh) if apart else mesh)
    assert volumes(bodies) == [16.0, 16.0, 16.0, 8.0]
    assert all(b.is_watertight for b in bodies)


def test_a_solid_touching_itself_along_an_edge_stays_one_body():
    """Two lobes of one solid meeting along an edge only (no faces back to back): one
    part, as a single STEP shell is (an Inventor part of one closed shell)."""
    lobes = fused(box([1, 1, 1], [0, 0, 0]), box([1, 1, 1], [1, 1, 0]))
    assert closed_bodies(faces_apart(lobes)) is None


def test_a_cavity_stays_with_the_body_around_it():
    hollow = fused(box([4, 4, 4], [0, 0, 0]), inside_out(box([2, 2, 2], [0, 0, 0])))
    bodies = closed_bodies(fused(hollow, box([1, 1, 1], [10, 0, 0])))
    assert volumes(bodies) == [56.0, 1.0]


def test_a_body_written_inside_out_is_turned():
    bodies = closed_bodies(fused(box([1, 1, 1], [0, 0, 0]), inside_out(box([2, 1, 1], [5, 0, 0]))))
    assert volumes(bodies) == [1.0, 2.0]


def test_a_mesh_with_an_open_piece_is_not_split():
    open_box = box([1, 1, 1], [5, 0, 0])
    open_box.update_faces(np.arange(len(open_box.faces)) > 1)  # one side removed
    assert closed_bodies(fused(box([1, 1, 1], [0, 0, 0]), open_box)) is None


def test_touching_bodies_that_share_a_corner_position_are_one_body():
    bodies = closed_bodies(fused(box([1, 1, 1], [0, 0, 0]), box([1, 1, 1], [1, 1, 1])))
    assert bodies is None


def write_one_node_glb(path, mesh):
    scene = trimesh.Scene()
    scene.add_geometry(mesh, node_name="truck", geom_name="truck")
    scene.export(path)
    return path


def test_a_one_part_file_of_several_bodies_plans_one_part_per_body(tmp_path):
    mesh = fused(box([0.01, 0.01, 0.01], [0, 0, 0]), box([0.01, 0.01, 0.02], [0.05, 0, 0]))
    path = write_one_node_glb(tmp_path / "truck.glb", faces_apart(mesh))
    with pytest.warns(UserWarning, match=r"truck is 2 separate closed bodies.*truck.glb#truck"):
        assembly = load_assembly(path)
    assert [p.id for p in assembly.parts] == ["truck_body_1", "truck_body_2"]
    assert read_scene(path).split == (("truck", ("truck_body_1", "truck_body_2")),)
    assert [round(float(p.mesh.volume)) for p in assembly.parts] == [1000, 2000]  # mm^3


def test_a_spec_part_naming_the_whole_part_keeps_it_one_rigid_part(tmp_path):
    mesh = fused(box([0.01, 0.01, 0.01], [0, 0, 0]), box([0.01, 0.01, 0.02], [0.05, 0, 0]))
    write_one_node_glb(tmp_path / "truck.glb", mesh)
    for file in ("truck.glb#truck", "truck.glb"):  # the part, or the whole file
        with warnings.catch_warnings(record=True) as said:
            warnings.simplefilter("always")
            records = [PartRecord(id="truck", name="truck", file=file)]
            assembly = load_parts(records, tmp_path)
        assert not [w for w in said if "closed bodies" in str(w.message)], file
        assert [p.id for p in assembly.parts] == ["truck"]
        assert round(float(assembly.parts[0].mesh.volume)) == 3000


def write_grouped_glb(path, pieces, loose):
    """A glTF in metres: ``pieces`` (name -> mesh) under a node ``spring``, ``loose``
    beside it, all under a product node."""
    scene = trimesh.Scene()
    scene.graph.update(frame_from="world", frame_to="engine")
    scene.graph.update(frame_from="engine", frame_to="spring")
    for parent, meshes in (("spring", pieces), ("engine", loose)):
        for name, mesh in meshes.items():
            scene.add_geometry(
                mesh.copy().apply_scale(0.001),
                node_name=name,
                geom_name=name,
                parent_node_name=parent,
            )
    scene.export(path)
    return path


def test_overlapping_parts_of_one_sub_assembly_are_one_rigid_part(tmp_path):
    links = {f"link_{k}": box([4, 4, 3], [0, 0, 2.5 * k]) for k in range(3)}  # 0.5 overlaps
    loose = {"block": box([4, 4, 4], [20, 0, 0]), "plate": box([30, 10, 2], [10, 0, -4])}
    path = write_grouped_glb(tmp_path / "engine.glb", links, loose)
    with pytest.warns(
        UserWarning, match=r"engine.glb: parts of one sub-assembly .*spring \(3 parts\)"
    ):
        assembly = load_assembly(path)
    assert assembly.ids == ("block", "plate", "spring")
    spring = assembly.parts[2]
    assert spring.source.endswith("engine.glb#link_0+link_1+link_2")
    assert len(spring.mesh.faces) == 36
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        again = load_parts([PartRecord(id="spring", name="spring", file=spring.source)], tmp_path)
        group = load_parts([PartRecord(id="s", name="s", file="engine.glb#spring")], tmp_path)
    assert len(again.parts[0].mesh.faces) == len(group.parts[0].mesh.faces) == 36


def test_overlapping_parts_of_no_common_group_stay_apart(tmp_path):
    links = {"link_1": box([4, 4, 3], [0, 0, 0]), "link_2": box([4, 4, 3], [20, 0, 0])}
    loose = {"block": box([4, 4, 4], [0, 0, 3])}  # overlaps link_1 by 0.5 mm
    path = write_grouped_glb(tmp_path / "engine.glb", links, loose)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assembly = load_assembly(path)
    assert assembly.ids == ("block", "link_1", "link_2")
    with pytest.raises(GeometryError) as info:
        compute_relations(assembly)
    assert (
        "plan them as one rigid part: in the spec's parts, `- {id: block, file: "
        "'engine.glb#block+link_1'}` in place of both, and no operation placing link_1"
    ) in str(info.value)


def open_halves():
    """A 10 mm cube cut at z = 5 into two open halves, neither with the cut face (parts cut
    from one visual mesh)."""
    cube = trimesh.creation.box(extents=[10, 10, 10]).subdivide()
    centres = cube.triangles_center
    lower = cube.submesh([np.flatnonzero(centres[:, 2] < 0)], append=True)
    upper = cube.submesh([np.flatnonzero(centres[:, 2] > 0)], append=True)
    return lower, upper


def test_open_parts_touching_without_opposing_faces_are_in_contact():
    from cad.assembly import Assembly

    lower, upper = open_halves()
    assert not lower.is_watertight and lower.bounds[1][2] == 0.0 == upper.bounds[0][2]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rel = compute_relations(Assembly.from_meshes({"lower": lower, "upper": upper}))
    up, down = 4, 5  # +z, -z
    assert rel.tc[0, 1].tolist() == [k == up for k in range(6)]
    assert rel.tc[1, 0].tolist() == [k == down for k in range(6)]
    assert rel.sp[1, 0, down] and rel.sp[0, 1, up]
    far = upper.copy().apply_translation([0, 0, 1.0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        apart = compute_relations(Assembly.from_meshes({"lower": lower, "upper": far}))
    assert not apart.tc.any()


def test_the_bodies_of_one_part_fall_into_distinct_shape_classes(tmp_path):
    """The bodies of a split part share the name base ``<part>_body``: three screws and
    two wheels are two shape classes with two names, never one class of five."""
    from cad.identical import shape_classes

    screws = [
        trimesh.creation.cylinder(radius=1, height=8).apply_translation([x, 0, 0])
        for x in (0, 5, 10)
    ]
    wheels = [
        trimesh.creation.cylinder(radius=4, height=2).apply_translation([x, 20, 0]) for x in (0, 12)
    ]
    path = tmp_path / "fused.stl"
    fused(*screws, *wheels).export(path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assembly = load_assembly(path)
    classes = shape_classes(assembly.parts)
    assert len(classes) == 5 and len(set(classes)) == 2
    assert classes[0] == classes[1] == classes[2] != classes[3] == classes[4]


def linked_rings(centre=(0.0, 0.0, 0.0)) -> dict:
    """Two chain links (tori of 10 mm radius, 2 mm tube) through each other, clear of each
    other by 6 mm: as rigid bodies each blocks the other along every direction."""
    c = np.asarray(centre, float)
    a = trimesh.creation.torus(major_radius=10, minor_radius=2, major_sections=48)
    b = a.copy().apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, (1, 0, 0)))
    return {"link_a": a.apply_translation(c), "link_b": b.apply_translation(c + (10, 0, 0))}


def test_locking_parts_of_one_sub_assembly_are_one_rigid_part(tmp_path):
    """Linked links of one group (a patch cable's plug round its boot): no order can place
    both, so they are one part; the same links in no common group stay two."""
    loose = {"plate": box([60, 30, 2], [5, 0, -13])}
    path = write_grouped_glb(tmp_path / "chain.glb", linked_rings(), loose)
    with pytest.warns(UserWarning, match=r"lock each other .*: spring \(2 parts\)"):
        assembly = load_assembly(path)  # the group's node is called spring
    assert assembly.ids == ("plate", "spring")
    assert assembly.parts[1].source.endswith("chain.glb#link_a+link_b")
    apart = write_grouped_glb(tmp_path / "apart.glb", {}, {**linked_rings(), **loose})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert load_assembly(apart).ids == ("link_a", "link_b", "plate")


def test_a_part_joined_of_joined_parts_names_every_node_it_holds(tmp_path):
    """A bead sunk into one link (joined by overlap first), the links then locking each
    other (joined second): the part's source lists the bead's node too, so a spec naming
    the part by its source reads the same mesh (the two-cylinder engine's block lost the
    19 pieces joined into one of its members, and a plate no longer touched it)."""
    rings = linked_rings()
    bead = trimesh.creation.icosphere(subdivisions=2, radius=1.5).apply_translation((-10, 0, 1.5))
    loose = {"plate": box([60, 30, 2], [5, 0, -13])}
    path = write_grouped_glb(tmp_path / "chain.glb", {**rings, "bead": bead}, loose)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assembly = load_assembly(path)
        assert assembly.ids == ("plate", "spring")
        chain = assembly.parts[1]
        assert sorted(chain.source.partition("#")[2].split("+")) == ["bead", "link_a", "link_b"]
        again = load_parts([PartRecord(id="c", name="c", file=chain.source)], tmp_path)
    assert len(again.parts[0].mesh.faces) == len(chain.mesh.faces)


def brep_patches(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """``mesh`` as OCCT tessellates a B-rep: each planar face (facet) a patch of its own
    vertices, the patches one after the other."""
    pieces = []
    for facet in mesh.facets:
        tri = np.asarray(mesh.faces)[facet]
        used, local = np.unique(tri, return_inverse=True)
        pieces.append(trimesh.Trimesh(mesh.vertices[used], local.reshape(-1, 3), process=False))
    return trimesh.util.concatenate(pieces)


def slab_on_block():
    """A 20 x 20 x 5 slab on a 10 mm cube, one corner and two edges flush: the cube's top
    edges end halfway along the slab's (T-junctions), so by positions the two are one
    piece that cannot be cut at their contact."""
    cube = brep_patches(box([10, 10, 10], [5, 5, 5]))
    slab = brep_patches(box([20, 20, 5], [10, 10, 12.5]))
    return fused(cube, slab)


def test_the_shells_a_step_declares_cut_a_fused_mesh_into_its_bodies():
    mesh = slab_on_block()
    assert closed_bodies(mesh) is None  # the mesh alone: one piece
    bodies = closed_bodies(mesh, shells=(6, 6))
    assert volumes(bodies) == [1000.0, 2000.0]
    assert all(b.is_watertight for b in (trimesh.Trimesh(b.vertices, b.faces) for b in bodies))
    assert closed_bodies(mesh, shells=(5, 7)) is None  # no cut closes both: as before
    assert closed_bodies(mesh, shells=(6, 5)) is None  # not the faces declared


def write_tree_glb(path, tree):
    """A glTF in metres of a file tree: ``tree`` maps a name to a mesh (a part node) or to
    a dict (a group node holding its own tree), all under a product node ``engine``."""
    scene = trimesh.Scene()
    scene.graph.update(frame_from="world", frame_to="engine")

    def add(parent, items):
        for name, item in items.items():
            if isinstance(item, dict):
                scene.graph.update(frame_from=parent, frame_to=name)
                add(name, item)
            else:
                scene.add_geometry(
                    item.copy().apply_scale(0.001),
                    node_name=name,
                    geom_name=name,
                    parent_node_name=parent,
                )

    add("engine", tree)
    scene.export(path)
    return path


def coil(turns: int, at=(0.0, 0.0, 0.0)) -> dict:
    """A spring modelled as ``turns`` identical links: one 12 x 2 x 3 bar a turn, each
    turned 36 degrees on the one below and standing on it (touching, overlapping nothing,
    locking nothing)."""
    links = {}
    for k in range(turns):
        bar = box([12, 2, 3], [0, 0, 0])
        bar.apply_transform(trimesh.transformations.rotation_matrix(k * np.pi / 5, (0, 0, 1)))
        links[f"link_{k}"] = bar.apply_translation(np.add(at, (0, 0, 3.0 * k)))
    return links


def cylinder_head() -> dict:
    """A head holding a valve (its spring of 5 coil links on the cover, its cap on them)
    and the block and cover, which overlap by 0.5 mm (a visual model's press fit)."""
    valve = {"spring": coil(5, at=(0, 0, 15)), "cap": box([14, 14, 2], [0, 0, 29.5])}
    return {
        "head": {
            "valve": valve,
            "block": box([40, 40, 10], [0, 0, 5]),
            "cover": box([40, 40, 4], [0, 0, 11.5]),
        },
        "base": box([60, 60, 4], [0, 0, -2]),
    }


def test_a_spring_of_identical_links_touching_in_one_innermost_group_is_one_part(tmp_path):
    """The valve spring's five links (one shape, each touching the next, none overlapping
    or locking another) are one part; the cap in the valve's group stays a part."""
    path = write_tree_glb(tmp_path / "engine.glb", cylinder_head())
    with pytest.warns(UserWarning, match=r"one shape touching each other in a chain.*spring"):
        assembly = load_assembly(path)
    spring = assembly.parts[assembly.ids.index("spring")]
    assert spring.source.endswith("#" + "+".join(f"link_{k}" for k in range(5)))
    assert set(assembly.ids) == {"spring", "cap", "block", "cover", "base"}


def test_identical_pieces_of_a_group_that_do_not_touch_in_one_chain_stay_parts(tmp_path):
    """Four identical screws in one group, apart from each other: assembled one by one."""
    screws = {f"screw_{k}": box([3, 3, 12], [10.0 * k, 0, 6]) for k in range(4)}
    path = write_tree_glb(
        tmp_path / "plate.glb", {"screws": screws, "plate": box([50, 8, 2], [15, 0, -1])}
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assembly = load_assembly(path)
    assert assembly.ids == ("plate", "screw_0", "screw_1", "screw_2", "screw_3")


def test_overlapping_members_of_a_group_holding_groups_are_never_joined(tmp_path):
    """The head holds the valve's group: it is a sub-assembly of components, so its block
    and cover overlapping is reported by the relations (with the spec line accepting the
    pair), never welded into one part, let alone with the rest of the product (the merge
    joined the two-cylinder engine's block, crankshaft and valve gear into one part)."""
    path = write_tree_glb(tmp_path / "engine.glb", cylinder_head())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assembly = load_assembly(path)
        assert {"block", "cover"} <= set(assembly.ids)
        with pytest.raises(
            GeometryError, match=r"'block' and 'cover'.*overlap_ok: \[\[block, cover\]\]"
        ):
            compute_relations(assembly)


def test_a_spring_under_a_node_the_file_leaves_unnamed_is_named_by_its_first_link(tmp_path):
    """The two-cylinder engine's spring nodes have no names (read as ``group_<n>``): the
    joined spring takes its first link's name, which says what it is."""
    links = {name.replace("link", "coil"): mesh for name, mesh in coil(4).items()}
    tree = {"group_4": links, "base": box([30, 30, 2], [0, 0, -2.5])}
    path = write_tree_glb(tmp_path / "engine.glb", tree)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assembly = load_assembly(path)
    assert assembly.ids == ("base", "coil_0")
    assert assembly.parts[1].source.endswith("#coil_0+coil_1+coil_2+coil_3")


def test_identical_pieces_touching_other_than_in_a_chain_stay_parts(tmp_path):
    """Two identical gears meshing (two pieces) and four identical blocks in a square
    (each touching three, corners included) are no chain: each piece stays a part."""
    pair = {"gear_a": box([10, 10, 4], [0, 0, 2]), "gear_b": box([10, 10, 4], [10, 0, 2])}
    square = {f"block_{k}": box([5, 5, 5], [5.0 * (k % 2), 5.0 * (k // 2), 2.5]) for k in range(4)}
    tree = {"gears": pair, "blocks": square, "plate": box([40, 40, 2], [5, 5, -1])}
    path = write_tree_glb(tmp_path / "train.glb", tree)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ids = load_assembly(path).ids
    assert set(ids) == {"plate", *pair, *square}
