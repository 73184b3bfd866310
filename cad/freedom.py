"""Translational freedom ``TT_d(i, j)``: can part i leave along d without penetrating j?

Method (exact, no sampling of the motion)
-----------------------------------------
1. Tolerance by erosion. Every part p is eroded by its shrink ``s_p``: each face plane
   moves inwards by ``s_p`` (:mod:`cad.offset`). By default ``s_p`` follows the part's own
   size and thickness (:mod:`cad.tolerances`); an explicit ``penetration_tol`` gives every
   part ``penetration_tol / 2``. Two parts whose surfaces overlap by at most the pair's
   tolerance ``s_i + s_j`` are then disjoint, and a motion is *blocked* iff it drives
   the eroded parts into each other. Sliding along a shared face (or one overlapping by a
   few hundredths) therefore stays free, moving into it is blocked, and a slide that
   drives deeper than the tolerance is blocked. The eroded parts must be disjoint in the
   assembled pose; otherwise :func:`check_interpenetration` raises a ValueError naming the
   pair and an estimate of the depth.
2. Exact sweep test. Translating the eroded part i along ``d`` to infinity sweeps the
   region ``i + {s d : s >= 0}``. Since i starts disjoint from j, the sweep meets j iff a
   face of i that faces ``d`` (outward normal component along ``d`` > 0; only these
   bound the swept region ahead of i) and a face of j that faces ``-d`` (only through
   these can anything enter j moving along ``d``) have overlapping projections along ``d``
   with the face of j ahead (``h_j >= h_i``) somewhere on the overlap. Faces parallel to
   ``d`` bound no volume of the sweep and are skipped. The height difference is affine on
   the convex overlap polygon, so its maximum sits at one of the polygon's corners, which
   :func:`cad.projection.height_gap_range` enumerates exactly. The test needs no step
   size and no sweep length: a plate of any thickness anywhere ahead is found (the path
   goes beyond the assembly's bounding box, i.e. to infinity for this test).
3. Broad phase: part bounding boxes; then each face set is cut to the region the other
   part's faces span (:func:`cad.faces.crop_pair`, linear); then overlapping 2-D triangle
   boxes (:func:`cad.projection.box_pair_chunks`, brute force for small sets, an
   anisotropic grid for large ones, about linear in faces plus overlapping pairs); each
   ordered pair stops at the first blocking triangle pair.

Relative motion makes the relation antisymmetric in direction: i moving along ``d``
into j is j moving along ``-d`` into i, so ``TT_d(i, j) == TT_-d(j, i)`` for any shapes,
and each pair is computed once per axis.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np
import trimesh

from cad.assembly import Assembly
from cad.errors import Interpenetration
from cad.faces import FaceSet, axis_face_sets, bounds_overlap, crop_pair, unit_normals
from cad.offset import offset_vertices
from cad.progress import progress_bar
from cad.projection import box_pair_chunks, height_gap_range, overlap_share
from cad.tolerances import part_thickness, resolve_tolerances
from cad.unit_hints import unit_hint

_PARALLEL = 1e-9
"""Faces whose normal component along the axis is below this are parallel to it."""
_CHUNK = 4096


def part_diagonals(assembly: Assembly) -> np.ndarray:
    """Bounding-box diagonal of each part in mm, shape ``(n,)``."""
    return np.array([np.linalg.norm(np.ptp(p.bounds, axis=0)) for p in assembly.parts])


def eroded_meshes(assembly: Assembly, depth) -> list[trimesh.Trimesh]:
    """Every part with its faces moved inwards by ``depth`` mm (same topology).

    ``depth`` is one number for every part, or one per part (e.g. ``Tolerances.shrink``).
    """
    depths = np.broadcast_to(np.asarray(depth, dtype=float), (len(assembly),))
    return [
        trimesh.Trimesh(
            vertices=offset_vertices(p.mesh, -float(d)), faces=p.mesh.faces, process=False
        )
        for p, d in zip(assembly.parts, depths, strict=True)
    ]


def translational_freedom(
    assembly: Assembly,
    *,
    penetration_tol: float | None = None,
    progress: bool = False,
    check: bool = True,
    eroded: list[trimesh.Trimesh] | None = None,
) -> np.ndarray:
    """Translational freedom of every ordered pair of parts in every direction.

    Parameters
    ----------
    assembly : Assembly
        ``n`` parts in assembled pose (mm).
    penetration_tol : float or Tolerances, optional
        Overlap depth in mm that still counts as touching, for every pair; default the
        per-part rule of :mod:`cad.tolerances` (a pair tolerates ``s_i + s_j``).
    progress : bool
        Show a progress bar over the pairs.
    check : bool
        First verify that no pair interpenetrates deeper than the tolerance.
    eroded : list of trimesh.Trimesh, optional
        The parts already eroded by their shrinks (:func:`eroded_meshes`).

    Returns
    -------
    np.ndarray
        Bool, shape ``(n, n, 6)``: ``tt[i, j, d]`` is true iff part i can move from its
        pose along direction ``d`` (order ``+x,-x,+y,-y,+z,-z``) to beyond the assembly's
        bounding box without penetrating part j. The diagonal is false.

    Raises
    ------
    ValueError
        Two parts interpenetrate deeper than the tolerance (when ``check``).
    """
    tols = resolve_tolerances(assembly, None, penetration_tol)
    if eroded is None:
        eroded = eroded_meshes(assembly, tols.shrink)
    if check:
        check_interpenetration(assembly, penetration_tol=tols, eroded=eroded)
    n = len(assembly)
    blocked = np.zeros((n, n, 6), dtype=bool)
    for axis, a, b, front, back, bounds in facing_pairs(eroded, progress, "freedom"):
        if bounds[b][1, axis] < bounds[a][0, axis]:
            continue  # b lies entirely behind a
        if sweep_blocked(front, back):
            blocked[a, b, 2 * axis] = True
            blocked[b, a, 2 * axis + 1] = True
    tt = ~blocked
    tt[np.arange(n), np.arange(n), :] = False
    return tt


def facing_pairs(meshes: list[trimesh.Trimesh], progress: bool, label: str):
    """Ordered pairs of parts whose boxes overlap across an axis, with their facing faces.

    Yields
    ------
    axis : int
    a, b : int
        Part indices (``a != b``); ``a`` moves along ``+axis`` towards ``b``.
    front, back : FaceSet
        Faces of ``a`` facing ``+axis`` and of ``b`` facing ``-axis``.
    bounds : list of (2, 3) arrays
        Bounds of every mesh.
    """
    n = len(meshes)
    triangles = [np.asarray(m.triangles, dtype=float) for m in meshes]
    normals = [unit_normals(t) for t in triangles]
    bounds = [np.asarray(m.bounds, dtype=float) for m in meshes]
    pairs = [(a, b) for a in range(n) for b in range(n) if a != b]
    bar = progress_bar(progress, 3 * len(pairs), label)
    for axis in range(3):
        sets = [
            axis_face_sets(t, nn, axis, _PARALLEL) for t, nn in zip(triangles, normals, strict=True)
        ]
        others = ((axis + 1) % 3, (axis + 2) % 3)
        for a, b in pairs:
            bar.update(1)
            if bounds_overlap(bounds[a], bounds[b], axes=others):
                yield axis, a, b, sets[a][0], sets[b][1], bounds
    bar.close()


def sweep_blocked(front: FaceSet, back: FaceSet, travel: float = np.inf) -> bool:
    """Whether faces ``front`` of a part sweeping along ``+axis`` meet faces ``back``.

    Parameters
    ----------
    front : FaceSet
        Faces of the moving part that face ``+axis``.
    back : FaceSet
        Faces of the obstacle that face ``-axis``.
    travel : float
        Length of the move (default: to infinity). A finite travel ``t`` asks whether the
        part meets the obstacle within ``t`` (the support test, :mod:`cad.support`).

    Returns
    -------
    bool
        True iff some pair has overlapping projections with the obstacle face at or ahead
        of the moving face, by at most ``travel``, somewhere on the overlap (the height
        difference is affine on the convex overlap, so its range there is an interval).
    """
    front, back = crop_pair(front, back, 0.0, travel)
    for ia, ib in box_pair_chunks(front.box, back.box):
        ahead = (back.hmax[ib] >= front.hmin[ia]) & (back.hmin[ib] - front.hmax[ia] <= travel)
        ia, ib = ia[ahead], ib[ahead]
        # likeliest blockers first: obstacle face wholly ahead of the moving face, and
        # boxes that overlap by a large share (long slivers crossing rarely overlap)
        wholly = back.hmin[ib] >= front.hmax[ia]
        order = np.argsort(-(overlap_share(front.box[ia], back.box[ib]) + wholly), kind="stable")
        ia, ib = ia[order], ib[order]
        for start in range(0, len(ia), _CHUNK):
            sa, sb = ia[start : start + _CHUNK], ib[start : start + _CHUNK]
            overlap, gap_min, gap_max = height_gap_range(*front.take(sa), *back.take(sb))
            if np.any(overlap & (gap_max >= 0.0) & (gap_min <= travel)):
                return True
    return False


def _collision_object(mesh: trimesh.Trimesh):
    import fcl

    model = fcl.BVHModel()
    model.beginModel(len(mesh.vertices), len(mesh.faces))
    model.addSubModel(
        np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces, dtype=np.int32)
    )
    model.endModel()
    return fcl.CollisionObject(model, fcl.Transform())


def _intersect(a: trimesh.Trimesh, b: trimesh.Trimesh, obj_a=None, obj_b=None) -> bool:
    """Whether closed meshes a and b share volume: surfaces cross or one holds the other."""
    import fcl

    obj_a = obj_a if obj_a is not None else _collision_object(a)
    obj_b = obj_b if obj_b is not None else _collision_object(b)
    if fcl.collide(obj_a, obj_b, fcl.CollisionRequest(), fcl.CollisionResult()):
        return True
    for inner, outer in ((a, b), (b, a)):
        lo, hi = inner.bounds
        olo, ohi = outer.bounds
        inside_box = np.all(lo >= olo) and np.all(hi <= ohi)
        if inside_box and outer.is_watertight and outer.contains(inner.vertices[:1])[0]:
            return True
    return False


MAX_NAMED = 10
"""Overlapping pairs an error names (all are counted)."""
ERODE_SHARE = 0.4
"""The depth measurement erodes a part by at most this share of its thickness
(:func:`cad.tolerances.part_thickness`): deeper, a thin part turns inside out and its
eroded mesh crosses everything around it."""
_BISECTIONS = 14


@dataclass(frozen=True)
class Overlap:
    """Two parts sharing volume deeper than their tolerance, with the depth measured.

    Attributes
    ----------
    a, b : int
        Part indices, ``a < b``.
    depth : float
        Measured overlap (mm): the sum of the equal erosions of the two raw meshes
        (each capped at :data:`ERODE_SHARE` of its thickness) that part them.
    at_least : bool
        The meshes still share volume at the largest erosion tried: ``depth`` is a lower
        bound.
    """

    a: int
    b: int
    depth: float
    at_least: bool = False

    def text(self) -> str:
        """``about 0.5 mm`` or ``at least 2.5 mm``."""
        return f"{'at least' if self.at_least else 'about'} {self.depth:.3g} mm"


def check_interpenetration(
    assembly: Assembly,
    *,
    penetration_tol=None,
    eroded: list[trimesh.Trimesh] | None = None,
) -> None:
    """Raise if parts overlap deeper than their tolerance in the assembled pose.

    A pair overlaps (:func:`overlaps`) iff its raw meshes share volume (FCL finds their
    surfaces crossing, or one holds the other), its parts eroded by their shrinks
    (:mod:`cad.tolerances`; ``penetration_tol / 2`` each if a number is given) still do,
    and the depth measured on the raw meshes (:func:`measured_overlap`) exceeds the pair's
    tolerance. The depth does not depend on the tolerance, so a larger tolerance never
    flags more pairs.

    Raises
    ------
    ValueError
        One line naming every overlapping pair (the first :data:`MAX_NAMED`) and its depth.
    """
    tols = resolve_tolerances(assembly, None, penetration_tol)
    found = overlaps(assembly, tols, eroded)
    if found:
        raise interpenetration_error(assembly, tols, found)


def overlapping_pairs(
    assembly: Assembly, tols, eroded: list[trimesh.Trimesh] | None = None, *, first: bool = False
) -> list[tuple[int, int]]:
    """Pairs ``(a, b)``, ``a < b``, that overlap deeper than their tolerance
    (:func:`overlaps`); only the first one if ``first``."""
    return [(o.a, o.b) for o in overlaps(assembly, tols, eroded, first=first)]


def overlaps(
    assembly: Assembly, tols, eroded: list[trimesh.Trimesh] | None = None, *, first: bool = False
) -> list[Overlap]:
    """Every pair whose parts eroded by their shrinks share volume, whose raw meshes share
    volume, and whose measured depth exceeds the pair's tolerance, in pair order."""
    if eroded is None:
        eroded = eroded_meshes(assembly, tols.shrink)
    objects = [_collision_object(m) for m in eroded]
    bounds = [np.asarray(m.bounds) for m in eroded]
    n = len(assembly)
    found = []
    for a in range(n):
        for b in range(a + 1, n):
            if not bounds_overlap(bounds[a], bounds[b]):
                continue
            if not _intersect(eroded[a], eroded[b], objects[a], objects[b]):
                continue
            raw_a, raw_b = _centred(assembly.parts[a].mesh, assembly.parts[b].mesh)
            if not _intersect(raw_a, raw_b):
                continue  # the erosion slid a vertex across: the surfaces do not cross
            overlap = measured_overlap(raw_a, raw_b, a, b)
            if overlap.depth > tols.pair(a, b):
                found.append(overlap)
                if first:
                    return found
    return found


