"""Reading assemblies: folders, scenes, BOMs, assembly.yaml, units and bad input."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from asmplan.pipeline import part_geometry as load_geometry
from cad import Assembly, compute_relations, load_assembly, read_bom
from tests.cad import shapes


def write_folder(folder: Path, assembly: Assembly, suffix: str = ".stl", scale: float = 1.0):
    """Export each part of ``assembly`` to ``folder/<id><suffix>``, scaled by ``scale``."""
    folder.mkdir(parents=True, exist_ok=True)
    for part in assembly.parts:
        part.mesh.copy().apply_scale(scale).export(folder / f"{part.id}{suffix}")
    return folder


def write_scene(path: Path, assembly: Assembly, scale: float = 1.0) -> Path:
    """One multi-body scene, a node per part named by its id."""
    scene = trimesh.Scene()
    for part in assembly.parts:
        # move each body to its own origin and put the offset in the node transform
        offset = part.mesh.bounds.mean(axis=0) * scale
        local = part.mesh.copy().apply_scale(scale).apply_translation(-offset)
        transform = trimesh.transformations.translation_matrix(offset)
        scene.add_geometry(local, node_name=part.id, geom_name=f"g_{part.id}", transform=transform)
    scene.export(path)
    return path


def same_tables(a, b) -> bool:
    """Equal tables once ``b`` is put in ``a``'s part order."""
    if sorted(a.parts) != sorted(b.parts):
        return False
    order = [b.index(p) for p in a.parts]
    tc = b.tc[np.ix_(order, order)]
    tt = b.tt[np.ix_(order, order)]
    return np.array_equal(a.tc, tc) and np.array_equal(a.tt, tt)


@pytest.fixture(scope="module")
def reference():
    return compute_relations(shapes.boxed_container())


@pytest.mark.parametrize("suffix", [".stl", ".obj", ".ply"])
def test_folder_of_meshes(tmp_path, reference, suffix):
    folder = write_folder(tmp_path / "asm", shapes.boxed_container(), suffix)
    assembly = load_assembly(folder)
    assert assembly.ids == ("item", "lid", "tray")
    assert assembly.units == "mm"
    assert same_tables(compute_relations(assembly), reference)


def test_folder_in_centimetres_with_units_option(tmp_path, reference):
    folder = write_folder(tmp_path / "asm", shapes.boxed_container(), scale=0.1)
    assembly = load_assembly(folder, units="cm")
    assert assembly.units == "cm"
    assert same_tables(compute_relations(assembly), reference)


def test_glb_scene_in_metres_gives_same_tables(tmp_path, reference):
    path = write_scene(tmp_path / "asm.glb", shapes.boxed_container(), scale=0.001)
    assembly = load_assembly(path)
    assert assembly.units == "m"
    assert assembly.ids == ("item", "lid", "tray")
    assert np.allclose(assembly.parts[2].mesh.bounds, [[0, 0, 0], [30, 30, 20]], atol=1e-5)
    assert same_tables(compute_relations(assembly), reference)


def test_bom_csv_in_folder(tmp_path):
    folder = write_folder(tmp_path / "asm", shapes.boxed_container())
    (folder / "bom.csv").write_text(
        "id,name,file,quantity,type\n"
        "T,Tray,tray.stl,1,\n"
        "L,Lid,lid.stl,1,cover\n"
        "I,Item,item.stl,2,\n"
    )
    assembly = load_assembly(folder)
    assert assembly.ids == ("T", "L", "I")
    assert [p.name for p in assembly.parts] == ["Tray", "Lid", "Item"]
    assert [p.quantity for p in assembly.parts] == [1, 1, 2]
    assert assembly.parts[1].type == "cover"
    rel = compute_relations(assembly)
    assert rel.tc[rel.index("I"), rel.index("T"), 5]


def test_bom_yaml_and_scene(tmp_path):
    path = write_scene(tmp_path / "asm.glb", shapes.stacked_cubes())
    bom = tmp_path / "bom.yaml"
    bom.write_text("parts:\n  - {id: B, file: bottom}\n  - {id: T, file: top, type: lid}\n")
    assembly = load_assembly(path, bom=bom)
    assert assembly.ids == ("B", "T")
    assert [r.type for r in read_bom(bom)] == ["", "lid"]


