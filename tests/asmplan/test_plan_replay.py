"""An independent checker: replay a plan's lines from ``plan.json`` and the meshes alone.

It plays the part of a checker that knows nothing of ``asp``: it reads only the plan file
(README, "The plan file": ``workspaces``, each step's ``insertions``, ``gravity``,
``geometry``, ``parts[].source``), loads the meshes it names with trimesh, and tests each
insertion with python-fcl (through trimesh's collision manager):

- **free**: the body, moved step by step along ``free_along`` (``-insert_along``) from its
  assembled pose to beyond everything, never collides with the parts already in its
  workspace, every part eroded by its ``part_shrink`` (so an overlap within the pair's
  tolerance is touching, not collision); the step is a quarter of the thinnest part, so
  nothing thin is jumped over;
- **touching**: the gap to those parts is at most ``contact_tol`` (or they overlap);
- **supported** (unless ``held``): moved along ``gravity`` by three times the pair's
  tolerance, the eroded body collides with them (it rests on something), or it is fitted:
  the same move in each of the four directions across gravity collides (a bearing pressed
  in a holder, a nut on its bolt). The fit rule is more lenient than the planner's.

The first body of a workspace stands on the fixture and is not tested; after a unit's
insertion its members are in ``main``.
"""

from __future__ import annotations

import copy
import json
from pathlib import Path

import numpy as np
import pytest
import trimesh

from asmplan import pipeline
from tests.asmplan.test_generated_held import plate_with_dowel
from tests.cad.test_subassemblies import TOWER_TREE, rod_tower, write_glb

AXES = {"x": 0, "y": 1, "z": 2}
SUPPORT_FACTOR = 3.0


class Rejected(AssertionError):
    """The replay found a step the geometry does not allow."""


def vector(direction: str) -> np.ndarray:
    v = np.zeros(3)
    v[AXES[direction[1]]] = 1.0 if direction[0] == "+" else -1.0
    return v


def load_meshes(plan: dict) -> dict[str, trimesh.Trimesh]:
    """Part id -> mesh in mm, from ``parts[].source`` and ``geometry.scale`` only."""
    scale = plan["geometry"]["scale"]
    source = Path(plan["source"])
    folder = source if source.is_dir() else source.parent
    out = {}
    for part in plan["parts"]:
        src = part["source"]
        path = Path(src["path"]) if src["path"] else folder / src["file"]
        if src["node"] is None:
            mesh = trimesh.load(path, force="mesh")
        else:
            scene = trimesh.load(path, force="scene")
            transform, geometry = scene.graph[src["node"]]
            mesh = scene.geometry[geometry].copy().apply_transform(transform)
        out[part["id"]] = mesh.apply_scale(scale)
    return out


def eroded(mesh: trimesh.Trimesh, shrink: float) -> trimesh.Trimesh:
    """Each vertex moved inwards along its normal so that every face plane it touches moves
    by at least ``shrink`` (at most twice that at sharp corners)."""
    normals = mesh.vertex_normals
    cos = np.ones(len(mesh.vertices))
    for k in range(mesh.vertex_faces.shape[1]):
        f = mesh.vertex_faces[:, k]
        has = f >= 0
        dots = np.einsum("ij,ij->i", normals[has], mesh.face_normals[f[has]])
        cos[has] = np.minimum(cos[has], dots)
    move = shrink / np.clip(cos, 0.5, 1.0)
    return trimesh.Trimesh(mesh.vertices - normals * move[:, None], mesh.faces, process=False)