def measured_overlap(mesh_a: trimesh.Trimesh, mesh_b: trimesh.Trimesh, a: int, b: int) -> Overlap:
    """How deep two raw meshes that share volume overlap: bisection on an equal erosion of
    both (each capped at :data:`ERODE_SHARE` of its thickness) for the least that parts
    them; the depth is the sum of the two erosions there."""
    caps = [ERODE_SHARE * part_thickness(m) for m in (mesh_a, mesh_b)]
    sizes = np.concatenate([np.ptp(mesh_a.bounds, axis=0), np.ptp(mesh_b.bounds, axis=0)])
    hi = float(sizes.min()) / 4.0

    def amount(e: float) -> float:
        return min(e, caps[0]) + min(e, caps[1])

    def still(e: float) -> bool:
        ea = trimesh.Trimesh(offset_vertices(mesh_a, -min(e, caps[0])), mesh_a.faces, process=False)
        eb = trimesh.Trimesh(offset_vertices(mesh_b, -min(e, caps[1])), mesh_b.faces, process=False)
        return _intersect(ea, eb)

    if hi <= 0 or still(hi):
        return Overlap(a, b, amount(max(hi, 0.0)), at_least=True)
    lo = 0.0
    for _ in range(_BISECTIONS):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if still(mid) else (lo, mid)
    return Overlap(a, b, amount(lo))