def test_assembly_yaml_parts_load_through_the_spec(tmp_path, reference):
    # cad takes part records, not YAML: the spec's one parser reads the parts
    write_folder(tmp_path / "meshes", shapes.boxed_container(), scale=0.1)
    spec = tmp_path / "assembly.yaml"
    spec.write_text(
        "units: cm\n"
        "agents: {H: human}\n"
        "operations: [{id: '1.1', agents: {H: 1}}]\n"
        "parts:\n"
        "  - {id: item, file: meshes/item.stl}\n"
        "  - {id: lid, name: Lid, file: meshes/lid.stl, quantity: 1, type: cover}\n"
        "  - {id: tray, file: meshes/tray.stl}\n"
    )
    assembly = load_geometry(spec)
    assert assembly.ids == ("item", "lid", "tray")
    assert assembly.parts[1].name == "Lid"
    assert same_tables(compute_relations(assembly), reference)


def test_step_without_cascadio_is_a_clear_error(tmp_path):
    pytest.importorskip("trimesh")
    try:
        import cascadio  # noqa: F401

        pytest.skip("cascadio installed")
    except ImportError:
        pass
    path = tmp_path / "asm.step"
    path.write_text("ISO-10303-21;\n")
    with pytest.raises(ValueError, match="cascadio"):
        load_assembly(path)


def _bad_bom(folder: Path, rows: str) -> Path:
    (folder / "bom.csv").write_text("id,name,file,quantity,type\n" + rows)
    return folder


BAD = [
    ("missing path", lambda d: d / "nope", FileNotFoundError, "nope"),
    (
        "bom names missing file",
        lambda d: _bad_bom(d, "a,,gone.stl,1,\n"),
        FileNotFoundError,
        "gone.stl",
    ),
    ("bom row without mesh", lambda d: _bad_bom(d, "a,,,1,\n"), ValueError, "'a' has no mesh"),
    (
        "duplicate ids",
        lambda d: _bad_bom(d, "a,,lid.stl,1,\na,,tray.stl,1,\n"),
        ValueError,
        "duplicate part id 'a'",
    ),
    ("bad quantity", lambda d: _bad_bom(d, "a,,lid.stl,many,\n"), ValueError, "quantity"),
    (
        "bom type a mapping",
        lambda d: _write(d / "bom.yaml", "parts: [{id: lid, file: lid.stl, type: {a: 1}}]\n") and d,
        ValueError,
        r"row\[0\] \(part 'lid'\): type: expected a text, got a mapping",
    ),
    (
        "unreadable file",
        lambda d: _write(d / "junk.stl", "not a mesh at all"),
        ValueError,
        "junk.stl",
    ),
    ("empty file", lambda d: _write(d / "void.stl", ""), ValueError, "void.stl"),
    (
        "unknown unit",
        lambda d: _write(d / "a.yaml", "units: furlong\nparts: []\n"),
        ValueError,
        "furlong",
    ),
    (
        "yaml without parts",
        lambda d: _write(
            d / "b.yaml", "name: x\nagents: {H: human}\noperations: [{id: 1, agents: {H: 1}}]\n"
        ),
        ValueError,
        "parts",
    ),
]


def _write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    ("make", "error", "message"), [b[1:] for b in BAD], ids=[b[0] for b in BAD]
)
def test_bad_input(tmp_path, make, error, message):
    folder = write_folder(tmp_path / "asm", shapes.boxed_container())
    with pytest.raises(error, match=message):
        load_geometry(make(folder))


def test_empty_mesh_in_code_names_part():
    with pytest.raises(ValueError, match="'ghost'.*empty mesh"):
        Assembly.from_meshes({"ghost": trimesh.Trimesh()})


def test_interpenetration_names_pair(tmp_path):
    folder = write_folder(tmp_path / "asm", shapes.stacked_cubes(1.0))
    with pytest.raises(ValueError, match=r"'bottom' and 'top' interpenetrate by about 1 mm"):
        compute_relations(load_assembly(folder))


def test_non_watertight_part_warns():
    open_box = shapes.box((10, 10, 10))
    open_box.update_faces(np.arange(len(open_box.faces)) > 1)
    with pytest.warns(UserWarning, match="'open' .*not watertight"):
        Assembly.from_meshes({"open": open_box, "other": shapes.box((5, 5, 5), (20, 0, 0))})


