"""The part meshes of a plan, as plain arrays for the page's 3D view (plotly ``Mesh3d``).

The files are the ones the plan's assembly names (``parts[].file``, relative to the
assembly's folder), read once when the service starts; a request never names a file.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np


def plan_meshes(plan: dict, *, max_faces: int = 20_000) -> dict[str, dict]:
    """Part id -> ``{"x", "y", "z", "i", "j", "k", "name"}`` for every part with a mesh.

    Parts whose file is missing or unreadable are left out (the page draws what it has).
    Vertices are rounded to 0.01 of the file's unit to keep the JSON small.
    """
    import trimesh

    source = plan.get("source") or ""
    folder = Path(source).parent if source else None
    out: dict[str, dict] = {}
    for part in plan.get("parts", []):
        file = part.get("file")
        if not file or folder is None:
            continue
        path = folder / file
        if not path.is_file():
            continue
        try:
            mesh = trimesh.load(path, force="mesh")
        except (ValueError, OSError):
            continue
        faces = np.asarray(mesh.faces)[:max_faces]
        v = np.round(np.asarray(mesh.vertices, dtype=np.float64), 2)
        out[part["id"]] = {
            "name": part.get("name", ""),
            "x": v[:, 0].tolist(),
            "y": v[:, 1].tolist(),
            "z": v[:, 2].tolist(),
            "i": faces[:, 0].tolist(),
            "j": faces[:, 1].tolist(),
            "k": faces[:, 2].tolist(),
        }
    return out


def base_parts(plan: dict) -> list[str]:
    """Parts no operation places: in place from the start (the base part on its fixture)."""
    placed = {p for op in plan.get("operations", {}).values() for p in op.get("parts", [])}
    return [p["id"] for p in plan.get("parts", []) if p["id"] not in placed]
