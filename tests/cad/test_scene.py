"""Scene files: part ids and names from the file, its hierarchy, units, identical parts."""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np
import pytest
import trimesh

from cad import load_assembly, load_parts
from cad.bom import PartRecord
from cad.identical import shape_classes
from cad.scene import (
    STEP_CHORD_MM,
    clean_name,
    display_name,
    is_generic,
    load_scene_file,
    read_scene,
    unique_ids,
)
from tests.cad import shapes

DATA = Path(__file__).parent / "data"


@pytest.mark.parametrize(
    ("raw", "clean"),
    [
        ("Hex Nut M6<2>", "hex_nut_m6"),
        ("bearing#1:23:2:16:4:13:10:12:11", "bearing"),
        ("Bolt:1", "bolt"),
        ("Bracket (3)", "bracket"),
        ("Side Panel.SLDPRT", "side_panel"),
        ("608-2RS bearing", "p_608_2rs_bearing"),
        ("NAUO7", "nauo7"),
        ("=>[0:1:1:7]_1", "1"),
        (
            "a-very-long-name-of-a-part-that-goes-on-and-on-forever",
            "part_that_goes_on_and_on_forever",
        ),
        ("User Library-XBee-Chip_XBee-10pin-male", "xbee_chip_xbee_10pin_male"),
        ("User Library-XBee-Chip_XBee-Chip-antenna", "xbee_chip_xbee_chip_antenna"),
    ],
)
def test_clean_name(raw, clean):
    assert clean_name(raw) == clean


@pytest.mark.parametrize(
    ("raw", "shown"),
    [
        ("Hex Nut M6<2>", "Hex Nut M6"),
        ("Washer#1:8:6", "Washer"),
        ("Bolt:1", "Bolt"),
        ("Tom <b>", "Tom <b>"),
        ('"><img src=x>', '"><img src=x>'),
        ("Gear <small> (3)", "Gear <small>"),
        ("<2>", "<2>"),
    ],
)
def test_display_name_drops_only_the_instance_suffix(raw, shown):
    assert display_name(raw) == shown


@pytest.mark.parametrize(
    ("name", "generic"),
    [("nauo7", True), ("12", True), ("open_cascade_step_translator_7_8_1_1", True),
     ("mesh_0", True), ("mesh0", True), ("g3", True), ("bolt", False), ("", True),
     ("p_0_1_1_7_1", True), ("0_1_1_7", True), ("p_608_2rs_bearing", False),
     ("p_91780a169", False)],
)  # fmt: skip
def test_generic_names(name, generic):
    assert is_generic(name) == generic


def test_unique_ids_number_repeats_in_order():
    assert unique_ids(["nut", "bolt", "nut", "nut"]) == ["nut_1", "bolt", "nut_2", "nut_3"]
    assert unique_ids(["cap"], taken={"cap"}) == ["cap_2"]


def test_step_in_inches_with_a_product_tree():
    pytest.importorskip("cascadio")
    assembly = load_assembly(DATA / "table_frame_in.step")
    assert assembly.ids == ("base_plate", "cap_1", "pillar_1", "cap_2", "pillar_2", "top_plate")
    assert [p.name for p in assembly.parts][:3] == ["Base Plate", "Cap", "Pillar"]
    assert assembly.groups == (
        ("pillar_unit_1", ("cap_1", "pillar_1")),
        ("pillar_unit_2", ("cap_2", "pillar_2")),
    )
    # 4 x 4 x 0.5 inch base plate, read in millimetres
    base = assembly.parts[0]
    assert np.allclose(base.mesh.extents, [101.6, 101.6, 12.7], atol=1e-3)
    assert shape_classes(assembly.parts) == (
        "base_plate", "cap", "pillar", "cap", "pillar", "top_plate",
    )  # fmt: skip


def test_step_tessellation_tolerance_reaches_cascadio(step_deflections):
    scene = load_scene_file(DATA / "table_frame_in.step")
    assert step_deflections == [STEP_CHORD_MM] and len(scene.geometry) == 6