def _centred(a: trimesh.Trimesh, b: trimesh.Trimesh) -> tuple[trimesh.Trimesh, trimesh.Trimesh]:
    """Both meshes moved by the same shift to put their joint box's centre at the origin
    (FCL and the erosion lose digits on coordinates far from it, e.g. near 1e9)."""
    centre = 0.5 * (np.minimum(a.bounds[0], b.bounds[0]) + np.maximum(a.bounds[1], b.bounds[1]))
    if not np.any(np.abs(centre) > 1e3):
        return a, b
    return tuple(
        trimesh.Trimesh(np.asarray(m.vertices) - centre, m.faces, process=False) for m in (a, b)
    )


def interpenetration_error(assembly: Assembly, tols, found: list[Overlap]) -> Interpenetration:
    """The one-line error for every pair in ``found`` (the first :data:`MAX_NAMED` named),
    ending with the one spec line that accepts them all (:func:`overlap_line`) unless the
    unit is wrong (``unit_wrong``); its ``pairs`` hold the pairs' part ids."""
    parts = assembly.parts
    first = found[0]
    pairs = [(parts[o.a].id, parts[o.b].id) for o in found]
    hint = unit_hint(assembly, first.a, first.b)
    unit_wrong = bool(hint)
    if not hint:
        join = joining_line(parts[first.a], parts[first.b]) if len(found) == 1 else ""
        hint = (
            f"if {'they overlap' if len(found) == 1 else 'these overlaps are'} as modelled (a "
            f"press fit, a thread, a visual asset's pieces), the spec line `{overlap_line(pairs)}`"
            f" takes {'the pair' if len(found) == 1 else 'each pair'} as touching"
            + (f"; {join}" if join else "")
            + " (`asmplan init` writes the spec)"
        )
    if len(found) == 1:
        message = (
            f"parts {parts[first.a].id!r} and {parts[first.b].id!r} interpenetrate by "
            f"{first.text()} (penetration tolerance of this pair {tols.pair(first.a, first.b):.3g}"
            f" mm); {hint}"
        )
    else:
        named = "; ".join(
            f"{parts[o.a].id!r} and {parts[o.b].id!r} by {o.text()} (tolerance "
            f"{tols.pair(o.a, o.b):.3g} mm)"
            for o in found[:MAX_NAMED]
        )
        more = f"; and {len(found) - MAX_NAMED} more" if len(found) > MAX_NAMED else ""
        message = (
            f"{len(found)} pairs of parts interpenetrate deeper than their tolerance: "
            f"{named}{more}; {hint}"
        )
    return Interpenetration(message, pairs, unit_wrong=unit_wrong)


