"""An independent checker: replay a plan's lines from ``plan.json`` and the meshes alone.

It plays the part of a checker that knows nothing of ``asp`` or ``cad``: it reads only the
plan file (README, "The plan file": ``workspaces``, each step's ``insertions``,
``gravity``, ``geometry``, ``parts[].source``), loads the meshes it names with trimesh and
tests each insertion with python-fcl. The rules (``geometry``):

- **meshes**: each part's mesh from ``parts[].source`` (a STEP tessellated to within
  ``geometry.step_chord`` mm, as the planner read it), times its ``scale`` (else
  ``geometry.scale``: mm per coordinate as trimesh reads the file), turned into the build
  frame by ``geometry.build_rotation`` (``x_build = R @ x_file``; directions are its axes), its
  coincident vertices merged when ``merge_vertices`` (by position alone: a glTF's vertices
  at one corner with different texture coordinates or normals are one; a STEP or 3DXML
  tessellation gives every face its own vertices; an unmerged mesh cannot be eroded: every
  vertex would move along its own face only, leaving the edges in place), a closed mesh
  with its normals inwards turned outwards;
- **erosion**: every part shrunk by its ``part_shrink``: each vertex moved inwards along
  its normal, never moving any face plane by more than the shrink (conservative: the
  replay tolerates at most what the plan says), and the free edges of an open part (edges
  of one face) moved back in their faces by ``free_edge_pull`` shrinks; the inner part of a
  pair in ``fits`` is shrunk by ``extra_shrink`` more against that pair's outer part only;
- **open parts**: ``open_parts`` must be exactly the parts whose mesh is not closed once
  merged; a closed part has an inside (a body lying wholly in it collides with it, as a
  body whose surface crosses it does), an open one has none (its relations are
  approximate: only crossing surfaces count);
- **free**: the body, moved along ``free_along`` (``-insert_along``) from its assembled pose
  to beyond everything in steps of a quarter of the thinnest part (so nothing thin is
  jumped over), never collides with the parts already in its workspace, both eroded;
- **touching**: the gap to those parts is at most the pair's contact tolerance
  (``min(contact_reach[i], contact_reach[j])``, else ``contact_tol``), or they overlap, or
  the body comes to rest on one of them (the fall of the support test below meets it: a
  clip hanging on a barrel across its clearance touches it once settled);
- **supported** (unless ``held``), along ``gravity`` (the workspace's own, for a unit
  built in another orientation), by the rules ``geometry.support`` lists (DESIGN.md,
  "Support"; ``cad/support.py``), for some part of the body and some part already there:
  ``rests``: moved along gravity by the support travel (``support_travel_factor`` times
  the pair's tolerance) the eroded body meets the part; ``captured``: the part holds the
  body all round across gravity (a move of the pair's contact tolerance plus its
  tolerance in each of the four directions across gravity meets it, and a move on to
  beyond everything never gets clear) and a fall of the shorter of the two extents along
  gravity meets it (a dowel in a blind hole); ``threaded``: held all round likewise and
  the part's cross-section at the body's mid-height lies inside the body's (a nut on its
  bolt). A pin merely fitted in a through hole is not supported.

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
SUPPORT_RULES = ("rests", "captured", "threaded")
"""The ways a part is held up when the plan does not say (``geometry.support``)."""


class Rejected(AssertionError):
    """The replay found a step the geometry does not allow."""


def vector(direction: str) -> np.ndarray:
    """Unit vector of ``"+x"`` ... ``"-z"``, shape ``(3,)``."""
    v = np.zeros(3)
    v[AXES[direction[1]]] = 1.0 if direction[0] == "+" else -1.0
    return v


def read_options(path: Path, geo: dict) -> dict:
    """Keywords for ``trimesh.load`` of a scene file: a glTF mesh's primitives are one part,
    named as its node (not randomly); a STEP is tessellated to within ``step_chord`` mm."""
    suffix = path.suffix.lower()
    if suffix in (".glb", ".gltf"):
        return {"merge_primitives": True}
    if suffix in (".step", ".stp") and geo.get("step_chord"):
        return {"tol_linear": float(geo["step_chord"])}
    return {}


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
            mesh = trimesh.load(path, force="mesh", **read_options(path, geo))
        else:
            if path not in scenes:
                scenes[path] = trimesh.load(path, force="scene", **read_options(path, geo))
            transform, geometry = scenes[path].graph[src["node"]]
            mesh = scenes[path].geometry[geometry].copy().apply_transform(transform)
        mesh = mesh.apply_scale(src.get("scale") or geo["scale"])
        if geo.get("build_rotation") is not None:  # into the build frame: x' = R x
            turn = np.eye(4)
            turn[:3, :3] = np.asarray(geo["build_rotation"], float)
            mesh = mesh.apply_transform(turn)
        if geo.get("merge_vertices", False):  # by position: a glTF's UV seams are no holes
            mesh.merge_vertices(merge_tex=True, merge_norm=True)
        if mesh.is_watertight and mesh.volume < 0:
            mesh.invert()  # a closed mesh drawn inside out: erode it inwards all the same
        out[part["id"]] = mesh
    return out


def eroded(mesh: trimesh.Trimesh, shrink: float, pull: float = 0.0) -> trimesh.Trimesh:
    """Each vertex moved inwards along its normal so that no face plane it touches moves by
    more than ``shrink`` (exactly ``shrink`` for the plane closest to the normal); a vertex
    on free edges (edges of one face) also moved back in those faces, away from them, by
    at most ``pull * shrink`` (``free_edge_pull``)."""
    if shrink <= 0:
        return mesh
    back = np.zeros((len(mesh.vertices), 3))
    if pull > 0 and not mesh.is_watertight:
        counts = np.bincount(mesh.edges_unique_inverse)
        free = counts[mesh.edges_unique_inverse] == 1
        ends, faces = mesh.edges[free], mesh.edges_face[free]
        start, stop = mesh.vertices[ends[:, 0]], mesh.vertices[ends[:, 1]]
        away = np.cross(stop - start, mesh.face_normals[faces])
        outside = (start + stop) / 2 - mesh.triangles_center[faces]
        away *= np.sign(np.einsum("ij,ij->i", away, outside))[:, None]
        away /= np.maximum(np.linalg.norm(away, axis=1), 1e-300)[:, None]
        np.add.at(back, ends[:, 0], away)
        np.add.at(back, ends[:, 1], away)
        size = np.linalg.norm(back, axis=1)
        back /= np.maximum(size, 1.0)[:, None]  # at most one pull, however many free edges
    normals = mesh.vertex_normals
    cos = np.zeros(len(mesh.vertices))
    for k in range(mesh.vertex_faces.shape[1]):
        f = mesh.vertex_faces[:, k]
        has = f >= 0
        dots = np.einsum("ij,ij->i", normals[has], mesh.face_normals[f[has]])
        cos[has] = np.maximum(cos[has], dots)
    move = shrink / np.clip(cos, 0.5, 1.0)
    moved = mesh.vertices - normals * move[:, None] - back * (pull * shrink)
    return trimesh.Trimesh(moved, mesh.faces, process=False)


def collision_object(mesh: trimesh.Trimesh) -> fcl.CollisionObject:
    model = fcl.BVHModel()
    model.beginModel(len(mesh.vertices), len(mesh.faces))
    model.addSubModel(np.asarray(mesh.vertices, float), np.asarray(mesh.faces, np.int32))
    model.endModel()
    return fcl.CollisionObject(model, fcl.Transform())


class Solid:
    """A mesh as an fcl object with its bounds; moved by a translation. A closed solid has
    an inside: a part lying wholly in it collides with it (no surface need cross)."""

    def __init__(self, mesh: trimesh.Trimesh, closed: bool = False):
        self.bounds = np.asarray(mesh.bounds, float)
        self.obj = collision_object(mesh)
        self.mesh = mesh
        self.closed = closed

    def hits(self, other: Solid, offset: np.ndarray) -> bool:
        """Whether this solid, moved by ``offset``, collides with ``other`` (in place): their
        surfaces cross, or one lies wholly inside the other, a closed solid."""
        lo, hi = self.bounds + offset
        if np.any(lo > other.bounds[1]) or np.any(hi < other.bounds[0]):
            return False
        self.obj.setTranslation(np.asarray(offset, float))
        hit = fcl.collide(self.obj, other.obj, fcl.CollisionRequest(), fcl.CollisionResult())
        self.obj.setTranslation(np.zeros(3))
        return bool(hit) or self.inside(other, offset) or other.inside(self, -offset)

    def inside(self, other: Solid, offset: np.ndarray) -> bool:
        """Whether this solid, moved by ``offset`` and clear of ``other``'s surface, lies in
        ``other`` (only a closed solid has an inside)."""
        lo, hi = self.bounds + offset
        if not other.closed or np.any(lo < other.bounds[0]) or np.any(hi > other.bounds[1]):
            return False
        return bool(other.mesh.contains(self.mesh.vertices[:1] + offset)[0])

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
        self.rules = set(geo.get("support", SUPPORT_RULES))
        self.gravity = vector(plan["gravity"])
        # a unit built in another orientation (upside down) has its own gravity
        self.down = {w["id"]: vector(w.get("gravity", plan["gravity"])) for w in plan["workspaces"]}
        self.extra = {(f["inner"], f["outer"]): f["extra_shrink"] for f in geo.get("fits", [])}
        # pairs accepted as overlapping, nested too deep to part: touching, resting on each
        # other, never blocking each other
        self.through = {frozenset(pair) for pair in geo.get("through", [])}
        # pairs across the model's gaps: touching; resting on the part on their gravity side
        self.nearest = {}
        for n in geo.get("nearest", []):
            self.nearest[(n["part"], n["near"])] = vector(n["side"])
            self.nearest[(n["near"], n["part"])] = -vector(n["side"])
        pull = float(geo.get("free_edge_pull", 0.0))
        self.open = {p for p, m in self.meshes.items() if not m.is_watertight}
        said = set(geo.get("open_parts", self.open))
        if said != self.open:
            raise Rejected(
                f"geometry.open_parts says {sorted(said)}, the meshes have {sorted(self.open)} open"
            )
        closed = {p: p not in self.open for p in self.meshes}
        self.plain = {p: Solid(m, closed[p]) for p, m in self.meshes.items()}
        self.solid = {
            p: Solid(eroded(m, self.shrink[p], pull), closed[p]) for p, m in self.meshes.items()
        }
        self.fitted = {
            pair: Solid(
                eroded(self.meshes[pair[0]], self.shrink[pair[0]] + extra, pull), closed[pair[0]]
            )
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
                if frozenset((p, j)) in self.through:
                    continue
                hit = self.first_hit(p, j, d, self.path(p, j, d))
                if hit is not None:
                    raise Rejected(
                        f"{where}: {body} is not free along {ins['free_along']}: {p} meets {j} "
                        f"after {hit:.3g} mm (pair tolerance {self.tolerance(p, j):.3g} mm)"
                    )
        down = self.down.get(ins["workspace"], self.gravity)
        rests = self.falls_into(body, there, down)
        gaps = {(p, j): self.plain[p].gap(self.plain[j]) for p in body for j in there}
        gaps.update(
            {
                (p, j): 0.0
                for p, j in gaps
                if frozenset((p, j)) in self.through or (p, j) in self.nearest
            }
        )
        touching = any(g <= self.contact(*pj) * 1.01 + 1e-6 for pj, g in gaps.items())
        if not touching and not rests:
            (p, j), gap = min(gaps.items(), key=lambda kv: kv[1])
            raise Rejected(f"{where}: {body} touches none of {there} ({p}-{j} gap {gap:.3f} mm)")
        if ins["held"]:
            return "held"
        how = self.support(body, there, down)
        if how is None:
            raise Rejected(f"{where}: {body} is not supported (it would fall along gravity)")
        return how

    # ------------------------------------------------------------------ support
    def support(self, body: list[str], there: list[str], down: np.ndarray) -> str | None:
        """How some part of ``body`` is held up by some part of ``there`` when it falls along
        ``down`` (``geometry.support``): ``rests`` (a fall of the support travel meets it),
        ``captured`` (fitted across gravity in a part that a fall of the shorter extent
        along gravity meets: a dowel in a blind hole), ``threaded`` (fitted across gravity
        around a part passing through it: a nut on its bolt); None when it would fall."""
        if self.falls_into(body, there, down):
            return "rests"
        if any(frozenset((p, j)) in self.through for p in body for j in there):
            return "rests"
        if any(
            np.allclose(self.nearest[(p, j)], down)
            for p in body
            for j in there
            if (p, j) in self.nearest
        ):
            return "nearest"
        axis = int(np.argmax(np.abs(down)))
        for p in body:
            for j in there:
                if not self.fitted_across(p, j, axis):
                    continue
                if "captured" in self.rules:
                    travel = min(
                        np.ptp(self.plain[p].bounds[:, axis]), np.ptp(self.plain[j].bounds[:, axis])
                    )
                    travel = max(travel, self.travel(p, j))
                    if self.first_hit(p, j, down, self.fall(travel, p, j)) is not None:
                        return "captured"
                if "threaded" in self.rules and self.passes_through(j, p, axis):
                    return "threaded"
        return None

    def travel(self, p: str, j: str) -> float:
        """Support travel of a pair (mm): ``support_travel_factor`` pair tolerances."""
        return self.factor * self.tolerance(p, j)

    def fall(self, travel: float, p: str, j: str) -> np.ndarray:
        """Offsets (mm) of a move of ``travel``: eighths of the pair's support travel, then
        steps of a quarter of the thinnest part (nothing thin is jumped over)."""
        t = self.travel(p, j)
        near = np.linspace(t / 8, t, 8)
        return np.unique(
            np.concatenate([near[near < travel], np.arange(t, travel, self.step), [travel]])
        )

    def fitted_across(self, p: str, j: str, axis: int) -> bool:
        """Whether ``j`` holds ``p`` all round across ``axis``: a move of the pair's contact
        tolerance plus its tolerance (the gap erosion opens) in each of the four directions
        across it meets ``j``, and a move on to beyond everything never gets clear (a pin in
        a hole, a nut on a bolt: ``TC`` and not ``TT`` in each)."""
        near = self.contact(p, j) + self.tolerance(p, j)
        for a in range(3):
            if a == axis:
                continue
            for sign in (1.0, -1.0):
                v = np.zeros(3)
                v[a] = sign
                if self.first_hit(p, j, v, self.fall(max(near, self.travel(p, j)), p, j)) is None:
                    return False
                if not self.blocked(p, j, v):
                    return False
        return True

    def blocked(self, p: str, j: str, v: np.ndarray) -> bool:
        """Whether ``p`` moved along ``v`` to beyond everything meets ``j``."""
        return self.first_hit(p, j, v, self.path(p, j, v)) is not None

    def passes_through(self, inner: str, outer: str, axis: int) -> bool:
        """Whether ``inner``'s cross-section at ``outer``'s mid-height (a plane across
        ``axis``) lies inside ``outer``'s and is smaller (a bolt through its nut; a plate a
        bolt passes through does not pass through the bolt)."""
        lo, hi = self.plain[outer].bounds[:, axis]
        normal = np.zeros(3)
        normal[axis] = 1.0
        origin = normal * 0.5 * (lo + hi)
        cuts = [
            self.meshes[k].section(plane_origin=origin, plane_normal=normal) for k in (inner, outer)
        ]
        if cuts[0] is None or cuts[1] is None:
            return False
        others = [k for k in range(3) if k != axis]
        b_in, b_out = (np.asarray(c.bounds)[:, others] for c in cuts)
        slack = 1e-6 * float(np.ptp(b_out, axis=0).max())
        inside = np.all(b_in[0] >= b_out[0] - slack) and np.all(b_in[1] <= b_out[1] + slack)
        smaller = np.any(np.ptp(b_in, axis=0) < np.ptp(b_out, axis=0) - slack)
        return bool(inside and smaller)

    def falls_into(self, body: list[str], there: list[str], v: np.ndarray) -> bool:
        """Whether a short move along ``v`` (the support travel of each pair) meets a part."""
        for p in body:
            for j in there:
                travel = self.travel(p, j)
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
