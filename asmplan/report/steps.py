"""The report's step pictures: the assembly growing along the principal line.

Each step that places parts is drawn from the part meshes (parts placed before it blue, the
step's own orange, the rest as faint outlines) by a camera that shows the part placed: it
looks from the side the part comes in from (``insert_along`` of the step's insertions in the
plan file: the camera stands on the ``free_along`` side, tilted off the axis so the picture
keeps its depth), centred on the new part and closer the smaller it is beside the whole
product. A red arrow for each insertion shows the way in, and the title names the parts by
their names (``Plastic case (PC)``), not by bare ids.

What is drawn is decided by :func:`step_view` (numbers only, tested on its own); the
drawing is matplotlib's ``mplot3d`` without pyplot, one figure reused for every step.
"""

from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass

import numpy as np

from asmplan.report.meshes import base_parts, part_meshes
from asmplan.report.png import data_uri, png_bytes

NEW, PLACED, GHOST = "#f28c28", "#4f81bd", "#cccccc"
ARROW = "#d62728"
PICTURE_FACES = 8_000
"""Faces drawn in one step picture, in all (the part meshes are thinned to it)."""
PART_FACES_MIN = 60
"""Faces a part keeps in a step picture however many parts share the budget."""
MAX_ZOOM = 3.0
"""The closest a step picture comes to a small part (times the whole product's view)."""
DIRECTIONS = {
    "+x": (1.0, 0.0, 0.0),
    "-x": (-1.0, 0.0, 0.0),
    "+y": (0.0, 1.0, 0.0),
    "-y": (0.0, -1.0, 0.0),
    "+z": (0.0, 0.0, 1.0),
    "-z": (0.0, 0.0, -1.0),
}
TILT = np.array([0.55, -0.75, 0.45])
"""Added to the camera's side so it never looks straight down an axis (a flat picture)."""
DEFAULT_VIEW = (22.0, -60.0)
"""(elevation, azimuth) in degrees of a step without a way in (the first part)."""


@dataclass(frozen=True)
class StepView:
    """How one step picture is taken.

    Attributes
    ----------
    elev, azim : float
        The camera's elevation and azimuth in degrees (matplotlib's ``view_init``).
    center : (3,) float
        The point the picture is centred on (the new parts' box centre).
    zoom : float
        Magnification against the whole product's view (1 to :data:`MAX_ZOOM`).
    arrows : list of ((3,) start, (3,) vector)
        One per insertion with a way in: the arrow ends at the part and points along
        ``insert_along``.
    ways : list of str
        The insertions' ``insert_along`` directions (``-z``), in order, None left out.
    """

    elev: float
    azim: float
    center: np.ndarray
    zoom: float
    arrows: list
    ways: list


def camera_angles(free_along: str | None) -> tuple[float, float]:
    """(elevation, azimuth) in degrees of a camera on the ``free_along`` side, tilted by
    :data:`TILT`; :data:`DEFAULT_VIEW` without a direction."""
    if free_along is None:
        return DEFAULT_VIEW
    side = np.asarray(DIRECTIONS[free_along])
    tilt = TILT - side * (TILT @ side)  # the part of the tilt across the side
    v = side + 0.9 * tilt / np.linalg.norm(tilt)
    v /= np.linalg.norm(v)
    return math.degrees(math.asin(v[2])), math.degrees(math.atan2(v[1], v[0]))


def step_view(step: dict, meshes: dict, lo: np.ndarray, hi: np.ndarray) -> StepView:
    """The camera and arrows of the picture of ``step`` (a line step of the plan file with
    ``parts`` and ``insertions``); ``meshes`` part id -> (vertices, faces), ``lo, hi`` the
    whole product's box."""
    new = [p for p in step.get("parts", []) if p in meshes]
    size = float(np.max(hi - lo)) or 1.0
    if not new:
        return StepView(*DEFAULT_VIEW, (lo + hi) / 2, 1.0, [], [])
    points = np.concatenate([meshes[p][0] for p in new])
    plo, phi = points.min(axis=0), points.max(axis=0)
    center = (plo + phi) / 2
    part = float(np.max(phi - plo)) or size
    zoom = float(np.clip(0.45 * size / part, 1.0, MAX_ZOOM))
    insertions = [i for i in step.get("insertions") or [] if i.get("insert_along")]
    arrows, ways = [], []
    for ins in insertions:
        body = [p for p in ins.get("parts", []) if p in meshes]
        if not body:
            continue
        v = np.concatenate([meshes[p][0] for p in body])
        blo, bhi = v.min(axis=0), v.max(axis=0)
        way = np.asarray(DIRECTIONS[ins["insert_along"]])
        length = 0.35 * size / zoom
        reach = float(np.abs(way) @ (bhi - blo)) / 2  # half the body along its way in
        tip = (blo + bhi) / 2 - way * (reach + 0.04 * size / zoom)
        arrows.append((tip - way * length, way * length))
        ways.append(ins["insert_along"])
    free = insertions[0].get("free_along") if insertions else None
    return StepView(*camera_angles(free), center, zoom, arrows, ways)