def test_a_spec_may_name_one_part_of_a_scene():
    pytest.importorskip("cascadio")
    records = [
        PartRecord(id="c", file="table_frame_in.step#cap_2"),
        PartRecord(id="b", file="table_frame_in.step#Base Plate"),
    ]
    assembly = load_parts(records, DATA)
    assert assembly.ids == ("c", "b")
    assert np.isclose(assembly.parts[0].mesh.bounds[0][0], 69.85, atol=1e-3)
    with pytest.raises(ValueError, match=r"no part 'cap_9' in .*its parts: base_plate, cap_1"):
        load_parts([PartRecord(id="x", file="table_frame_in.step#cap_9")], DATA)


def write_named_glb(path: Path) -> Path:
    """A glTF in metres: a product node over two groups, CAD-style instance names."""
    scene = trimesh.Scene()
    parts = {
        "Bottom Plate#1:2:3": shapes.box_between((0, 0, 0), (40, 40, 5)),
        "bearing#1:23:2:16:4": shapes.box_between((5, 5, 5), (15, 15, 15)),
        "bearing#1:23:2:16:5": shapes.box_between((25, 5, 5), (35, 15, 15)),
        "NAUO7": shapes.box_between((0, 0, 15), (40, 40, 20)),
    }
    scene.graph.update(frame_from="world", frame_to="Pump Assembly")
    scene.graph.update(frame_from="Pump Assembly", frame_to="Bearing Set")
    for k, (name, mesh) in enumerate(parts.items()):
        parent = "Bearing Set" if name.startswith("bearing") else "Pump Assembly"
        scene.add_geometry(
            mesh.copy().apply_scale(0.001),
            node_name=name,
            geom_name=f"Mesh_{k}",
            parent_node_name=parent,
        )
    scene.export(path)
    return path


def write_3dxml(path, parts):
    """A minimal 3DXML (tessellated): one Reference3D per part under a root product."""
    refs, files = [], {}
    k = 2
    for name, mesh in parts.items():
        pid, rid, iid, irid = k, k + 1, k + 2, k + 3
        k += 4
        rep = f"part{pid}.3DRep"
        pos = " ".join(f"{x:.6g},{y:.6g},{z:.6g}" for x, y, z in mesh.vertices)
        nor = " ".join(f"{x:.6g},{y:.6g},{z:.6g}" for x, y, z in mesh.vertex_normals)
        tri = " ".join(str(int(i)) for i in np.asarray(mesh.faces).ravel())
        files[rep] = (
            '<?xml version="1.0"?><XMLRepresentation xmlns="http://www.3ds.com/xsd/3DXML">'
            f'<Root><Rep><Faces><Face triangles="{tri}"/></Faces><VertexBuffer>'
            f"<Positions>{pos}</Positions><Normals>{nor}</Normals></VertexBuffer></Rep></Root>"
            "</XMLRepresentation>"
        )
        refs.append(
            f'<Reference3D id="{pid}" name="{name}"/>'
            f'<ReferenceRep id="{rid}" name="{name}" format="TESSELLATED" '
            f'associatedFile="urn:3DXML:{rep}"/>'
            f'<InstanceRep id="{irid}"><IsAggregatedBy>{pid}</IsAggregatedBy>'
            f"<IsInstanceOf>{rid}</IsInstanceOf></InstanceRep>"
            f'<Instance3D id="{iid}" name="{name}.1"><IsAggregatedBy>1</IsAggregatedBy>'
            f"<IsInstanceOf>{pid}</IsInstanceOf>"
            "<RelativeMatrix>1 0 0 0 1 0 0 0 1 0 0 0</RelativeMatrix></Instance3D>"
        )
    files["Product.3dxml"] = (
        '<?xml version="1.0"?><Model_3dxml xmlns="http://www.3ds.com/xsd/3DXML">'
        '<ProductStructure root="1"><Reference3D id="1" name="Root Assembly"/>'
        + "".join(refs)
        + "</ProductStructure></Model_3dxml>"
    )
    files["Manifest.xml"] = '<?xml version="1.0"?><Manifest><Root>Product.3dxml</Root></Manifest>'
    with zipfile.ZipFile(path, "w") as archive:
        for name, text in files.items():
            archive.writestr(name, text)
    return Path(path)


