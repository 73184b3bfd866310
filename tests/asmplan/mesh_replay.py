"""An independent checker: replay a plan's lines from ``plan.json`` and the meshes alone.

It plays the part of a checker that knows nothing of ``asp`` or ``cad``: it reads only the
plan file (README, "The plan file": ``workspaces``, each step's ``insertions``,
``gravity``, ``geometry``, ``parts[].source``), loads the meshes it names with trimesh and
tests each insertion with python-fcl. The rules (``geometry``):

- **meshes**: each part's mesh from ``parts[].source``, times its ``scale`` (else
  ``geometry.scale``: mm per coordinate as trimesh reads the file), turned into the build
  frame by ``geometry.build_rotation`` (``x_build = R @ x_file``; directions are its axes), its
  coincident vertices merged when ``merge_vertices`` (a STEP or 3DXML tessellation gives
  every face its own vertices; an unmerged mesh cannot be eroded: every vertex would move
  along its own face only, leaving the edges in place), a closed mesh with its normals
  inwards turned outwards;
- **erosion**: every part shrunk by its ``part_shrink``: each vertex moved inwards along
  its normal, never moving any face plane by more than the shrink (conservative: the
  replay tolerates at most what the plan says); the inner part of a pair in ``fits`` is
  shrunk by ``extra_shrink`` more against that pair's outer part only;
- **free**: the body, moved along ``free_along`` (``-insert_along``) from its assembled pose
  to beyond everything in steps of a quarter of the thinnest part (so nothing thin is
  jumped over), never collides with the parts already in its workspace, both eroded;
- **touching**: the gap to those parts is at most the pair's contact tolerance
  (``min(contact_reach[i], contact_reach[j])``, else ``contact_tol``), or they overlap, or
  the body comes to rest on one of them (the fall of the support test below meets it: a
  clip hanging on a barrel across its clearance touches it once settled);
- **supported** (unless ``held``): moved along ``gravity`` (the workspace's own, for a
  unit built in another orientation) by ``support_travel_factor``
  times the pair's tolerance, the eroded body collides with them (it rests on something),
  or it is fitted: the same move in each of the four directions across gravity collides (a
  bearing pressed in a holder, a nut on its bolt). The fit rule is more lenient than the
  planner's.

The first body of a workspace stands on the fixture and is not tested; after a unit's
insertion its members are in ``main``. A rejection names the step, the pair, the
direction and the distance.
"""

from __future__ import annotations

import json
from pathlib import Path

import fcl
import numpy as np
import trimesh

AXES = {"x": 0, "y": 1, "z": 2}
SUPPORT_FACTOR = 3.0
"""Support travel in pair tolerances when the plan does not say."""


class Rejected(AssertionError):
    """The replay found a step the geometry does not allow."""


def vector(direction: str) -> np.ndarray:
    """Unit vector of ``"+x"`` ... ``"-z"``, shape ``(3,)``."""
    v = np.zeros(3)
    v[AXES[direction[1]]] = 1.0 if direction[0] == "+" else -1.0
    return v


def load_meshes(plan: dict) -> dict[str, trimesh.Trimesh]:
    """Part id -> mesh in mm, from ``parts[].source`` and ``geometry`` only."""
    geo = plan["geometry"]
    source = Path(plan["source"])
    folder = source if source.is_dir() else source.parent
    scenes: dict[Path, trimesh.Scene] = {}
    out = {}
    for part in plan["parts"]:
        src = part["source"]
        path = Path(src["path"]) if src["path"] else folder / src["file"]
        if src["node"] is None:
            mesh = trimesh.load(path, force="mesh")
        else:
            if path not in scenes:
                scenes[path] = trimesh.load(path, force="scene")
            transform, geometry = scenes[path].graph[src["node"]]
            mesh = scenes[path].geometry[geometry].copy().apply_transform(transform)
        mesh = mesh.apply_scale(src.get("scale") or geo["scale"])
        if geo.get("build_rotation") is not None:  # into the build frame: x' = R x
            turn = np.eye(4)
            turn[:3, :3] = np.asarray(geo["build_rotation"], float)
            mesh = mesh.apply_transform(turn)
        if geo.get("merge_vertices", False):
            mesh.merge_vertices()
        if mesh.is_watertight and mesh.volume < 0:
            mesh.invert()  # a closed mesh drawn inside out: erode it inwards all the same
        out[part["id"]] = mesh
    return out


