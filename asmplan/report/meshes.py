"""The part meshes a plan names (for the report's step pictures and the page's 3D view).

Each part is read from where ``plan.json`` says it came from: ``parts[].source`` (``path``
of the mesh or scene file, ``node`` inside a scene file, ``scale`` in millimetres per
coordinate as trimesh reads the file), so a folder of part meshes, a STEP/glTF/3DXML scene
and a spec's own files are all found. Plans written before ``source`` was recorded fall
back to ``parts[].file`` relative to the plan's ``source`` folder. A part whose file is
missing or unreadable is left out. Meshes are turned into the build frame
(``geometry.build_rotation``: gravity is down) and can be thinned to a face budget
(:func:`clustered`) so that pictures of 70-part products stay quick to draw.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from asmplan.planfile import source_folder, split_file


def part_meshes(
    plan: dict, *, max_faces: int | None = None
) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Part id -> ``(vertices (V, 3) float64 in mm, faces (F, 3) int64)``, build frame.

    Parameters
    ----------
    plan : dict
        A ``plan.json`` document.
    max_faces : int, optional
        At most this many faces per part (:func:`clustered`); None keeps every face.
    """
    from cad.scene import read_scene

    turn = (plan.get("geometry") or {}).get("build_rotation")
    rotation = np.eye(3) if turn is None else np.asarray(turn, dtype=np.float64)
    default_scale = float((plan.get("geometry") or {}).get("scale") or 1.0)
    out: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    for part in plan.get("parts", []):
        where = _where(plan, part)
        if where is None:
            continue
        path, node, scale = where
        try:
            scene = read_scene(path)
        except (ValueError, OSError):
            continue
        if node:
            k = scene.find(node)
            if k is None:
                continue
            meshes = [scene.meshes[k]]
        else:
            meshes = list(scene.meshes)
        if not meshes:
            continue
        vertices, faces = _joined(meshes)
        vertices = vertices * ((scale or default_scale) / scene.rescale) @ rotation.T
        if max_faces is not None:
            vertices, faces = clustered(vertices, faces, max_faces)
        out[part["id"]] = (vertices, faces)
    return out


def _where(plan: dict, part: dict) -> tuple[Path, str | None, float | None] | None:
    """``(file, node in it, mm per coordinate)`` of one part, or None if it has no file."""
    source = part.get("source")
    if isinstance(source, dict) and source.get("path"):
        path = Path(source["path"])
        if path.is_file():
            return path, source.get("node"), source.get("scale")
    file = part.get("file")
    top = plan.get("source") or ""
    if not file or not top:
        return None
    name, node = split_file(str(file))
    path = source_folder(top) / name
    return (path, node or None, None) if path.is_file() else None


def _joined(meshes: list) -> tuple[np.ndarray, np.ndarray]:
    """One vertex and face array of several meshes."""
    vertices, faces, offset = [], [], 0
    for mesh in meshes:
        vertices.append(np.asarray(mesh.vertices, dtype=np.float64))
        faces.append(np.asarray(mesh.faces, dtype=np.int64) + offset)
        offset += len(mesh.vertices)
    return np.concatenate(vertices), np.concatenate(faces)


def clustered(
    vertices: np.ndarray, faces: np.ndarray, max_faces: int
) -> tuple[np.ndarray, np.ndarray]:
    """A mesh thinned to at most ``max_faces`` faces by vertex clustering.

    Vertices are snapped to a grid (as many cells along each side: 64, then fewer), each
    cell's vertices merged into their mean, and faces that collapse dropped: the outline
    of the part stays, its fine detail goes. A budget too small for any grid keeps every
    n-th face of the finest grid. Quick (numpy only) and good enough for a
    picture; never used for geometry.

    Parameters
    ----------
    vertices : (V, 3) float
    faces : (F, 3) int
    max_faces : int
        At least 1.

    Returns
    -------
    vertices (V', 3) float64, faces (F', 3) int64
        The mesh unchanged when it has at most ``max_faces`` faces.
    """
    if max_faces < 1:
        raise ValueError(f"max_faces must be at least 1, got {max_faces}")
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    if len(faces) <= max_faces:
        return vertices, faces
    lo = vertices.min(axis=0)
    size = np.maximum(vertices.max(axis=0) - lo, 1e-12)  # (3,): a thin side keeps its cells
    cells = 64
    finest = vertices, faces
    while True:
        cell = np.minimum(np.floor((vertices - lo) / (size / cells)).astype(np.int64), cells)
        key = (cell[:, 0] * (cells + 1) + cell[:, 1]) * (cells + 1) + cell[:, 2]  # (V,)
        _, inverse, counts = np.unique(key, return_inverse=True, return_counts=True)
        merged = np.zeros((len(counts), 3))
        np.add.at(merged, inverse, vertices)
        merged /= counts[:, None]
        f = inverse[faces]
        f = f[(f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2])]
        ordered = np.sort(f, axis=1)
        n = len(counts)
        _, first = np.unique(
            (ordered[:, 0] * n + ordered[:, 1]) * n + ordered[:, 2], return_index=True
        )
        f = f[np.sort(first)]
        if 0 < len(f) <= max_faces:
            return merged, f
        if len(f) == 0 or cells <= 2:  # too coarse: every n-th face of the finest so far
            merged, f = finest if len(f) == 0 else (merged, f)
            return merged, f[:: -(-len(f) // max_faces)]
        finest = merged, f
        cells = max(2, int(cells * 0.7))


def base_parts(plan: dict) -> list[str]:
    """Parts no operation places: in place from the start (the base part on its fixture)."""
    placed = {p for op in plan.get("operations", {}).values() for p in op.get("parts", [])}
    return [p["id"] for p in plan.get("parts", []) if p["id"] not in placed]