def test_3dxml_sub_assemblies_from_the_instance_paths(tmp_path):
    from cad.scene import _3dxml_groups

    path = write_3dxml(tmp_path / "a.3dxml", {"Plate": shapes.box_between((0, 0, 0), (1, 1, 1))})
    with zipfile.ZipFile(path, "a") as archive:
        archive.writestr(
            "Sub.3dxml",
            '<Model_3dxml><Reference3D id="8" name="Cam Stack"/>'
            '<Reference3D id="2" name="Drive"/></Model_3dxml>',
        )
    nodes = ["nut#1:3:2:9:8:15:14:16:4", "bolt#1:3:2:9:8:17:12:16:4", "ring#1:3:2:19:18:16:4"]
    groups = _3dxml_groups(path, nodes)
    assert groups == [("Drive", nodes), ("Cam Stack", nodes[:2])]


def test_3dxml_parts_and_names(tmp_path):
    b = shapes.box_between
    path = write_3dxml(
        tmp_path / "plate.3dxml",
        {
            "Base Plate": b((0, 0, 0), (40, 40, 5)),
            "Washer": b((5, 5, 5), (15, 15, 7)),
            "Washer ": b((25, 25, 5), (35, 35, 7)),
        },
    )
    assembly = load_assembly(path)
    assert assembly.ids == ("base_plate", "washer_1", "washer_2")
    assert assembly.parts[0].name == "Base Plate" and assembly.units == "mm"
    corners = sorted(tuple(p.mesh.bounds[0].round(6)) for p in assembly.parts[1:])
    assert corners == [(5, 5, 5), (25, 25, 5)]
    assert shape_classes(assembly.parts)[1:] == ("washer", "washer")


def test_occ_label_nodes_take_their_parents_names(tmp_path):
    """A Pro/E STEP through cascadio: each solid is a node ``=>[0:1:1:7]`` (an OCC label)
    under its product's instance node; ids and names come from the product, never the label
    (trimesh's models/as1_pe_203.stp, the CAx-IF bolted brackets)."""
    scene = trimesh.Scene()
    scene.graph.update(frame_from="world", frame_to="AS1_PE_ASM")
    for k, (product, label) in enumerate(
        [
            ("L-BRACKET_1", "=>[0:1:1:7]_1"),
            ("BOLT_3", "=>[0:1:1:11]_3"),
            ("BOLT_4", "=>[0:1:1:11]_4"),
        ]
    ):
        scene.graph.update(frame_from="AS1_PE_ASM", frame_to=product)
        mesh = shapes.box_between((10 * k, 0, 0), (10 * k + 5, 5, 5)).apply_scale(0.001)
        scene.add_geometry(mesh, node_name=label, geom_name=f"SOLID_{k}", parent_node_name=product)
    path = tmp_path / "as1_pe.glb"
    scene.export(path)
    parts = read_scene(path)
    assert sorted(zip(parts.ids, parts.names, strict=True)) == [
        ("bolt_3", "BOLT_3"), ("bolt_4", "BOLT_4"), ("l_bracket_1", "L-BRACKET_1"),
    ]  # fmt: skip


def test_one_obj_file_with_several_objects_is_an_assembly(tmp_path):
    """An OBJ exported with one ``o`` object per part: each object is a part (it was read
    as one merged part); a part file of a folder with several objects stays one part."""
    scene = trimesh.Scene()
    scene.add_geometry(
        shapes.box_between((0, 0, 0), (40, 40, 5)), node_name="Base Plate", geom_name="Base Plate"
    )
    scene.add_geometry(
        shapes.box_between((5, 5, 5), (15, 15, 15)), node_name="Block", geom_name="Block"
    )
    path = tmp_path / "pair.obj"
    scene.export(path)
    assembly = load_assembly(path)
    assert sorted(assembly.ids) == ["base_plate", "block"]
    assert all(p.mesh.is_watertight for p in assembly.parts)
    folder = tmp_path / "parts"
    folder.mkdir()
    path.rename(folder / "pair.obj")
    (folder / "other.stl").write_bytes(
        shapes.box_between((0, 0, 5), (4, 4, 9)).export(file_type="stl")
    )
    parts = load_assembly(folder)
    assert parts.ids == ("other", "pair") and len(parts.parts[1].mesh.faces) == 24