def eroded(mesh: trimesh.Trimesh, shrink: float) -> trimesh.Trimesh:
    """Each vertex moved inwards along its normal so that no face plane it touches moves by
    more than ``shrink`` (exactly ``shrink`` for the plane closest to the normal)."""
    if shrink <= 0:
        return mesh
    normals = mesh.vertex_normals
    cos = np.zeros(len(mesh.vertices))
    for k in range(mesh.vertex_faces.shape[1]):
        f = mesh.vertex_faces[:, k]
        has = f >= 0
        dots = np.einsum("ij,ij->i", normals[has], mesh.face_normals[f[has]])
        cos[has] = np.maximum(cos[has], dots)
    move = shrink / np.clip(cos, 0.5, 1.0)
    return trimesh.Trimesh(mesh.vertices - normals * move[:, None], mesh.faces, process=False)


def collision_object(mesh: trimesh.Trimesh) -> fcl.CollisionObject:
    model = fcl.BVHModel()
    model.beginModel(len(mesh.vertices), len(mesh.faces))
    model.addSubModel(np.asarray(mesh.vertices, float), np.asarray(mesh.faces, np.int32))
    model.endModel()
    return fcl.CollisionObject(model, fcl.Transform())


class Solid:
    """A mesh as an fcl object with its bounds; moved by a translation."""

    def __init__(self, mesh: trimesh.Trimesh):
        self.bounds = np.asarray(mesh.bounds, float)
        self.obj = collision_object(mesh)

    def hits(self, other: Solid, offset: np.ndarray) -> bool:
        """Whether this solid, moved by ``offset``, collides with ``other`` (in place)."""
        lo, hi = self.bounds + offset
        if np.any(lo > other.bounds[1]) or np.any(hi < other.bounds[0]):
            return False
        self.obj.setTranslation(np.asarray(offset, float))
        hit = fcl.collide(self.obj, other.obj, fcl.CollisionRequest(), fcl.CollisionResult())
        self.obj.setTranslation(np.zeros(3))
        return bool(hit)

    def gap(self, other: Solid) -> float:
        """Distance to ``other`` in place (0 when they collide)."""
        if self.hits(other, np.zeros(3)):
            return 0.0
        return float(fcl.distance(self.obj, other.obj, fcl.DistanceRequest(), fcl.DistanceResult()))


