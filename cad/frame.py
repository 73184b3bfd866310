"""The build frame: the orientation in which a product is fixtured in the cell.

The six directions of DESIGN.md (and gravity) are the axis directions of the *build
frame*. A product whose parts go in along a tilted axis (the Fabrica duct's cap and its six
pins lie along ``(0.5, 0, 0.866)``, 30 degrees off ``z``) is fixtured turned so that axis is
vertical: the build frame is the file's frame rotated by a rotation ``R``,

    x_build = R @ x_file          (millimetres, about the file's origin)

``R`` is the spec's ``frame:`` (:func:`parse_frame`), or chosen for a generated spec
(:mod:`asp.fromcad.framing`). Parts are turned once, where they are loaded
(:func:`cad.loading.load_parts`): relations, tolerances, support, gravity and every mesh
output are then in the build frame. ``None`` is the file's own frame (no rotation).

Candidate frames come from the parts' own axes (:func:`candidate_frames`): each part's
principal axes of inertia that are well defined (an eigenvalue apart from the other two: a
pin's or a disc's axis, a plate's normal), those more than :data:`ALIGNED_DEG` off every
coordinate axis clustered (up to sign), and for the clusters shared by the most parts the
rotation that turns the cluster's direction onto the nearest coordinate axis, a shared axis
square to it onto another (a tilted plate's edge beside its normal), then the smallest
rotation turning the first alone.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, replace

import numpy as np

from cad.numbers import WRITTEN_PLAINLY, plain_number

Rotation = tuple[tuple[float, float, float], ...]
"""A 3x3 rotation, row by row: ``x_build = R @ x_file``."""

ALIGNED_DEG = 1.0
"""A part axis within this angle of a coordinate axis is aligned with it."""
CLUSTER_DEG = 3.0
"""Part axes within this angle of each other (up to sign) are one direction."""
DISTINCT = 0.1
"""A principal axis is well defined when its moment differs from the other two by this
share of the largest moment (a cylinder's axis is, its two cross axes are not)."""
SQUARE_DEG = 10.0
"""A second shared axis within this angle of square to the first is aligned as well."""
MAX_CANDIDATES = 3
"""Candidate frames tried at most (each costs one computation of the relations)."""
AXIS_DECIMALS = 4
DEGREE_DECIMALS = 3
"""A frame is kept as ``{axis, degrees}`` rounded so (what ``asmplan init`` writes)."""


def rotation_matrix(axis, degrees: float) -> np.ndarray:
    """The right-handed rotation by ``degrees`` about ``axis`` (any length), shape (3, 3)."""
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    t = np.radians(float(degrees))
    k = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    return np.eye(3) + np.sin(t) * k + (1.0 - np.cos(t)) * (k @ k)


def axis_degrees(rotation) -> tuple[np.ndarray, float]:
    """``(unit axis, degrees in [0, 180])`` of a rotation (axis ``+z`` for the identity)."""
    r = np.asarray(rotation, dtype=float)
    angle = float(np.degrees(np.arccos(np.clip((np.trace(r) - 1.0) / 2.0, -1.0, 1.0))))
    if angle < 1e-9:
        return np.array([0.0, 0.0, 1.0]), 0.0
    if angle > 179.999:  # sin ~ 0: the axis from the symmetric part
        w, v = np.linalg.eigh((r + r.T) / 2.0)
        return v[:, int(np.argmax(w))], angle
    axis = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
    return axis / np.linalg.norm(axis), angle


def canonical(rotation) -> Rotation | None:
    """A rotation as the frame keeps it: through ``{axis, degrees}`` rounded (what a spec
    says), None for the identity (the file's own frame)."""
    axis, degrees = axis_degrees(rotation)
    degrees = round(degrees, DEGREE_DECIMALS)
    axis = np.round(axis, AXIS_DECIMALS) + 0.0
    if degrees == 0.0 or not axis.any():
        return None
    return as_rotation(rotation_matrix(axis, degrees))


def as_rotation(matrix) -> Rotation:
    """A 3x3 array as nested tuples of floats."""
    return tuple(tuple(float(x) for x in row) for row in np.asarray(matrix, dtype=float))


def frame_record(rotation: Rotation | None) -> dict | None:
    """The spec's ``frame:`` value of a rotation (``{axis: [x, y, z], degrees: a}``)."""
    if rotation is None:
        return None
    axis, degrees = axis_degrees(rotation)
    return {
        "axis": [float(round(x, AXIS_DECIMALS)) + 0.0 for x in axis],
        "degrees": float(round(degrees, DEGREE_DECIMALS)),
    }


def frame_text(rotation: Rotation | None) -> str:
    """``"30 degrees about (0, -1, 0)"`` for a person (``"the file's frame"`` for None)."""
    if rotation is None:
        return "the file's frame"
    record = frame_record(rotation)
    axis = ", ".join(f"{x:g}" for x in record["axis"])
    return f"the file's frame turned {record['degrees']:g} degrees about ({axis})"


def parse_frame(value) -> Rotation | None:
    """The rotation a spec's ``frame:`` gives (None: the file's own frame).

    Accepted: ``file`` or null (no rotation); ``{axis: [x, y, z], degrees: a}`` (a right-
    handed turn of ``a`` degrees about the axis; ``axis`` may also be ``x``, ``-y``, ...);
    or a 3x3 matrix ``[[...], [...], [...]]`` with ``x_build = R @ x_file`` (orthonormal
    within 1e-4, determinant +1). Numbers may be given as text.

    Raises
    ------
    ValueError
        One line saying what is wrong (the caller names the file and key).
    """
    if value is None or (isinstance(value, str) and value.strip().lower() == "file"):
        return None
    if isinstance(value, dict):
        unknown = set(value) - {"axis", "degrees"}
        if unknown or "axis" not in value or "degrees" not in value:
            raise ValueError(
                f"expected {{axis: [x, y, z], degrees: a}}, got keys {sorted(map(str, value))}"
            )
        axis = _axis(value["axis"])
        degrees = _float(value["degrees"], "degrees")
        return None if degrees % 360.0 == 0.0 else as_rotation(rotation_matrix(axis, degrees))
    if isinstance(value, list) and len(value) == 3 and all(isinstance(r, list) for r in value):
        rows = [[_float(x, "matrix entry") for x in row] for row in value]
        if any(len(row) != 3 for row in rows):
            raise ValueError("expected a 3x3 matrix (three rows of three numbers)")
        r = np.array(rows)
        if not np.allclose(r @ r.T, np.eye(3), atol=1e-4):
            raise ValueError("the matrix is not a rotation (its rows are not orthonormal)")
        if np.linalg.det(r) < 0:
            raise ValueError("the matrix is a reflection, not a rotation (determinant -1)")
        u, _, vt = np.linalg.svd(r)  # the nearest exact rotation
        r = u @ vt
        return None if np.allclose(r, np.eye(3), atol=1e-12) else as_rotation(r)
    raise ValueError(
        f"expected 'file', {{axis: [x, y, z], degrees: a}} or a 3x3 matrix, got {value!r}"
    )


def _float(value, what: str) -> float:
    x = plain_number(value)
    if x is None:
        raise ValueError(f"{what}: expected a number {WRITTEN_PLAINLY}, got {value!r}")
    if not np.isfinite(x):
        raise ValueError(f"{what}: expected a finite number, got {value!r}")
    return x


def _axis(value) -> np.ndarray:
    if isinstance(value, str):
        text = value.strip().lower()
        name = text.lstrip("+-")
        if name not in ("x", "y", "z") or len(text) - len(name) > 1:
            raise ValueError(f"axis: expected x, y, z (signed) or [x, y, z], got {value!r}")
        a = np.zeros(3)
        a["xyz".index(name)] = -1.0 if text.startswith("-") else 1.0
        return a
    if not isinstance(value, list) or len(value) != 3:
        raise ValueError(f"axis: expected [x, y, z], got {value!r}")
    a = np.array([_float(x, "axis") for x in value])
    if np.linalg.norm(a) < 1e-9:
        raise ValueError("axis: the zero vector has no direction")
    return a


def transform(rotation: Rotation | None) -> np.ndarray:
    """The 4x4 homogeneous transform of a rotation (identity for None)."""
    out = np.eye(4)
    if rotation is not None:
        out[:3, :3] = np.asarray(rotation, dtype=float)
    return out


def rotated(assembly, rotation: Rotation | None):
    """``assembly`` with every part's mesh turned into the build frame (unchanged for None).

    Part ids, names, sources and groups are kept; ``assembly.frame`` records the rotation.
    """
    if rotation is None:
        return assembly
    t = transform(rotation)
    parts = tuple(replace(p, mesh=p.mesh.copy().apply_transform(t)) for p in assembly.parts)
    return replace(assembly, parts=parts, frame=rotation)


# --------------------------------------------------------------------------- candidates


@dataclass(frozen=True)
class Candidate:
    """A frame worth trying: the rotation and the part axis it makes vertical (or level).

    Attributes
    ----------
    rotation : Rotation
        ``x_build = R @ x_file``.
    direction : tuple of float
        The parts' common axis (file frame) that the rotation turns onto a coordinate axis.
    parts : tuple of str
        The parts sharing that axis.
    across, across_parts
        A second shared axis, across the first, that the rotation turns onto a coordinate
        axis as well (None: the smallest rotation turning the first).
    """

    rotation: Rotation
    direction: tuple[float, float, float]
    parts: tuple[str, ...]
    across: tuple[float, float, float] | None = None
    across_parts: tuple[str, ...] = ()

    @property
    def reason(self) -> str:
        out = f"{_listed(self.parts)} share the file's axis {_vector(self.direction)}"
        if self.across is not None:
            out += f", and {_listed(self.across_parts)} the axis {_vector(self.across)} across it"
        return out


def _listed(parts: tuple[str, ...]) -> str:
    shown = ", ".join(parts[:8]) + (", ..." if len(parts) > 8 else "")
    return f"{len(parts)} part(s) ({shown})"


def _vector(direction) -> str:
    return "(" + ", ".join(f"{round(x, 3) + 0.0:g}" for x in direction) + ")"


def part_axes(mesh) -> list[np.ndarray]:
    """The well-defined principal axes of a closed mesh (unit vectors, file frame): those
    whose moment of inertia stands apart from the other two (:data:`DISTINCT`)."""
    if not mesh.is_watertight or abs(float(mesh.volume)) <= 0:
        return []
    moments = np.asarray(mesh.principal_inertia_components, dtype=float)
    vectors = np.asarray(mesh.principal_inertia_vectors, dtype=float)
    scale = float(np.max(np.abs(moments)))
    if not scale > 0:
        return []
    out = []
    for k in range(3):
        others = [moments[j] for j in range(3) if j != k]
        if all(abs(moments[k] - m) > DISTINCT * scale for m in others):
            out.append(vectors[k] / np.linalg.norm(vectors[k]))
    return out


def off_axis_directions(assembly) -> list[tuple[np.ndarray, tuple[str, ...]]]:
    """The parts' well-defined axes that lie off every coordinate axis, clustered up to
    sign: ``(mean unit direction, the parts having it)``, the most shared first (then the
    order the parts come in)."""
    aligned = np.cos(np.radians(ALIGNED_DEG))
    close = np.cos(np.radians(CLUSTER_DEG))
    clusters: list[list] = []  # [sum of directions, parts]
    for part in assembly.parts:
        for v in part_axes(part.mesh):
            if np.max(np.abs(v)) >= aligned:
                continue
            for cluster in clusters:
                mean = cluster[0] / np.linalg.norm(cluster[0])
                dot = float(mean @ v)
                if abs(dot) >= close:
                    cluster[0] = cluster[0] + (v if dot > 0 else -v)
                    if part.id not in cluster[1]:
                        cluster[1].append(part.id)
                    break
            else:
                clusters.append([v.copy(), [part.id]])
    ranked = sorted(enumerate(clusters), key=lambda kc: (-len(kc[1][1]), kc[0]))
    return [(c[0] / np.linalg.norm(c[0]), tuple(c[1])) for _, c in ranked]


def onto_axis(direction) -> np.ndarray:
    """The smallest rotation turning ``direction`` onto its nearest coordinate axis
    (either sign), shape (3, 3)."""
    v = np.asarray(direction, dtype=float)
    v = v / np.linalg.norm(v)
    k = int(np.argmax(np.abs(v)))
    e = np.zeros(3)
    e[k] = 1.0 if v[k] > 0 else -1.0
    cross = np.cross(v, e)
    degrees = float(np.degrees(np.arctan2(np.linalg.norm(cross), float(v @ e))))
    if degrees < 1e-9:
        return np.eye(3)
    return rotation_matrix(cross, degrees)


def candidate_frames(
    assembly, limit: int = MAX_CANDIDATES, parts: Iterable[str] | None = None
) -> list[Candidate]:
    """At most ``limit`` frames turning a shared off-axis part axis onto the nearest
    coordinate axis, the axes shared by the most parts first (module docstring).

    For each such axis, when another shared axis lies across it (within
    :data:`SQUARE_DEG` of a right angle: a tilted plate's edge beside its normal), the frame
    turning that one onto a coordinate axis as well comes first, then the smallest
    rotation. ``parts``: only the axes some of these parts have (the parts that cannot go in
    in the file's frame).
    """
    found = off_axis_directions(assembly)
    if parts is not None:
        wanted = set(parts)
        found = [(d, ps) for d, ps in found if wanted & set(ps)]
    square = np.sin(np.radians(SQUARE_DEG))
    out: list[Candidate] = []
    for direction, members in found:
        first = onto_axis(direction)
        across = [(d, ps) for d, ps in found if abs(float(d @ direction)) <= square]
        ways = [(first, None)]
        if across:  # its image across the first axis, made exactly square to it
            e1 = first @ direction
            w = first @ across[0][0]
            ways.insert(0, (onto_axis(w - (w @ e1) * e1) @ first, across[0]))
        for rotation, second in ways:
            rotation = canonical(rotation)
            if rotation is None or any(np.allclose(rotation, c.rotation) for c in out):
                continue
            out.append(Candidate(rotation, _upwards(direction), members, *_second(second)))
            if len(out) >= limit:
                return out
    return out


def _upwards(direction) -> tuple[float, float, float]:
    """A direction signed so that its largest component is positive."""
    d = np.asarray(direction, dtype=float)
    sign = 1.0 if d[int(np.argmax(np.abs(d)))] > 0 else -1.0
    return tuple(float(x) for x in sign * d)


def _second(found) -> tuple:
    return () if found is None else (_upwards(found[0]), tuple(found[1]))


def interlocked(relations, first: str | None = None, directions=range(6)) -> list[tuple[str, str]]:
    """Pairs ``(i, j)`` that no sequence can assemble in this frame, with or without
    subassemblies: each blocks the other along every direction in ``directions``
    (``TT_d`` false both ways: whichever goes in second has no way in), or ``j`` is the
    part placed ``first`` (the base) and blocks ``i`` along every direction."""
    tt = np.asarray(relations.tt, dtype=bool)
    stuck = ~tt[:, :, list(directions)].any(axis=2)
    np.fill_diagonal(stuck, False)
    ids = [str(p) for p in relations.parts]
    pairs = np.triu(stuck & stuck.T)
    if first in ids:
        pairs[:, ids.index(first)] |= stuck[:, ids.index(first)]
        pairs[ids.index(first), :] = False
    i, j = np.nonzero(pairs)
    return [(ids[a], ids[b]) for a, b in zip(i.tolist(), j.tolist(), strict=True)]


__all__ = [
    "Candidate",
    "Rotation",
    "as_rotation",
    "axis_degrees",
    "candidate_frames",
    "canonical",
    "frame_record",
    "frame_text",
    "interlocked",
    "off_axis_directions",
    "onto_axis",
    "parse_frame",
    "part_axes",
    "rotated",
    "rotation_matrix",
    "transform",
]