def test_gltf_names_and_hierarchy(tmp_path):
    """Names from the nodes; the name-less ``NAUO7`` straight under the product is ``part``,
    never the product's name (no such part is in the tree: trimesh's glTF export of
    ``FM1_satellite.3DXML`` once named three parts ``satellite_1..3``)."""
    path = write_named_glb(tmp_path / "pump.glb")
    scene = read_scene(path)
    assert scene.ids == ("bearing_1", "bearing_2", "bottom_plate", "part")
    assert scene.groups == (("bearing_set", ("bearing_1", "bearing_2")),)
    assembly = load_assembly(path)
    assert assembly.units == "m"
    assert np.allclose(assembly.parts[2].mesh.extents, [40, 40, 5], atol=1e-4)
    classes = shape_classes(assembly.parts)
    assert classes[0] == classes[1] == "bearing" and classes[2] == "bottom_plate"


def test_occt_reference_labels_give_way_to_the_product_name(tmp_path):
    """Pro/E STEP through cascadio: shape nodes ``=>[0:1:1:7]`` under ``L-BRACKET``."""
    scene = trimesh.Scene()
    scene.graph.update(frame_from="world", frame_to="AS1_PE_ASM")
    nodes = {
        "L-BRACKET": ("=>[0:1:1:7]", shapes.box_between((0, 0, 0), (40, 40, 5))),
        "L-BRACKET_1": ("=>[0:1:1:7]_1", shapes.box_between((0, 0, 5), (40, 40, 10))),
        "PLATE": ("=>[0:1:1:3]", shapes.box_between((0, 0, 10), (40, 40, 15))),
    }
    for k, (parent, (node, mesh)) in enumerate(nodes.items()):
        scene.graph.update(frame_from="AS1_PE_ASM", frame_to=parent)
        scene.add_geometry(
            mesh.copy().apply_scale(0.001),
            node_name=node,
            geom_name=f"SOLID_{k}",
            parent_node_name=parent,
        )
    path = tmp_path / "brackets.glb"
    scene.export(path)
    parts = read_scene(path)
    assert parts.ids == ("l_bracket_1", "l_bracket_2", "plate")
    assert parts.names == ("L-BRACKET", "L-BRACKET", "PLATE")


def _scaled_step(source: Path, target: Path, factor: float) -> Path:
    """``source`` with every coordinate and length (points, vector magnitudes) times
    ``factor``, its units unchanged."""
    import re

    def points(match: re.Match) -> str:
        values = ",".join(f"{float(v) * factor:.9g}" for v in match.group(2).split(","))
        return f"{match.group(1)}({values})"

    text = source.read_text()
    text = re.sub(r"(CARTESIAN_POINT\('[^']*',)\(([^)]*)\)", points, text)
    text = re.sub(
        r"(VECTOR\('[^']*',#\d+,)([-\d.Ee+]+)\)",
        lambda m: f"{m.group(1)}{float(m.group(2)) * factor:.9g})",
        text,
    )
    target.write_text(text)
    return target


def test_millimetre_numbers_under_an_inch_label_are_read_as_millimetres(tmp_path):
    """A Pro/E-style STEP: the unit says INCH, the numbers are millimetres (a 400 x 400 mm
    plate that, read in inches, would be 10 m wide)."""
    pytest.importorskip("cascadio")
    from cad.scene import coordinate_scale, step_length_unit

    path = _scaled_step(DATA / "table_frame_in.step", tmp_path / "frame_mm_as_in.step", 100.0)
    assert step_length_unit(path) == "in"
    with pytest.warns(UserWarning, match=r"declares inches, but read so it is .* m across"):
        assembly = load_assembly(path)
    assert np.allclose(assembly.parts[0].mesh.extents, [400, 400, 50], atol=1e-2)
    assert coordinate_scale(path) == pytest.approx(1000 / 25.4)  # what plan.json records
    # a true inch file stays in inches (4 in = 101.6 mm)
    assert step_length_unit(DATA / "table_frame_in.step") == "in"
    assert step_length_unit(DATA / "two_boxes.step") == "mm"


