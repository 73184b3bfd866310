"""Identical parts: the same shape up to a rigid motion, recognised from the meshes.

Two parts are taken as identical when their volumes, surface areas, sorted principal
moments of inertia and sorted oriented-bounding-box extents agree within a relative
tolerance (:data:`RELATIVE_TOL`). These are invariant under rotation and translation, so
copies placed anywhere match, whatever their tessellation. A part and its mirror image
also match (the invariants cannot tell them apart); a BOM or spec ``shape:`` overrides.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from cad.assembly import Part

RELATIVE_TOL = 2e-3
"""Relative tolerance on every invariant."""


def shape_signature(part: Part) -> np.ndarray:
    """Invariants of a part's shape, shape (8,): volume, area, 3 moments, 3 OBB extents."""
    mesh = part.mesh
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
    members without their number (``nut_1``, ``nut_2`` -> ``nut``) when they share one,
    else the first member's id.
    """
    signatures = [shape_signature(p) for p in parts]
    label = [-1] * len(parts)
    classes: list[list[int]] = []
    for i, sig in enumerate(signatures):
        if parts[i].shape:
            continue
        for members in classes:
            ref = signatures[members[0]]
            scale = np.maximum(np.abs(ref), np.abs(sig))
            if np.all(np.abs(ref - sig) <= RELATIVE_TOL * scale + 1e-9):
                members.append(i)
                label[i] = classes.index(members)
                break
        else:
            label[i] = len(classes)
            classes.append([i])
    names = [_class_name([parts[k].id for k in members]) for members in classes]
    return tuple(p.shape if p.shape else names[label[i]] for i, p in enumerate(parts))


def _class_name(ids: list[str]) -> str:
    if len(ids) == 1:
        return ids[0]
    bases = {pid.rsplit("_", 1)[0] if pid.rsplit("_", 1)[-1].isdigit() else pid for pid in ids}
    return bases.pop() if len(bases) == 1 else ids[0]
