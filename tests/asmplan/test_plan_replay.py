"""Plans replayed by the independent mesh checker (:mod:`tests.asmplan.mesh_replay`)."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
import trimesh

from asmplan import pipeline
from asmplan.planfile import validate_plan
from tests.asmplan.mesh_replay import Rejected, Replay, Solid, replayed
from tests.asmplan.test_generated_held import plate_with_dowel
from tests.cad.real_shapes import box, finger_box, unmerged
from tests.cad.test_subassemblies import TOWER_TREE, rod_tower, write_glb


@pytest.fixture(scope="module")
def tower_plan(tmp_path_factory):
    folder = tmp_path_factory.mktemp("tower")
    write_glb(folder / "tower.glb", rod_tower(), TOWER_TREE)
    return pipeline.plan(folder / "tower.glb", time_limit=5).to_dict()


def test_the_pump_replays():
    plan = pipeline.plan("examples/vacuum_pump", time_limit=5).to_dict()
    replayed(plan)


def test_the_pump_concurrent_plan_replays():
    plan = pipeline.plan(
        "examples/vacuum_pump", time_limit=5, turn_model="concurrent", max_k=0
    ).to_dict()
    assert plan["turn_model"] == "concurrent"
    replayed(plan)


def test_the_rod_tower_with_units_replays(tower_plan):
    assert tower_plan["geometry"]["file_unit"] == "m" and tower_plan["geometry"]["scale"] == 1000
    assert [w["id"] for w in tower_plan["workspaces"]][0] == "main"
    assert {s["workspace"] for s in tower_plan["robust_plan"]} == {"main", "level_1", "level_2"}
    replayed(tower_plan)


def test_held_parts_replay(tmp_path):
    plan = pipeline.plan(plate_with_dowel(tmp_path / "meshes"), time_limit=5).to_dict()
    held = [i for s in plan["robust_plan"] for i in s["insertions"] if i["held"]]
    assert [i["parts"] for i in held] == [["dowel"]] and plan["operations"][held[0]["operation"]][
        "held"
    ]
    replayed(plan)
    # unheld, the dowel loose in the through hole falls: fitted all round is not support
    unheld = tampered(plan, _nothing_held)
    with pytest.raises(Rejected, match=r"\['dowel'\] is not supported"):
        Replay(unheld).line("robust_plan")


def _nothing_held(plan):
    for step in plan["robust_plan"]:
        for ins in step["insertions"]:
            ins["held"] = False


def tampered(plan: dict, change) -> dict:
    plan = copy.deepcopy(plan)
    change(plan)
    return plan


def _flip_unit_direction(plan):
    for step in plan["robust_plan"]:
        for ins in step["insertions"]:
            if ins["unit"]:
                ins["insert_along"], ins["free_along"] = ins["free_along"], ins["insert_along"]


def _unit_into_its_workspace(plan):
    """A checker that ignored workspaces: every member placed straight into main."""
    for step in plan["robust_plan"]:
        for ins in step["insertions"]:
            ins["workspace"] = "main"


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (_flip_unit_direction, "is not free along"),
        (_unit_into_its_workspace, "no insertion direction|touches none of|not free|not supported"),
    ],
)
def test_the_checker_rejects_a_wrong_line(tower_plan, change, message):
    with pytest.raises(Rejected, match=message):
        Replay(tampered(tower_plan, change)).line("robust_plan")


def _without_merging(plan):
    """Unmerged, every face is a mesh of its own: every part is open."""
    plan["geometry"]["merge_vertices"] = False
    plan["geometry"]["open_parts"] = [p["id"] for p in plan["parts"]]
    plan["geometry"]["free_edge_pull"] = 0.0  # and the free edges left in place too


@pytest.mark.parametrize(
    ("parts", "tree", "slide"),
    [
        # a rod standing on the base leaves sideways, sliding on the face they share
        (rod_tower, TOWER_TREE, "rod_"),
        # a wall's tab leaves the bottom's edge notch, its flanks interfering by the kerf
        (finger_box, {"Product": ["bottom", "front", "back", "left", "right", "lid"]}, ""),
    ],
    ids=["rod_tower", "finger_box"],
)
def test_a_face_by_face_export_replays(tmp_path, parts, tree, slide):
    """Exports that tessellate face by face (no vertex shared between faces, like the rod
    tower's 3DXML and the finger-jointed box's STEP) replay once their vertices are merged,
    as ``geometry.merge_vertices`` says; unmerged, the erosion leaves every edge in place
    and a slide along a shared face or through a kerf-wide interference collides."""
    write_glb(tmp_path / "model.glb", {k: unmerged(m) for k, m in parts().items()}, tree)
    plan = pipeline.plan(tmp_path / "model.glb", time_limit=5).to_dict()
    assert plan["geometry"]["merge_vertices"] and plan["geometry"]["open_parts"] == []
    replayed(plan)
    sideways = [
        i
        for s in plan["robust_plan"]
        for i in s["insertions"]
        if i["free_along"] and i["free_along"][1] != "z" and i["parts"][0].startswith(slide)
    ]
    assert sideways, "no body leaves sideways: the geometry does not test the slide"
    with pytest.raises(Rejected, match="is not free along"):
        Replay(tampered(plan, _without_merging)).line("robust_plan")


def test_millimetre_numbers_under_a_metre_label_replay(tmp_path):
    """A glTF (metres by default) holding millimetre numbers is read in mm by the planner
    (cad/scene.py); ``geometry.scale`` and each ``parts[].source.scale`` say so, so the
    replay reads the same millimetres (with the unit label's 1000 the parts would be a
    thousand times too large for their tolerances)."""
    scene = trimesh.Scene()
    scene.add_geometry(box((0, 0, 0), (400, 300, 20)), node_name="block")
    scene.add_geometry(box((0, 0, 20), (40, 40, 60)), node_name="cap")
    scene.export(tmp_path / "engine.glb")
    with pytest.warns(UserWarning, match="declares metres"):
        plan = pipeline.plan(tmp_path / "engine.glb", time_limit=5).to_dict()
    assert plan["geometry"]["scale"] == pytest.approx(1.0)
    assert all(p["source"]["scale"] == pytest.approx(1.0) for p in plan["parts"])
    replayed(plan)


def test_an_inside_out_part_replays(tmp_path):
    """A closed mesh drawn inside out (normals inwards) is turned outwards by the planner
    (:func:`cad.assembly.prepare_part`) and by the replay; eroded as drawn the block would
    grow by more than the cap shrinks, and the cap sliding on its top face would collide."""
    parts = {"block": box((0, 0, 0), (60, 40, 10)), "cap": box((0, 0, 10), (20, 20, 30))}
    parts["block"].invert()
    write_glb(tmp_path / "model.glb", parts, {"Product": ["block", "cap"]})
    plan = pipeline.plan(tmp_path / "model.glb", time_limit=5).to_dict()
    (ins,) = [i for s in plan["robust_plan"] for i in s["insertions"] if i["parts"] == ["cap"]]
    assert ins["free_along"][1] != plan["gravity"][1]  # it leaves sliding on the block
    replayed(plan)


def test_a_part_inside_a_closed_part_collides_not_inside_an_open_one():
    """A closed solid has an inside (the planner's interpenetration test,
    ``cad.freedom._intersect``): a cube wholly in a block collides with it though no
    surfaces cross; a block with a face missing (``geometry.open_parts``) has no inside."""
    cube = Solid(box((4, 4, 4), (6, 6, 6)), closed=True)
    block = box((0, 0, 0), (10, 10, 10))
    assert cube.hits(Solid(block, closed=True), np.zeros(3))
    assert not cube.hits(Solid(block, closed=True), np.array([0.0, 0.0, 20.0]))
    opened = block.copy()
    opened.update_faces(np.arange(len(opened.faces)) > 1)
    assert not opened.is_watertight
    assert not cube.hits(Solid(opened, closed=False), np.zeros(3))


def test_the_open_parts_must_be_the_open_meshes(tmp_path):
    plan = pipeline.plan(plate_with_dowel(tmp_path / "meshes"), time_limit=5).to_dict()
    assert plan["geometry"]["open_parts"] == []
    Replay(plan)
    with pytest.raises(Rejected, match="open_parts says"):
        Replay(tampered(plan, lambda p: p["geometry"].update(open_parts=["plate"])))


def test_support_follows_the_rules_the_plan_names(tower_plan):
    """The tower's flanged bearings are held up by what passes through them (``threaded``,
    :mod:`cad.support`); a plan whose ``geometry.support`` named the drop test alone would
    leave them unsupported."""
    assert tower_plan["geometry"]["support"] == ["rests", "captured", "threaded"]
    assert "threaded" in Replay(tower_plan).line("robust_plan")
    rests_only = tampered(tower_plan, lambda p: p["geometry"].update(support=["rests"]))
    with pytest.raises(Rejected, match="is not supported"):
        Replay(rests_only).line("robust_plan")


def test_a_step_plan_replays_from_the_meshes_the_planner_read(step_deflections):
    """A STEP is tessellated to within ``geometry.step_chord`` mm (:data:`cad.scene.STEP_CHORD_MM`,
    OCCT's linear deflection): the replay reads the file with it, so its meshes are the
    planner's, triangle for triangle."""
    from cad.scene import STEP_CHORD_MM, load_scene_file
    from tests.asmplan.mesh_replay import load_meshes

    step = Path(__file__).resolve().parents[1] / "cad" / "data" / "table_frame_in.step"
    plan = pipeline.plan(step, time_limit=5).to_dict()
    assert plan["geometry"]["step_chord"] == STEP_CHORD_MM
    step_deflections.clear()
    meshes = load_meshes(plan)
    assert step_deflections == [STEP_CHORD_MM]
    scene = load_scene_file(step)  # as the planner reads it
    read = {
        p["id"]: len(scene.geometry[scene.graph[p["source"]["node"]][1]].faces)
        for p in plan["parts"]
    }
    assert read == {k: len(m.faces) for k, m in meshes.items()}
    replayed(plan)


def test_a_textured_glb_counts_open_parts_as_the_planner_does(tmp_path):
    """A glTF mesh has a vertex per corner and texture coordinate: a box's faces meet at
    seams of vertices at one position with different UVs (the Cesium milk truck's
    wheels). Merged by position, as the planner merges them, each box is closed; the
    replay, merging the same way, agrees (it had called them open: trimesh keeps
    vertices of different UVs apart)."""
    from PIL import Image

    from tests.asmplan.mesh_replay import load_meshes

    scene = trimesh.Scene()
    texture = Image.new("RGB", (4, 4), (200, 80, 40))
    for k, (lo, hi) in enumerate((((0, 0, 0), (40, 40, 10)), ((5, 5, 10), (35, 35, 30)))):
        mesh = unmerged(box(lo, hi))
        uv = np.random.default_rng(k).random((len(mesh.vertices), 2))
        mesh.visual = trimesh.visual.TextureVisuals(uv=uv, image=texture)
        scene.add_geometry(mesh.apply_scale(0.001), node_name=f"block_{k}")
    scene.export(str(tmp_path / "blocks.glb"))
    plan = pipeline.plan(tmp_path / "blocks.glb", time_limit=5).to_dict()
    assert plan["geometry"]["open_parts"] == []
    assert all(m.is_watertight for m in load_meshes(plan).values())
    replayed(plan)


def test_a_part_joined_across_the_models_gap_replays_by_the_rule_the_plan_states(tmp_path):
    """A lid floating 1 mm over a box (a visual model's gap) touches it by the nearest-part
    rule (``cad.relations.with_nearest``): the plan file states the pair, the replay from
    the meshes takes it as touching and the lid as resting on the box; without the stated
    pair the replay refuses the lid."""
    folder = tmp_path / "meshes"
    folder.mkdir()
    meshes = {
        "foot": box((10, 10, -5), (30, 30, 0)),
        "box": box((0, 0, 0), (40, 40, 20)),
        "lid": box((0, 0, 21), (40, 40, 25)),
    }
    for name, mesh in meshes.items():
        mesh.export(folder / f"{name}.stl")
    plan = pipeline.plan(folder, time_limit=5).to_dict()
    assert plan["geometry"]["nearest"] == [{"part": "box", "near": "lid", "side": "+z", "gap": 1.0}]
    validate_plan(plan)
    replayed(plan)
    del plan["geometry"]["nearest"]
    with pytest.raises(Rejected, match="touches none"):
        replayed(plan)