def test_a_gltf_with_millimetre_numbers_is_read_in_millimetres(tmp_path):
    """glTF is metres; a converter that keeps a CAD model's millimetre numbers writes an
    engine hundreds of metres across (Khronos' 2CylinderEngine: 743 m)."""
    scene = trimesh.Scene()
    scene.add_geometry(shapes.box_between((0, 0, 0), (400, 300, 20)), node_name="Block")
    scene.add_geometry(shapes.box_between((0, 0, 20), (40, 40, 60)), node_name="Cap")
    path = tmp_path / "engine.glb"
    scene.export(path)
    expected = r"declares metres \(glTF\), but read so it is 504 m across"
    from cad.scene import coordinate_scale

    with pytest.warns(UserWarning, match=expected):
        assembly = load_assembly(path)
    assert np.allclose(assembly.parts[0].mesh.extents, [400, 300, 20], atol=1e-3)
    assert coordinate_scale(path) == pytest.approx(1.0)  # what plan.json records


def test_a_gltf_declaring_millimetres_keeps_its_numbers(tmp_path):
    """trimesh writes a mesh's unit into the glTF (``extras.units``), as in a public pins
    assembly 360 mm across: the file says millimetres, so nothing is rescaled (it was read
    as metres taken for millimetres, 1000 times too small, with tolerances to match)."""
    import warnings

    from cad.scene import coordinate_scale

    scene = trimesh.Scene()
    for name, lo, hi in (("Block", (0, 0, 0), (400, 300, 20)), ("Cap", (0, 0, 20), (40, 40, 60))):
        mesh = shapes.box_between(lo, hi)
        mesh.units = "mm"
        scene.add_geometry(mesh, node_name=name)
    path = tmp_path / "pins.glb"
    scene.export(path)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assembly = load_assembly(path)
    assert not [w for w in caught if "declares" in str(w.message)]
    assert assembly.units == "mm"
    assert np.allclose(assembly.parts[0].mesh.extents, [400, 300, 20], atol=1e-3)
    assert coordinate_scale(path) == 1.0


def test_plain_part_names_win_over_the_product_name(tmp_path):
    """A FreeCAD STEP (the APLAN benchmark's pen and shear mold): parts ``body_001`` and
    ``3_001`` (item numbers) straight under the product ``asm_pen``: ids come from the parts'
    own names, never the product's (which named every part ``asm_pen_<n>``)."""
    scene = trimesh.Scene()
    scene.graph.update(frame_from="world", frame_to="asm_pen")
    for k, node in enumerate(["body_001", "head_001", "3_001", "12_001"]):
        mesh = shapes.box_between((10 * k, 0, 0), (10 * k + 5, 5, 5)).apply_scale(0.001)
        scene.add_geometry(mesh, node_name=node, geom_name=node, parent_node_name="asm_pen")
    path = tmp_path / "pen.glb"
    scene.export(path)
    parts = read_scene(path)
    assert dict(zip(parts.ids, parts.names, strict=True)) == {
        "body_001": "body_001", "head_001": "head_001", "part_3_001": "3_001",
        "part_12_001": "12_001",
    }  # fmt: skip


def test_a_gltf_mesh_of_several_primitives_is_one_part(tmp_path):
    """A glTF node whose mesh has two primitives (two materials, as CAD exporters write a
    part of two colours) is one part with the node's name, read the same on every load
    (trimesh made each primitive a node named with a random suffix: the 2-cylinder engine
    of the Khronos samples)."""
    import json

    from trimesh.exchange.gltf import export_gltf

    scene = trimesh.Scene()
    scene.graph.update(frame_from="world", frame_to="Gearbox")
    meshes = {
        "Housing": shapes.box_between((0, 0, 0), (40, 40, 5)),
        "Housing lid": shapes.box_between((0, 0, 5), (40, 40, 10)),  # a 2nd primitive
        "Gear": shapes.box_between((10, 10, 10), (20, 20, 15)),
    }
    for k, (name, mesh) in enumerate(meshes.items()):
        colour = trimesh.visual.material.PBRMaterial(baseColorFactor=[60 * k, 90, 200, 255])
        mesh.visual = trimesh.visual.TextureVisuals(material=colour)
        scene.add_geometry(
            mesh.apply_scale(0.001), node_name=name, geom_name=name, parent_node_name="Gearbox"
        )
    files = export_gltf(scene)
    doc = json.loads(files["model.gltf"])
    by_name = {node["name"]: node for node in doc["nodes"]}
    housing, lid = by_name["Housing"], by_name["Housing lid"]
    doc["meshes"][housing["mesh"]]["primitives"] += doc["meshes"][lid["mesh"]]["primitives"]
    lid.pop("mesh")  # an empty node now
    files["model.gltf"] = json.dumps(doc).encode()
    for name, data in files.items():
        (tmp_path / name).write_bytes(data)
    first = read_scene(tmp_path / "model.gltf")
    assert first.ids == ("gear", "housing")
    assert np.allclose(first.meshes[1].extents, [0.04, 0.04, 0.01])
    (tmp_path / "again.gltf").write_bytes(files["model.gltf"])
    assert read_scene(tmp_path / "again.gltf").nodes == first.nodes == ("Gear", "Housing")