def locking_pairs(tt: np.ndarray, ids) -> list[tuple[str, str]]:
    """Pairs ``(i, j)`` of parts that block each other along all six directions (``tt``
    false both ways): whichever goes in second has no way in."""
    stuck = ~np.asarray(tt, dtype=bool).any(axis=2)
    np.fill_diagonal(stuck, False)
    i, j = np.nonzero(np.triu(stuck & stuck.T))
    names = [str(p) for p in ids]
    return [(names[a], names[b]) for a, b in zip(i.tolist(), j.tolist(), strict=True)]


def flexing_parts(assembly: Assembly, pairs) -> tuple[str, ...]:
    """The parts a ``flex:`` line names to let each locking pair in (``pairs`` of part ids):
    of each pair the smaller part (by bounding-box diagonal; a snap fit's clip, a
    connector in its panel), each once, in the assembly's order."""
    size = {p.id: float(np.linalg.norm(np.ptp(p.bounds, axis=0))) for p in assembly.parts}
    chosen = {a if size[a] <= size[b] else b for a, b in pairs}
    return tuple(p.id for p in assembly.parts if p.id in chosen)


def flex_line(parts) -> str:
    """The ``flex:`` spec line naming ``parts``."""
    return "flex: [" + ", ".join(parts) + "]"


