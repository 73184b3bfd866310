"""Realistic assemblies built in code, as CAD exports them (sizes in mm).

Each builder returns ``{part id: trimesh.Trimesh}`` in assembled pose and takes ``detail``,
a multiplier on the number of segments of every curve (1 for the tests, larger for the
benchmark's heavy parts). They carry what real exports carry:

- :func:`finger_box`: a laser-cut box of 6 mm panels, cut with kerf compensation, so
  every finger and tab interferes with its neighbour by 0.2 mm;
- :func:`bearing_stack`: shaft, inner ring, outer ring, housing and a retaining collar,
  concentric and drawn at the same diameters (zero clearance), each circle with another
  number of segments;
- :func:`bolted_bracket`: base plate, L-bracket, two bolts with hex heads, washers and
  nuts, shafts drawn at the hole diameter;
- :func:`gear_pair`: two involute spur gears meshing with 0.25 mm of extra tooth thickness
  (negative backlash), on shafts standing in blind holes of a base plate.
"""

from __future__ import annotations

import manifold3d
import numpy as np
import trimesh

KERF = 0.2
"""Interference of the finger-jointed box's fingers and tabs (mm)."""


def box(lo, hi) -> trimesh.Trimesh:
    """Axis-aligned box from corner ``lo`` to corner ``hi``."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    mesh = trimesh.creation.box(extents=hi - lo)
    return mesh.apply_translation((lo + hi) / 2)


def cylinder(radius, z0, z1, sections, xy=(0.0, 0.0)) -> trimesh.Trimesh:
    """Cylinder along z from ``z0`` to ``z1`` around ``xy`` (a ``sections``-gon)."""
    mesh = trimesh.creation.cylinder(radius=radius, height=z1 - z0, sections=int(sections))
    return mesh.apply_translation((xy[0], xy[1], (z0 + z1) / 2))


def union(*meshes: trimesh.Trimesh) -> trimesh.Trimesh:
    return trimesh.boolean.union(list(meshes), engine="manifold")


def difference(a: trimesh.Trimesh, *cutters: trimesh.Trimesh) -> trimesh.Trimesh:
    return trimesh.boolean.difference([a, *cutters], engine="manifold")


def annulus(r_in, r_out, z0, z1, n_in, n_out, xy=(0.0, 0.0)) -> trimesh.Trimesh:
    """Ring along z; inner and outer circles with their own segment counts."""
    return difference(cylinder(r_out, z0, z1, n_out, xy), cylinder(r_in, z0 - 1, z1 + 1, n_in, xy))


def extrude(
    contours: list[np.ndarray], z0: float, z1: float, twist: float = 0.0
) -> trimesh.Trimesh:
    """Extrude closed 2-D contours (outer CCW, holes CW) from ``z0`` to ``z1``, the top
    section turned by ``twist`` radians about the z axis (a helical gear's helix)."""
    section = manifold3d.CrossSection([np.asarray(c, dtype=float) for c in contours])
    turned = {"n_divisions": 12, "twist_degrees": float(np.degrees(twist))} if twist else {}
    solid = manifold3d.Manifold.extrude(section, z1 - z0, **turned).translate((0.0, 0.0, z0))
    mesh = solid.to_mesh()
    return trimesh.Trimesh(
        vertices=np.asarray(mesh.vert_properties)[:, :3], faces=np.asarray(mesh.tri_verts)
    )


def revolve(profile, sections: int) -> trimesh.Trimesh:
    """Solid of revolution about z of a closed ``(r, z)`` profile (CCW), a ``sections``-gon."""
    outline = manifold3d.CrossSection([np.asarray(profile, dtype=float)])
    mesh = manifold3d.Manifold.revolve(outline, circular_segments=int(sections)).to_mesh()
    return trimesh.Trimesh(
        vertices=np.asarray(mesh.vert_properties)[:, :3], faces=np.asarray(mesh.tri_verts)
    )


def unmerged(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """``mesh`` as STEP and 3DXML exports tessellate it: no vertex shared between faces
    (here every triangle has its own three), so as read it is not watertight and a
    vertex-normal erosion would leave every edge where it was."""
    corners = np.asarray(mesh.triangles, dtype=float).reshape(-1, 3)
    return trimesh.Trimesh(corners, np.arange(len(corners)).reshape(-1, 3), process=False)


def _seg(n: float, detail: float) -> int:
    return max(3, int(round(n * detail)))


# --------------------------------------------------------------------------- finger box

BOX_L, BOX_W, BOX_H, PANEL = 120.0, 80.0, 60.0, 6.0
FINGERS = 5  # vertical segments per corner, odd: front/back own the even ones


def _corner_fingers(x0: float, y0: float, own_even: bool) -> list[trimesh.Trimesh]:
    """Fingers in the corner column ``[x0, x0+t] x [y0, y0+t]`` between bottom and lid,
    widened by KERF / 2 at every interior end (so mating fingers overlap by KERF)."""
    edges = np.linspace(PANEL, BOX_H, FINGERS + 1)
    out = []
    for k in range(FINGERS):
        if (k % 2 == 0) != own_even:
            continue
        z0 = edges[k] - (KERF / 2 if k > 0 else 0.0)
        z1 = edges[k + 1] + (KERF / 2 if k < FINGERS - 1 else 0.0)
        out.append(box((x0, y0, z0), (x0 + PANEL, y0 + PANEL, z1)))
    return out


def _tab_x(y0: float, z0: float, half: float) -> trimesh.Trimesh:
    """Tab of a front/back wall (centred on x), KERF wider on each side than its notch."""
    c = BOX_L / 2
    return box((c - half - KERF, y0, z0), (c + half + KERF, y0 + PANEL, z0 + PANEL))


def _tab_y(x0: float, z0: float, half: float) -> trimesh.Trimesh:
    c = BOX_W / 2
    return box((x0, c - half - KERF, z0), (x0 + PANEL, c + half + KERF, z0 + PANEL))


def _panel_with_notches(z0: float) -> trimesh.Trimesh:
    """Bottom (``z0 = 0``) or lid panel with an edge notch for each wall's tab."""
    plate = box((0, 0, z0), (BOX_L, BOX_W, z0 + PANEL))
    cx, cy, lo, hi = BOX_L / 2, BOX_W / 2, z0 - 1, z0 + PANEL + 1
    notches = [
        box((cx - 20, -1, lo), (cx + 20, PANEL, hi)),
        box((cx - 20, BOX_W - PANEL, lo), (cx + 20, BOX_W + 1, hi)),
        box((-1, cy - 15, lo), (PANEL, cy + 15, hi)),
        box((BOX_L - PANEL, cy - 15, lo), (BOX_L + 1, cy + 15, hi)),
    ]
    return difference(plate, *notches)


def finger_box(detail: float = 1.0) -> dict[str, trimesh.Trimesh]:
    """Bottom, four walls and lid; walls finger-jointed at the corners and tabbed into
    edge notches of bottom and lid; every joint interferes by :data:`KERF`."""
    del detail  # flat panels: nothing to tessellate
    t, top = PANEL, BOX_H
    walls = {}
    for name, y0 in (("front", 0.0), ("back", BOX_W - t)):
        body = box((t, y0, t), (BOX_L - t, y0 + t, top))
        walls[name] = union(
            body,
            *_corner_fingers(0.0, y0, True),
            *_corner_fingers(BOX_L - t, y0, True),
            _tab_x(y0, 0.0, 20),
            _tab_x(y0, top, 20),
        )
    for name, x0 in (("left", 0.0), ("right", BOX_L - t)):
        body = box((x0, t, t), (x0 + t, BOX_W - t, top))
        walls[name] = union(
            body,
            *_corner_fingers(x0, 0.0, False),
            *_corner_fingers(x0, BOX_W - t, False),
            _tab_y(x0, 0.0, 15),
            _tab_y(x0, top, 15),
        )
    return {"bottom": _panel_with_notches(0.0), **walls, "lid": _panel_with_notches(top)}


# ------------------------------------------------------------------------ bearing stack


def bearing_stack(detail: float = 1.0) -> dict[str, trimesh.Trimesh]:
    """Shaft (r 10) through an inner ring (10-15) and outer ring (15-22) seated on the
    shoulder of a housing bore (22 above z=8, 17 below), a collar (10-14) on the inner
    ring. Every shared diameter is drawn twice with different segment counts."""
    s = lambda n: _seg(n, detail)  # noqa: E731
    housing = difference(
        box((-40, -40, 0), (40, 40, 30)),
        cylinder(22, 8, 31, s(72)),
        cylinder(17, -1, 9, s(48)),
    )
    return {
        "shaft": cylinder(10, -20, 60, s(96)),
        "inner_ring": annulus(10, 15, 8, 20, s(64), s(80)),
        "outer_ring": annulus(15, 22, 8, 20, s(128), s(100)),
        "housing": housing,
        "collar": annulus(10, 14, 20, 23, s(40), s(60)),
    }


# ---------------------------------------------------------------------- bolted bracket

BOLT_R, HEAD_R, BOLT_XS = 4.0, 7.5, (-25.0, 25.0)


def bolted_bracket(detail: float = 1.0) -> dict[str, trimesh.Trimesh]:
    """Base plate (top at z=0), L-bracket on it (6 mm flanges), two M8 bolts through both
    with hex heads on washers, washers and hex nuts underneath."""
    s = lambda n: _seg(n, detail)  # noqa: E731
    base = difference(
        box((-50, -30, -10), (50, 30, 0)),
        *(cylinder(BOLT_R, -11, 1, s(48), (x, 0)) for x in BOLT_XS),
    )
    bracket = difference(
        union(box((-40, -25, 0), (40, 25, 6)), box((-40, 19, 0), (40, 25, 60))),
        *(cylinder(BOLT_R, -1, 7, s(40), (x, 0)) for x in BOLT_XS),
        *(
            cylinder(3, -1, 1, s(36))
            .apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, (1, 0, 0)))
            .apply_translation((x, 22, 40))
            for x in BOLT_XS
        ),
    )
    parts = {"base": base, "bracket": bracket}
    for k, x in enumerate(BOLT_XS, start=1):
        parts[f"bolt_{k}"] = union(
            cylinder(BOLT_R, -20, 7.6, s(32), (x, 0)), cylinder(HEAD_R, 7.6, 12.9, 6, (x, 0))
        )
        parts[f"washer_{k}"] = annulus(BOLT_R, 8, 6, 7.6, s(36), s(64), (x, 0))
        parts[f"washer_{k}b"] = annulus(BOLT_R, 8, -11.6, -10, s(36), s(64), (x, 0))
        parts[f"nut_{k}"] = annulus(BOLT_R, HEAD_R, -18.1, -11.6, s(24), 6, (x, 0))
    return parts