def test_3dxml_parts_take_names_from_their_sub_assemblies_never_the_root():
    from cad.scene import _3dxml_ancestors

    references = {"1": "satellite", "2": "Drive", "8": "Cam Stack"}
    node = "Open CASCADE STEP translator 6.2#1:3:2:9:8:15:14:16:4"
    assert _3dxml_ancestors(node, references) == ["Cam Stack", "Drive"]
    assert _3dxml_ancestors("Plate#1:3:2:4", references) == []


def test_generic_names_give_way_to_classes_of_alike_parts(tmp_path):
    """FreeCAD's ``Body``, ``Body001``, ... on a flange coupling: ids by class of identical
    parts (``alike_a_1..2``, ``alike_b_1..3``), the file's names kept as names; a 3DXML of
    name-less parts is never named after its root product."""
    b = shapes.box_between
    scene = trimesh.Scene()
    scene.graph.update(frame_from="world", frame_to="Coupling")
    meshes = [b((0, 0, 0), (40, 40, 5)), b((0, 0, 5), (40, 40, 10))]
    meshes += [b((5 + 10 * k, 5, -5), (8 + 10 * k, 8, 15)) for k in range(3)]
    for k, mesh in enumerate(meshes):
        node = "Body" if k == 0 else f"Body{k:03d}"
        scene.add_geometry(
            mesh.apply_scale(0.001), node_name=node, geom_name=node, parent_node_name="Coupling"
        )
    scene.export(tmp_path / "coupling.glb")
    parts = read_scene(tmp_path / "coupling.glb")
    assert parts.ids == ("alike_a_1", "alike_a_2", "alike_b_1", "alike_b_2", "alike_b_3")
    assert parts.names == ("Body", "Body001", "Body002", "Body003", "Body004")
    unnamed = "Open CASCADE STEP translator 6.2 62.6.1.1"
    alike = {unnamed: b((0, 0, 0), (4, 4, 4)), unnamed + " ": b((9, 0, 0), (13, 4, 4))}
    path = write_3dxml(tmp_path / "sat.3dxml", alike)
    assert read_scene(path).ids == ("alike_a_1", "alike_a_2")


def test_a_gltf_whose_buffer_is_not_its_data_says_which_and_why(tmp_path):
    """A glTF whose buffer uri is replaced by text that is no base64 (or names no file
    beside it): the one-line error names the buffer and the cause, not a reader's bare
    AssertionError."""
    import json

    from cad.errors import GeometryError
    from cad.scene import load_scene_file

    scene = trimesh.Scene(trimesh.creation.box(extents=[0.01, 0.01, 0.01]))
    files = scene.export(file_type="gltf")
    (tmp_path / "box.gltf").write_bytes(files["model.gltf"])
    doc = json.loads(files["model.gltf"])
    for uri, said in (
        ("data:image/jpeg;base64,<img src=x onerror=alert(1)>", "is data that is not base64"),
        ("box0.bin", "file 'box0.bin' is not beside it"),
    ):
        doc["buffers"][0]["uri"] = uri
        (tmp_path / "box.gltf").write_text(json.dumps(doc))
        with pytest.raises(GeometryError, match=f"box.gltf: buffer 0's .*{said}"):
            load_scene_file(tmp_path / "box.gltf")
