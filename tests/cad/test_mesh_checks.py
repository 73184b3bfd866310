"""Meshes no part can be made of, refused where a file is read, in every format: a NaN or
infinite vertex coordinate, a part whose triangles all have zero area."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from cad import load_assembly
from cad.errors import GeometryError
from cad.readers import load_file, reader_for
from cad.scene import read_scene
from tests.cad import shapes

TETRA = [
    ((0, 0, 0), (1, 0, 0), (0, 1, 0)),
    ((0, 0, 0), (0, 1, 0), (0, 0, 1)),
    ((0, 0, 0), (0, 0, 1), (1, 0, 0)),
    ((1, 0, 0), (0, 0, 1), (0, 1, 0)),
]


def stl_text(triangles) -> str:
    """An ASCII STL of ``triangles`` written as given (``nan``, ``inf`` included)."""
    lines = ["solid p"]
    for triangle in triangles:
        lines += ["facet normal 0 0 0", "outer loop"]
        lines += [f"vertex {x} {y} {z}" for x, y, z in triangle]
        lines += ["endloop", "endfacet"]
    return "\n".join([*lines, "endsolid p", ""])


NAN_STL = stl_text([((0, 0, 0), (1, 0, 0), (float("nan"), 1, 0)), *TETRA])
INF_STL = stl_text([*TETRA[:3], ((1e400, 0, 0), (0, 0, 1), (0, 1, 0))])
FLAT_STL = stl_text([((0, 0, 0), (0, 0, 0), (0, 0, 0))] * 4)


def _nan_box() -> trimesh.Trimesh:
    box = trimesh.creation.box((5, 5, 5))
    vertices = box.vertices.copy()
    vertices[2, 0] = np.nan
    return trimesh.Trimesh(vertices, box.faces, process=False)


def _scene(**meshes: trimesh.Trimesh) -> trimesh.Scene:
    scene = trimesh.Scene()
    for name, mesh in meshes.items():
        scene.add_geometry(mesh, node_name=name, geom_name=name)
    return scene


def _base() -> trimesh.Trimesh:
    return trimesh.creation.box((10, 10, 10)).apply_translation((0, 0, -10))


def _flat() -> trimesh.Trimesh:
    return trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [2, 0, 0]], [[0, 1, 2]], process=False)


def _write(path: Path, data) -> Path:
    path.write_bytes(data if isinstance(data, bytes) else data.encode())
    return path


def _export(what, file_type=None):
    """A writer of ``what()`` (a mesh or scene) as trimesh exports it."""
    return lambda path: _write(path, what().export(file_type=file_type or path.suffix[1:]))


def _lid_scene() -> trimesh.Scene:
    return _scene(base=_base(), lid=_nan_box())


NON_FINITE = "vertex 3 has a non-finite coordinate"
# name: (file name, its writer, what the one-line message says after the file's path)
BAD = {
    "stl nan": ("part.stl", lambda p: _write(p, NAN_STL), f": {NON_FINITE} (nan, 1, 0)"),
    "stl inf": ("part.stl", lambda p: _write(p, INF_STL), ": vertex 10 has a non-finite"),
    "ply nan": ("part.ply", _export(_nan_box), f": {NON_FINITE}"),
    "off nan": ("part.off", _export(_nan_box), f": {NON_FINITE}"),
    "obj nan": ("asm.obj", _export(_lid_scene), f": mesh 'lid': {NON_FINITE}"),
    "glb nan": ("asm.glb", _export(_lid_scene), f": mesh 'lid': {NON_FINITE}"),
    "3mf nan": ("asm.3mf", _export(_lid_scene), f": mesh 'lid': {NON_FINITE}"),
    "stl zero area": (
        "part.stl",
        lambda p: _write(p, FLAT_STL),
        ": no solid geometry: all 4 triangles have zero area",
    ),
    "glb part of zero area": (
        "asm.glb",
        _export(lambda: _scene(base=_base(), flat=_flat())),
        ": part 'flat': no solid geometry: its one triangle has zero area",
    ),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_a_mesh_no_part_is_made_of_is_refused_at_reading(tmp_path, case):
    name, write, said = BAD[case]
    path = tmp_path / name
    write(path)
    with pytest.raises(GeometryError) as info:
        read_scene(path)
    message = str(info.value)
    assert message.startswith(f"{path}{said}") and "\n" not in message


@pytest.mark.parametrize(("content", "said"), [(NAN_STL, "non-finite"), (FLAT_STL, "zero area")])
def test_a_bad_file_of_a_folder_is_named(tmp_path, content, said):
    folder = tmp_path / "meshes"
    folder.mkdir()
    shapes.boxed_container().parts[0].mesh.export(folder / "good.stl")
    _write(folder / "bad.stl", content)
    with pytest.raises(GeometryError, match=rf"^{folder / 'bad.stl'}: .*{said}"):
        load_assembly(folder)


@pytest.mark.parametrize("suffix", [".stl", ".obj", ".ply", ".off", ".glb", ".3mf"])
def test_the_checked_read_gives_trimeshs_own_meshes(tmp_path, suffix):
    """Read unprocessed, checked, then processed where trimesh processes: the same
    vertices, faces and nodes as ``trimesh.load`` (what a checker of a plan reads)."""
    container = shapes.boxed_container()
    path = tmp_path / f"asm{suffix}"
    if reader_for(path).scene or suffix == ".obj":
        _scene(**{p.id: p.mesh for p in container.parts}).export(path)
    else:
        container.parts[0].mesh.export(path)
    reader = reader_for(path)
    ours, theirs = load_file(path, reader), trimesh.load(path, force="scene", **reader.options)
    assert list(ours.geometry) == list(theirs.geometry)
    for key, mesh in ours.geometry.items():
        assert np.array_equal(mesh.vertices, theirs.geometry[key].vertices)
        assert np.array_equal(mesh.faces, theirs.geometry[key].faces)
    assert sorted(ours.graph.nodes_geometry) == sorted(theirs.graph.nodes_geometry)
