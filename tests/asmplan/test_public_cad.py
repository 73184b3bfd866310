"""Public CAD files of issue 24, when present under ``$ASMPLAN_REAL_CAD`` (default
``/tmp/realcad``; each test skips without its file; never copied into the repository):
the APLAN toy truck's one STEP solid is split into its bodies, a Z-up 3DXML written as GLB
by trimesh gets its true gravity, and a single-shell Inventor part stays one part."""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import pytest
import trimesh

from cad.scene import read_scene


def public(name: str) -> Path:
    """The first file called ``name`` under the public CAD folders, else skip."""
    for folder in os.environ.get("ASMPLAN_REAL_CAD", "/tmp/realcad").split(":"):
        found = sorted(Path(folder).rglob(name)) if Path(folder).is_dir() else []
        if found:
            return found[0]
    pytest.skip(f"{name} not found under $ASMPLAN_REAL_CAD")


def test_the_toy_truck_is_its_bodies():
    """One solid of 121 shells (61 objects): bodies resting face to face are split at
    their contact; the screws, tyres and drum are closed bodies of their own."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = read_scene(public("toy_truck.stp"))
    assert len(scene.ids) >= 45
    assert sum(m.is_watertight for m in scene.meshes) >= 43
    assert all(pid.startswith("cement_mixer_truck_body_") for pid in scene.ids)


def test_the_toy_truck_is_its_61_declared_shells():
    """The APLAN toy truck (one BREP_WITH_VOIDS of 61 shells, 542 faces): every shell a
    closed body, when the file is at hand."""
    from cad.step import solid_shells

    path = public("toy_truck.stp")
    shells = solid_shells(path)
    assert len(shells) == 61 and sum(shells) == 542
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = read_scene(path)
    assert len(scene.ids) == 61 and all(m.is_watertight for m in scene.meshes)


def test_a_single_shell_part_stays_one_part():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert len(read_scene(public("11752.stp")).ids) == 1


def test_a_z_up_3dxml_written_as_glb_gets_minus_z(tmp_path):
    """trimesh's GLB of ``rod.3DXML`` keeps the Z-up numbers: the tower is planned
    standing (gravity -z), as from the 3DXML, not on its side along glTF's -y."""
    from asmplan import pipeline

    source = tmp_path / "rod.glb"
    trimesh.load(public("rod.3DXML"), force="scene").export(source)
    notes: list[str] = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        spec = pipeline.load(source, on_step=notes.append).spec
    assert spec.gravity == "-z"
    assert any("gravity -z: not the default -y" in n for n in notes)
