"""The part meshes of a plan as plain arrays for the page's 3D view (plotly ``Mesh3d``).

Read once per plan (:func:`asmplan.report.meshes.part_meshes`); a request never names a file.
"""

from __future__ import annotations

import numpy as np

from asmplan.report.meshes import base_parts, part_meshes

__all__ = ["base_parts", "plan_meshes"]


def plan_meshes(plan: dict, *, max_faces: int = 20_000) -> dict[str, dict]:
    """Part id -> ``{"x", "y", "z", "i", "j", "k", "name"}`` for every part with a mesh.

    Vertices are in mm in the build frame, rounded to 0.01 mm to keep the JSON small; a
    part of more than ``max_faces`` faces is thinned to that many
    (:func:`asmplan.report.meshes.clustered`).
    """
    names = {p["id"]: p.get("name", "") for p in plan.get("parts", [])}
    out: dict[str, dict] = {}
    for pid, (vertices, faces) in part_meshes(plan, max_faces=max_faces).items():
        v = np.round(vertices, 2)
        f = faces
        out[pid] = {
            "name": names.get(pid, ""),
            "x": v[:, 0].tolist(),
            "y": v[:, 1].tolist(),
            "z": v[:, 2].tolist(),
            "i": f[:, 0].tolist(),
            "j": f[:, 1].tolist(),
            "k": f[:, 2].tolist(),
        }
    return out
