"""Identical parts: the same shape up to a rigid motion, recognised from the meshes.

Two parts are taken as identical when their volumes, surface areas, sorted principal
moments of inertia and sorted oriented-bounding-box extents agree within a relative
tolerance (:data:`RELATIVE_TOL`). These are invariant under rotation and translation, so
copies placed anywhere match, whatever their tessellation. A part and its mirror image
also match (the invariants cannot tell them apart); a BOM or spec ``shape:`` overrides.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence

import numpy as np
import trimesh

from cad.assembly import Part

RELATIVE_TOL = 2e-3
"""Relative tolerance on every invariant."""


def shape_signature(part: Part) -> np.ndarray:
    """Invariants of a part's shape, shape (8,): volume, area, 3 moments, 3 OBB extents."""
    return mesh_signature(part.mesh)


def mesh_signature(mesh: trimesh.Trimesh) -> np.ndarray:
    """Invariants of a mesh's shape, shape (8,): volume, area, 3 moments, 3 OBB extents."""
    volume = abs(float(mesh.volume)) if mesh.is_watertight else 0.0
    moments = np.sort(np.abs(mesh.principal_inertia_components)) if volume else np.zeros(3)
    try:
        extents = np.sort(np.asarray(mesh.bounding_box_oriented.primitive.extents, dtype=float))
    except Exception:  # pragma: no cover - degenerate mesh
        extents = np.sort(np.asarray(mesh.extents, dtype=float))
    return np.array([volume, float(mesh.area), *moments, *extents])


def shape_classes(parts: Sequence[Part]) -> tuple[str, ...]:
    """A shape-class id per part: identical parts share one (the first member's id base).

    A part whose ``shape`` is already set keeps it. A class's id is the common name of its
    members without their number (``nut_1``, ``nut_2`` -> ``nut``) when they share one and
    no other class does, else the first member's id (the bodies of one split part, all
    ``truck_body_<n>``, are screws and tyres: two classes, never one).
    """
    free = [k for k, p in enumerate(parts) if not p.shape]
    label = dict(zip(free, alike_labels([parts[k].mesh for k in free]), strict=True))
    members: dict[int, list[str]] = {}
    for k, cls in label.items():
        members.setdefault(cls, []).append(parts[k].id)
    names = {cls: _class_name(ids) for cls, ids in members.items()}
    taken = Counter(names.values())
    for cls, name in names.items():  # two classes of one name base: each its first id
        if taken[name] > 1:
            names[cls] = members[cls][0]
    return tuple(p.shape if p.shape else names[label[k]] for k, p in enumerate(parts))


def alike_labels(meshes: Sequence[trimesh.Trimesh]) -> list[int]:
    """A class number per mesh: identical shapes share one; classes numbered 0, 1, ... in
    the order of their first member."""
    signatures = [mesh_signature(m) for m in meshes]
    label = []
    firsts: list[int] = []  # each class's first member
    for sig in signatures:
        for cls, first in enumerate(firsts):
            ref = signatures[first]
            scale = np.maximum(np.abs(ref), np.abs(sig))
            if np.all(np.abs(ref - sig) <= RELATIVE_TOL * scale + 1e-9):
                label.append(cls)
                break
        else:
            label.append(len(firsts))
            firsts.append(len(label) - 1)
    return label


def _class_name(ids: list[str]) -> str:
    if len(ids) == 1:
        return ids[0]
    bases = {pid.rsplit("_", 1)[0] if pid.rsplit("_", 1)[-1].isdigit() else pid for pid in ids}
    return bases.pop() if len(bases) == 1 else ids[0]