def with_locking(error: Interpenetration, assembly: Assembly, relations) -> Interpenetration:
    """``error`` (of :func:`interpenetration_error`) told what else the file needs once its
    overlaps are accepted (``relations``, computed so): the pairs that then lock each other
    and the ``flex:`` line that lets each in, so that one message names every line to add;
    its ``flex`` holds those parts (empty: none lock), its ``relations`` the relations."""
    locked = locking_pairs(relations.tt, assembly.ids)
    flex = flexing_parts(assembly, locked)
    text = str(error)
    if locked:
        shown = "; ".join(f"{a} and {b}" for a, b in locked[:MAX_NAMED])
        more = f" and {len(locked) - MAX_NAMED} more pair(s)" if len(locked) > MAX_NAMED else ""
        text = (
            f"{text.replace(' (`asmplan init` writes the spec)', '')}; with the overlaps so "
            f"accepted, {shown}{more} block each other along every direction (whichever goes "
            "in second has no way in): if the smaller of each pair flexes in (a snap fit, a "
            f"clip, a connector), the line `{flex_line(flex)}` lets it in after the other "
            "(`asmplan init` writes the spec, both lines commented)"
        )
    return Interpenetration(text, error.pairs, flex=flex, relations=relations)


def overlap_line(pairs) -> str:
    """The ``overlap_ok:`` spec line accepting ``pairs`` (part ids) as modelled."""
    return "overlap_ok: [" + ", ".join(f"[{a}, {b}]" for a, b in pairs) + "]"


def joining_line(a, b) -> str:
    """The spec line that plans two parts of one scene file as one rigid part (their
    meshes together, :mod:`cad.merging`), or "" when they are not nodes of one file."""
    file_a, _, node_a = a.source.partition("#")
    file_b, _, node_b = b.source.partition("#")
    if not node_a or file_a != file_b:
        return ""
    name = os.path.basename(file_a)
    return (
        f"if {a.id!r} and {b.id!r} are one component, plan them as one rigid part: in the "
        f"spec's parts, `- {{id: {a.id}, file: '{name}#{node_a}+{node_b}'}}` in place of both, "
        f"and no operation placing {b.id}"
    )


def intersects(a: trimesh.Trimesh, b: trimesh.Trimesh) -> bool:
    """Whether closed meshes ``a`` and ``b`` share volume (crossing surfaces or nesting)."""
    return _intersect(a, b)
