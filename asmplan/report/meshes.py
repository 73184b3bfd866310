"""The part meshes a plan names, read from the assembly's folder (for the pictures and the page).

The files are the ones the plan's assembly lists (``parts[].file``, relative to the folder
of ``source``); a part whose file is missing or unreadable is left out.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np


def part_meshes(plan: dict) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Part id -> ``(vertices (V, 3) float64, faces (F, 3) int64)`` for every readable mesh,
    turned into the plan's build frame (``geometry.build_rotation``: gravity is down)."""
    import trimesh

    source = plan.get("source") or ""
    folder = Path(source).parent if source else None
    out: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    turn = (plan.get("geometry") or {}).get("build_rotation")
    rotation = np.eye(3) if turn is None else np.asarray(turn, dtype=np.float64)
    for part in plan.get("parts", []):
        file = part.get("file")
        if not file or folder is None or not (folder / file).is_file():
            continue
        try:
            mesh = trimesh.load(folder / file, force="mesh")
        except (ValueError, OSError):
            continue
        out[part["id"]] = (
            np.asarray(mesh.vertices, dtype=np.float64) @ rotation.T,
            np.asarray(mesh.faces, dtype=np.int64),
        )
    return out


def base_parts(plan: dict) -> list[str]:
    """Parts no operation places: in place from the start (the base part on its fixture)."""
    placed = {p for op in plan.get("operations", {}).values() for p in op.get("parts", [])}
    return [p["id"] for p in plan.get("parts", []) if p["id"] not in placed]