# ---------------------------------------------------------------------------- gear pair

MODULE, TEETH_A, TEETH_B, PRESSURE = 2.0, 20, 30, np.radians(20.0)
GEAR_INTERFERENCE = 0.25
"""Extra tooth thickness at the pitch circle (mm): the teeth overlap by about this."""


def _inv(angle):
    return np.tan(angle) - angle


def gear_outline(
    teeth: int,
    flank_points: int,
    phase: float = 0.0,
    interference: float = GEAR_INTERFERENCE,
    addendum: float = 1.0,
    dedendum: float = 1.25,
) -> np.ndarray:
    """CCW outline of an involute spur gear (module :data:`MODULE`, 20 degrees, root
    clearance 0.25 m) with tooth thickness ``pi m / 2 + interference`` at the pitch
    circle (negative: backlash); a tooth is centred at angle ``phase``. ``addendum`` and
    ``dedendum`` in modules (a cutter for a ring gear: 1.25 and 1.0)."""
    r = MODULE * teeth / 2
    rb, ra, rf = r * np.cos(PRESSURE), r + addendum * MODULE, r - dedendum * MODULE
    half_pitch = (np.pi * MODULE / 2 + interference) / (2 * r)  # half tooth angle at r
    radii = np.linspace(max(rb, rf), ra, flank_points)
    half = half_pitch + _inv(PRESSURE) - _inv(np.arccos(np.clip(rb / radii, -1, 1)))
    if rf < rb:  # radial flank below the base circle
        radii = np.concatenate([[rf], radii])
        half = np.concatenate([[half[0]], half])
    step = 2 * np.pi / teeth
    tip = max(2, flank_points // 4)
    points = []
    for k in range(teeth):
        c = phase + k * step
        rising = np.stack([radii, c - half], axis=1)  # root -> tip on the leading flank
        tip_arc = np.stack([np.full(tip, ra), np.linspace(c - half[-1], c + half[-1], tip)], 1)
        falling = np.stack([radii[::-1], c + half[::-1]], axis=1)
        gap_start, gap_end = c + half[0], c + step - half[0]
        root = np.stack([np.full(tip, rf), np.linspace(gap_start, gap_end, tip + 2)[1:-1]], 1)
        points.append(np.concatenate([rising, tip_arc[1:-1], falling, root]))
    polar = np.concatenate(points)
    return np.stack([polar[:, 0] * np.cos(polar[:, 1]), polar[:, 0] * np.sin(polar[:, 1])], 1)


def _gear(teeth, center, phase, flank_points, bore_sections) -> trimesh.Trimesh:
    outline = gear_outline(teeth, flank_points, phase) + np.asarray(center)
    angles = np.linspace(0, 2 * np.pi, bore_sections, endpoint=False)[::-1]  # CW hole
    bore = np.stack([5 * np.cos(angles), 5 * np.sin(angles)], 1) + np.asarray(center)
    return extrude([outline, bore], 0.0, 10.0)


def gear_pair(detail: float = 1.0) -> dict[str, trimesh.Trimesh]:
    """Gear ``gear_a`` (20 teeth, axis at the origin) meshing with ``gear_b`` (30 teeth,
    axis at x = 50) in z 0..10, on shafts (r 5, z -6..25) in blind holes of a base plate
    (top z = -2); a tooth of gear_a points at gear_b."""
    s = lambda n: _seg(n, detail)  # noqa: E731
    center_b = (MODULE * (TEETH_A + TEETH_B) / 2, 0.0)
    plate = difference(
        box((-30, -40, -12), (85, 40, -2)),
        cylinder(5, -6, 0, s(40)),
        cylinder(5, -6, 0, s(40), center_b),
    )
    return {
        "plate": plate,
        "shaft_a": cylinder(5, -6, 25, s(48)),
        "shaft_b": cylinder(5, -6, 25, s(56), center_b),
        "gear_a": _gear(TEETH_A, (0.0, 0.0), 0.0, s(8), s(36)),
        "gear_b": _gear(TEETH_B, center_b, np.pi + np.pi / TEETH_B, s(8), s(44)),
    }


BUILDERS = {
    "finger_box": finger_box,
    "bearing_stack": bearing_stack,
    "bolted_bracket": bolted_bracket,
    "gear_pair": gear_pair,
}


def die_set(
    detail: float = 1.0, stripper: bool = True, corners: int = 2
) -> dict[str, trimesh.Trimesh]:
    """A shear die set (mm, z up, drawn open) built as a toolmaker builds one.

    Lower half: a bottom plate with two guide pins standing in blind holes (press fit,
    0.05 mm), a die block on it fixed by two screws from above (heads in counterbores).
    Upper half: a top plate with two flanged guide bushings pressed in from below (flange
    under the plate), a punch holder under it fixed by two screws from below (heads in the
    holder's counterbores, threads in blind holes of the top plate), the punch hanging in
    the holder by its head and, with ``stripper``, a stripper plate around the punch
    hanging on two stripper bolts driven up into the holder. ``corners=4``: four guide pins
    and bushings, four screws in each half (as most die sets). Right side up every bushing
    and screw of the upper half falls out; upside down (top plate on the bench) each rests
    on what is already there. The upper half slides down the guide pins and, drawn open,
    rests on nothing of the lower half.
    """
    n = max(1, round(detail))
    pins, screws = [(-80.0, -55.0), (80.0, 55.0)], [(-35.0, -28.0), (35.0, 28.0)]
    tops, bolts = [(-35.0, 28.0), (35.0, -28.0)], [(0.0, 30.0), (0.0, -30.0)]
    if corners == 4:
        signs = [(-1, -1), (1, 1), (-1, 1), (1, -1)]
        pins = [(80.0 * a, 55.0 * b) for a, b in signs]
        screws = [(35.0 * a, 28.0 * b) for a, b in signs]
        tops = [(38.0 * a, 22.0 * b) for a, b in signs]
    parts = {
        "bottom_plate": difference(
            box((-100, -75, 0), (100, 75, 20)),
            *(cylinder(8, 6, 21, 48 * n, xy) for xy in pins),
            *(cylinder(4, 5, 21, 32 * n, xy) for xy in screws),
        ),
        "die_block": difference(
            box((-50, -40, 20), (50, 40, 45)),
            box((-20, -10, 19), (20, 10, 46)),
            *(cylinder(4, 19, 46, 32 * n, xy) for xy in screws),
            *(cylinder(6.5, 37, 46, 40 * n, xy) for xy in screws),
        ),
        "top_plate": difference(
            box((-100, -75, 130), (100, 75, 150)),
            *(cylinder(11, 129, 151, 56 * n, xy) for xy in pins),
            *(cylinder(4, 129, 142, 32 * n, xy) for xy in tops),
        ),
        "punch_holder": difference(
            box((-50, -40, 115), (50, 40, 130)),
            box((-20, -10, 114), (20, 10, 131)),
            box((-24, -14, 126), (24, 14, 131)),  # pocket of the punch head
            *(cylinder(4, 114, 131, 32 * n, xy) for xy in tops),
            *(cylinder(6.5, 114, 120, 40 * n, xy) for xy in tops),
            *(cylinder(3, 114, 131, 28 * n, xy) for xy in bolts),
        ),
        "punch": union(box((-20, -10, 50), (20, 10, 130)), box((-24, -14, 126), (24, 14, 130))),
    }
    for k, xy in enumerate(pins, 1):
        parts[f"guide_pin_{k}"] = cylinder(8.05, 6, 120, 40 * n, xy)
        parts[f"bushing_{k}"] = union(
            annulus(8, 11, 100, 150, 40 * n, 56 * n, xy),
            annulus(8, 13, 127, 130, 40 * n, 64 * n, xy),
        )
    for k, (xy, up) in enumerate(zip(screws, tops, strict=True), 1):
        parts[f"screw_{k}"] = union(
            cylinder(4, 8, 37, 24 * n, xy), cylinder(6.5, 37, 45, 40 * n, xy)
        )
        xy = up
        parts[f"top_screw_{k}"] = union(
            cylinder(4, 120, 142, 24 * n, xy), cylinder(6.5, 115, 120, 40 * n, xy)
        )
    if stripper:
        parts["stripper_plate"] = difference(
            box((-50, -40, 55), (50, 40, 65)),
            box((-20, -10, 54), (20, 10, 66)),
            *(cylinder(3, 54, 66, 28 * n, xy) for xy in bolts),
            *(cylinder(5, 54, 58, 36 * n, xy) for xy in bolts),
        )
        for k, xy in enumerate(bolts, 1):
            parts[f"stripper_bolt_{k}"] = union(
                cylinder(3, 58, 128, 24 * n, xy), cylinder(5, 54, 58, 36 * n, xy)
            )
    return parts


def tilted_pins(
    axis=(1.0, 1.0, 0.0), degrees: float = 25.0, detail: float = 1.0, upright: bool = False
) -> dict[str, trimesh.Trimesh]:
    """A plate pinned onto the slanted face of a base, drawn with the base level (mm).

    Built upright first: a base block whose top face carries two blind holes, a plate
    lying on it with two through holes, and two pins (0.05 mm clearance) through the
    plate standing on the holes' bottoms. The base's underside is cut level with the
    file's ``xy`` plane, and everything is turned by ``degrees`` about ``axis`` (as a
    product fixtured in its own orientation is drawn): the plate then lies on a slanted
    face and the pins stand at ``degrees`` off ``z``, along ``R @ (0, 0, 1)``. ``upright``:
    the same product before that turn (pins along ``z``, the base's underside slanted).
    """
    from cad.frame import rotation_matrix

    n = max(1, round(detail))
    turn = np.eye(4)
    turn[:3, :3] = rotation_matrix(axis, degrees)
    level = np.linalg.inv(turn)  # the file's level underside, seen upright
    holes = [(-12.0, 0.0), (12.0, 0.0)]
    block = difference(
        box((-60, -60, -80), (60, 60, 0)), *(cylinder(2.05, -8, 1, 32 * n, xy) for xy in holes)
    )
    underside = box((-25, -25, -30), (25, 25, 200)).apply_transform(level)
    parts = {
        "base": trimesh.boolean.intersection([block, underside], engine="manifold"),
        "plate": difference(
            box((-20, -15, 0), (20, 15, 5)), *(cylinder(2.05, -1, 6, 32 * n, xy) for xy in holes)
        ),
    }
    for k, xy in enumerate(holes, 1):
        parts[f"pin_{k}"] = cylinder(2.0, -8, 8, 24 * n, xy)
    return parts if upright else {pid: m.apply_transform(turn) for pid, m in parts.items()}