class Replay:
    """The geometry of one plan, and the tests of one insertion."""

    def __init__(self, plan: dict):
        geo = plan["geometry"]
        self.plan = plan
        self.meshes = load_meshes(plan)
        self.shrink = geo["part_shrink"]
        self.contact_tol = geo["contact_tol"]
        self.gravity = vector(plan["gravity"])
        # a unit built in another orientation (upside down) has its own gravity
        self.down = {w["id"]: vector(w.get("gravity", plan["gravity"])) for w in plan["workspaces"]}
        self.solid = {p: eroded(m, self.shrink[p]) for p, m in self.meshes.items()}
        thinnest = min(float(np.min(m.extents)) for m in self.meshes.values())
        self.step = float(np.clip(thinnest / 4, 0.05, 1.0))
        everything = np.vstack([m.bounds for m in self.meshes.values()])
        self.reach = float(np.linalg.norm(everything.max(0) - everything.min(0))) + 1.0

    def manager(self, parts, solid=True) -> trimesh.collision.CollisionManager:
        manager = trimesh.collision.CollisionManager()
        for p in parts:
            manager.add_object(p, (self.solid if solid else self.meshes)[p])
        return manager

    def hits(self, manager, body, offsets) -> bool:
        """Whether the eroded body, moved by any of ``offsets``, collides with ``manager``."""
        meshes = [self.solid[p] for p in body]
        for offset in offsets:
            transform = trimesh.transformations.translation_matrix(offset)
            if any(manager.in_collision_single(m, transform=transform) for m in meshes):
                return True
        return False

    def check(self, ins: dict, there: list[str], where: str) -> None:
        body = ins["parts"]
        if not there:
            return
        solid = self.manager(there)
        if ins["insert_along"] is None:
            raise Rejected(f"{where}: no insertion direction into {there}")
        d = -vector(ins["insert_along"])
        assert ins["free_along"] is not None and np.allclose(vector(ins["free_along"]), d)
        path = np.arange(self.step, self.reach, self.step)[:, None] * d
        if self.hits(solid, body, path):
            raise Rejected(f"{where}: {body} is not free along {ins['free_along']}")
        plain = self.manager(there, solid=False)
        gap = min(plain.min_distance_single(self.meshes[p]) for p in body)
        touching = gap <= self.contact_tol * 1.01 + 1e-6
        touching |= any(plain.in_collision_single(self.meshes[p]) for p in body)
        if not touching:
            raise Rejected(f"{where}: {body} touches none of {there} (gap {gap:.3f} mm)")
        if ins["held"]:
            return
        tol = max(self.shrink[p] for p in body) + max(self.shrink[p] for p in there)
        travel = SUPPORT_FACTOR * tol
        fall = np.linspace(travel / 8, travel, 8)[:, None]
        down = self.down.get(ins["workspace"], self.gravity)
        if self.hits(solid, body, fall * down):
            return
        across = [vector(s + a) for a in "xyz" for s in "+-"]
        across = [v for v in across if abs(v @ down) < 0.5]
        if all(self.hits(solid, body, fall * v) for v in across):
            return  # fitted: a bearing pressed in its holder, a nut on its bolt
        raise Rejected(f"{where}: {body} is not supported (it would fall along gravity)")

    def line(self, key: str) -> int:
        """Replay ``plan[key]``; return the number of insertions tested."""
        placed = {w["id"]: list(w["initial"]) for w in self.plan["workspaces"]}
        members = self.plan["subassemblies"]
        tested = 0
        for step in self.plan[key]:
            for ins in step["insertions"]:
                where = f"{key} step {step['step']} (operation {ins['operation']})"
                there = placed.setdefault(ins["workspace"], [])
                if ins["unit"]:
                    done = sorted(placed.get(ins["unit"], []))
                    if done != sorted(members[ins["unit"]]) or sorted(ins["parts"]) != done:
                        raise Rejected(f"{where}: unit {ins['unit']} is not complete")
                self.check(ins, there, where)
                tested += bool(there)
                there.extend(ins["parts"])
        missing = set(self.meshes) - set(placed["main"])
        if missing:
            raise Rejected(f"{key}: the line ends with {sorted(missing)} not in place")
        return tested


def replayed(plan: dict) -> Replay:
    """Round-trip through JSON (the checker sees only what the file holds), then replay."""
    plan = json.loads(json.dumps(plan))
    replay = Replay(plan)
    for key in ("robust_plan", "worst_line"):
        assert replay.line(key) > 0
    return replay


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