class Replay:
    """The geometry of one plan, and the tests of one insertion."""

    def __init__(self, plan: dict):
        geo = plan["geometry"]
        self.plan = plan
        self.meshes = load_meshes(plan)
        self.shrink = {p: float(s) for p, s in geo["part_shrink"].items()}
        self.contact_tol = float(geo["contact_tol"])
        self.reach = geo.get("contact_reach")
        self.factor = float(geo.get("support_travel_factor", SUPPORT_FACTOR))
        self.gravity = vector(plan["gravity"])
        # a unit built in another orientation (upside down) has its own gravity
        self.down = {w["id"]: vector(w.get("gravity", plan["gravity"])) for w in plan["workspaces"]}
        self.extra = {(f["inner"], f["outer"]): f["extra_shrink"] for f in geo.get("fits", [])}
        self.plain = {p: Solid(m) for p, m in self.meshes.items()}
        self.solid = {p: Solid(eroded(m, self.shrink[p])) for p, m in self.meshes.items()}
        self.fitted = {
            pair: Solid(eroded(self.meshes[pair[0]], self.shrink[pair[0]] + extra))
            for pair, extra in self.extra.items()
        }
        thinnest = min(float(np.min(m.extents)) for m in self.meshes.values())
        self.step = float(np.clip(thinnest / 4, 0.05, 1.0))
        everything = np.vstack([m.bounds for m in self.meshes.values()])
        self.span = float(np.linalg.norm(everything.max(0) - everything.min(0))) + 1.0

    # ------------------------------------------------------------------ pairs
    def tolerance(self, p: str, j: str) -> float:
        """Penetration tolerance of the pair (mm)."""
        extra = self.extra.get((p, j), 0.0) + self.extra.get((j, p), 0.0)
        return self.shrink[p] + self.shrink[j] + extra

    def contact(self, p: str, j: str) -> float:
        """Largest gap (mm) that counts as touching for the pair."""
        if self.reach is None:
            return self.contact_tol
        return min(float(self.reach[p]), float(self.reach[j]))

    def pair(self, p: str, j: str) -> tuple[Solid, Solid]:
        """The eroded solids of moving part ``p`` and obstacle ``j`` (a fit's inner part
        shrunk further)."""
        return self.fitted.get((p, j), self.solid[p]), self.fitted.get((j, p), self.solid[j])

    def first_hit(self, p: str, j: str, d: np.ndarray, offsets: np.ndarray) -> float | None:
        """The first of ``offsets`` (distances along ``d``) at which p meets j, or None."""
        a, b = self.pair(p, j)
        for s in offsets:
            if a.hits(b, s * d):
                return float(s)
        return None

    def path(self, p: str, j: str, d: np.ndarray) -> np.ndarray:
        """Distances along ``d`` at which p's box overlaps j's box, a step apart (both ends
        kept), from one step to beyond everything."""
        a, b = self.pair(p, j)
        axis = int(np.argmax(np.abs(d)))
        sign = d[axis]
        others = [k for k in range(3) if k != axis]
        lo, hi = a.bounds
        if np.any(lo[others] > b.bounds[1, others]) or np.any(hi[others] < b.bounds[0, others]):
            return np.zeros(0)
        if sign > 0:
            start, stop = b.bounds[0, axis] - hi[axis], b.bounds[1, axis] - lo[axis]
        else:
            start, stop = lo[axis] - b.bounds[1, axis], hi[axis] - b.bounds[0, axis]
        start, stop = max(start, self.step), min(stop, self.span)
        if stop < start:
            return np.zeros(0)
        return np.unique(np.append(np.arange(start, stop, self.step), stop))

    # ------------------------------------------------------------------ one insertion
    def check(self, ins: dict, there: list[str], where: str) -> str:
        """Test one insertion; return how it is supported (``held``, ``rests``, ``fitted``)."""
        body = ins["parts"]
        if not there:
            return "fixture"
        if ins["insert_along"] is None:
            raise Rejected(f"{where}: no insertion direction into {there}")
        d = -vector(ins["insert_along"])
        if ins["free_along"] is None or not np.allclose(vector(ins["free_along"]), d):
            raise Rejected(f"{where}: free_along is not the opposite of insert_along")
        for p in body:
            for j in there:
                hit = self.first_hit(p, j, d, self.path(p, j, d))
                if hit is not None:
                    raise Rejected(
                        f"{where}: {body} is not free along {ins['free_along']}: {p} meets {j} "
                        f"after {hit:.3g} mm (pair tolerance {self.tolerance(p, j):.3g} mm)"
                    )
        down = self.down.get(ins["workspace"], self.gravity)
        rests = self.falls_into(body, there, down)
        gaps = {(p, j): self.plain[p].gap(self.plain[j]) for p in body for j in there}
        touching = any(g <= self.contact(*pj) * 1.01 + 1e-6 for pj, g in gaps.items())
        if not touching and not rests:
            (p, j), gap = min(gaps.items(), key=lambda kv: kv[1])
            raise Rejected(f"{where}: {body} touches none of {there} ({p}-{j} gap {gap:.3f} mm)")
        if ins["held"]:
            return "held"
        if rests:
            return "rests"
        across = [vector(s + a) for a in "xyz" for s in "+-"]
        if all(self.falls_into(body, there, v) for v in across if abs(v @ down) < 0.5):
            return "fitted"  # a bearing pressed in its holder, a nut on its bolt
        raise Rejected(f"{where}: {body} is not supported (it would fall along gravity)")

    def falls_into(self, body: list[str], there: list[str], v: np.ndarray) -> bool:
        """Whether a short move along ``v`` (the support travel of each pair) meets a part."""
        for p in body:
            for j in there:
                travel = self.factor * self.tolerance(p, j)
                if self.first_hit(p, j, v, np.linspace(travel / 8, travel, 8)) is not None:
                    return True
        return False

    def line(self, key: str) -> list[str]:
        """Replay ``plan[key]``; return how each tested insertion is supported."""
        placed = {w["id"]: list(w["initial"]) for w in self.plan["workspaces"]}
        members = self.plan["subassemblies"]
        how = []
        for step in self.plan[key]:
            for ins in step["insertions"]:
                where = f"{key} step {step['step']} (operation {ins['operation']})"
                there = placed.setdefault(ins["workspace"], [])
                if ins["unit"]:
                    done = sorted(placed.get(ins["unit"], []))
                    if done != sorted(members[ins["unit"]]) or sorted(ins["parts"]) != done:
                        raise Rejected(f"{where}: unit {ins['unit']} is not complete")
                if there:
                    how.append(self.check(ins, there, where))
                there.extend(ins["parts"])
        missing = set(self.meshes) - set(placed["main"])
        if missing:
            raise Rejected(f"{key}: the line ends with {sorted(missing)} not in place")
        return how


def replayed(plan: dict) -> Replay:
    """Round-trip through JSON (the checker sees only what the file holds), then replay
    both lines; each must test at least one insertion."""
    plan = json.loads(json.dumps(plan))
    replay = Replay(plan)
    for key in ("robust_plan", "worst_line"):
        assert replay.line(key), f"{key}: no insertion tested"
    return replay