def part_label(part_id: str, names: dict[str, str]) -> str:
    """``Plastic case (PC)``: a part's name with its id, or the id alone when it has no
    other name."""
    name = (names.get(part_id) or "").strip()
    return f"{name} ({part_id})" if name and name != part_id else part_id


def step_title(step: dict, names: dict[str, str], ways: list[str]) -> str:
    """The picture's title: the operation, who does it, the parts by name and the ways in."""
    parts = ", ".join(part_label(p, names) for p in step["parts"])
    title = f"{step['operation']} by {step['agent']}: {parts}"
    if ways:
        title += " (in along\u00a0" + ", ".join(dict.fromkeys(ways)) + ")"
    return "\n".join(textwrap.wrap(title, 42, break_on_hyphens=False))


def assembly_steps(
    plan: dict, *, max_pictures: int = 40, max_faces: int = PICTURE_FACES
) -> list[tuple[dict, str]]:
    """The principal line's steps that place parts, each with its picture (a PNG data URI).

    The meshes are thinned to ``max_faces`` faces in all (shared out among the parts, at
    least :data:`PART_FACES_MIN` each), which keeps a picture of a 70-part product quick.
    """
    n_parts = max(1, len(plan.get("parts", [])))
    meshes = part_meshes(plan, max_faces=max(PART_FACES_MIN, max_faces // n_parts))
    if not meshes:
        return []
    from matplotlib.colors import to_rgba
    from matplotlib.figure import Figure
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    names = {p["id"]: p.get("name", "") for p in plan.get("parts", [])}
    ids = list(meshes)
    triangles = np.concatenate([v[f] for v, f in meshes.values()])  # (T, 3, 3)
    owner = np.repeat(np.arange(len(ids)), [len(f) for _, f in meshes.values()])  # (T,)
    colours = {
        "new": to_rgba(NEW, 1.0),
        "placed": to_rgba(PLACED, 1.0),
        "ghost": to_rgba(GHOST, 0.06),
    }
    everything = np.concatenate([v for v, _ in meshes.values()])
    lo, hi = everything.min(axis=0), everything.max(axis=0)
    half = (hi - lo) / 2 + 1e-9
    # one figure drawn again for each step: colours, camera, arrows and title change
    fig = Figure(figsize=(3.2, 3.1))
    fig.subplots_adjust(left=0.0, right=1.0, bottom=0.0, top=0.86)
    ax = fig.add_subplot(projection="3d")
    ax.computed_zorder = False  # the arrows stay in front of the parts
    poly = Poly3DCollection(triangles, edgecolor="none", zorder=1)
    ax.add_collection3d(poly)
    ax.set_axis_off()
    placed = set(base_parts(plan))
    out = []
    arrows = []
    for step in plan.get("robust_plan", []):
        if not step.get("parts") or len(out) >= max_pictures:
            continue
        new = set(step["parts"])
        kind = ["new" if p in new else "placed" if p in placed else "ghost" for p in ids]
        poly.set_facecolor(np.array([colours[k] for k in kind])[owner])
        view = step_view(step, meshes, lo, hi)
        ax.set_xlim(view.center[0] - half[0], view.center[0] + half[0])
        ax.set_ylim(view.center[1] - half[1], view.center[1] + half[1])
        ax.set_zlim(view.center[2] - half[2], view.center[2] + half[2])
        ax.set_box_aspect(2 * half, zoom=view.zoom)
        ax.view_init(elev=view.elev, azim=view.azim)
        for artist in arrows:
            artist.remove()
        arrows = [
            ax.quiver(
                *start,
                *vector,
                color=ARROW,
                linewidth=2.2,
                arrow_length_ratio=0.3,
                zorder=5,
            )
            for start, vector in view.arrows
        ]
        ax.set_title(step_title(step, names, view.ways), fontsize=9.5)
        out.append((step, _png(fig)))
        placed |= new
    return out


def _png(fig) -> str:
    """A matplotlib Figure as a ``data:image/png;base64,...`` URI."""
    return data_uri(png_bytes(fig, dpi=90))