def test_step_scene_loads_in_millimetres_with_the_stacked_relations():
    pytest.importorskip("cascadio")
    assembly = load_assembly(Path(__file__).parent / "data" / "two_boxes.step")
    assert len(assembly.parts) == 2
    low, high = sorted(assembly.parts, key=lambda p: p.mesh.bounds[0][2])
    assert np.allclose(low.mesh.extents, 10.0, atol=1e-3)
    assert np.isclose(high.mesh.bounds[0][2], 10.0, atol=1e-3)
    rel = compute_relations(assembly)
    i, j = rel.parts.index(low.id), rel.parts.index(high.id)
    # DIRECTIONS = +x -x +y -y +z -z: the high cube lies on the +z side of the low one
    assert rel.tc[i, j].tolist() == [False, False, False, False, True, False]
    assert rel.tt[j, i].tolist() == [True, True, True, True, True, False]


def test_a_step_that_only_references_other_files_says_so(tmp_path):
    pytest.importorskip("cascadio")
    path = tmp_path / "foot.stp"
    path.write_text(
        "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\n"
        "FILE_NAME('foot.stp','2026-01-01T00:00:00',(''),(''),'','','');\n"
        "FILE_SCHEMA(('AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }'));\nENDSEC;\nDATA;\n"
        "#1=APPLICATION_CONTEXT('automotive design');\n"
        "#2=PRODUCT_CONTEXT('',#1,'mechanical');\n"
        "#3=PRODUCT('FOOT','FOOT','',(#2));\n"
        "#4=PRODUCT_DEFINITION_FORMATION('','',#3);\n"
        "#5=PRODUCT_DEFINITION_CONTEXT('part definition',#1,'design');\n"
        "#6=PRODUCT_DEFINITION('design','',#4,#5);\n"
        "#7=DOCUMENT_TYPE('');\n"
        "#8=DOCUMENT_FILE('FOOT_FRONT.stp','','',#7,'',$);\n"
        "#9=DOCUMENT_FILE('FOOT_BACK.stp','','',#7,'',$);\n"
        "ENDSEC;\nEND-ISO-10303-21;\n"
    )
    with pytest.raises(ValueError, match=r"references external files \(FOOT_FRONT.stp, FOOT_BACK"):
        load_assembly(path)


def test_a_node_name_longer_than_a_file_name_is_read_from_its_scene(tmp_path):
    # `file#node` is first tried as one file name: past 255 bytes the system refuses the
    # name (ENAMETOOLONG) and the record is the node of its scene, as any other
    long_id = "bottom_" + "x" * 300
    scene = trimesh.Scene()
    for part in shapes.stacked_cubes().parts:
        scene.add_geometry(part.mesh, node_name=long_id if part.id == "bottom" else part.id)
    scene.export(tmp_path / "asm.glb")
    spec = tmp_path / "assembly.yaml"
    spec.write_text(
        "agents: {H: human}\n"
        "operations: [{id: '1.1', agents: {H: 1}}]\n"
        "parts:\n"
        f"  - {{id: B, file: 'asm.glb#{long_id}'}}\n"
        "  - {id: T, file: 'asm.glb#top'}\n"
    )
    assembly = load_geometry(spec)
    assert assembly.ids == ("B", "T")


def test_a_name_longer_than_a_file_name_is_never_asked_of_the_system(tmp_path, monkeypatch):
    """``could_be_file_name`` says no to a component past the longest file name (or a path
    past the longest path) and the record's ``file#node`` is never stat'ed then."""
    from cad.bom import PartRecord
    from cad.loading import could_be_file_name, load_parts

    assert could_be_file_name(tmp_path / ("a" * 255))
    assert not could_be_file_name(tmp_path / ("a" * 256))
    assert not could_be_file_name(tmp_path / "/".join(["b" * 200] * 30))  # 6,000 bytes
    long_id = "bottom_" + "x" * 300
    scene = trimesh.Scene()
    for part in shapes.stacked_cubes().parts:
        scene.add_geometry(part.mesh, node_name=long_id if part.id == "bottom" else part.id)
    scene.export(tmp_path / "asm.glb")
    asked = []
    is_file = Path.is_file
    monkeypatch.setattr(Path, "is_file", lambda self: asked.append(str(self)) or is_file(self))
    records = [PartRecord(id="B", name="B", file=f"asm.glb#{long_id}")]
    assert load_parts(records, tmp_path).ids == ("B",)
    assert not [name for name in asked if long_id in name]
