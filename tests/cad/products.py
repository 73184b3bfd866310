"""Products of the kinds the planner meets in real CAD, built in code (sizes in mm).

- :func:`ballpoint_pen`: barrel, refill, a helical spring, end plug, cap and clip, coaxial
  along z with the tip down (``axis="x"``: lying along x);
- :func:`gearbox`: a housing with two shafts standing in blind bores, two spur gears on the
  shafts' collars meshing with ``backlash`` (negative: the teeth overlap), a lid over the
  shafts' ends;
- :func:`helical_pair`: two helical gears of opposite hands meshing on shafts standing in a
  plate (the teeth of each block the other along the shafts);
- :func:`planetary_stage`: a sun on its shaft, three identical planets on pins pressed into
  the base, a ring gear around them and a carrier plate over the planets;
- :func:`shear_mold`: a die set of a lower shoe with press-fitted guide pins and dowels in
  blind holes, a die plate on the dowels, a punch in the die opening (0.05 mm per side),
  an upper shoe with guide bushings pressed in, sliding on the pins.
"""

from __future__ import annotations

import numpy as np
import trimesh

from tests.cad.real_shapes import (
    MODULE,
    annulus,
    box,
    cylinder,
    difference,
    extrude,
    gear_outline,
    revolve,
    union,
)


def helix_spring(
    r_coil: float, r_wire: float, z0: float, z1: float, turns: float, sections: int = 24
) -> trimesh.Trimesh:
    """A closed coil spring along z: wire of radius ``r_wire`` on a helix of radius ``r_coil``
    from ``z0`` to ``z1`` (outside of the wire), ``sections`` segments per turn."""
    n, around = int(turns * sections) + 1, 8
    t = np.linspace(0.0, 2 * np.pi * turns, n)
    height = np.linspace(z0 + r_wire, z1 - r_wire, n)
    path = np.stack([r_coil * np.cos(t), r_coil * np.sin(t), height], 1)
    tangent = np.gradient(path, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    radial = np.stack([np.cos(t), np.sin(t), np.zeros_like(t)], 1)
    binormal = np.cross(tangent, radial)
    a = np.linspace(0.0, 2 * np.pi, around, endpoint=False)[None, :, None]
    rings = path[:, None] + r_wire * (np.cos(a) * radial[:, None] + np.sin(a) * binormal[:, None])
    i, j = np.meshgrid(np.arange(n - 1), np.arange(around), indexing="ij")
    a0, a1 = i * around + j, i * around + (j + 1) % around
    b0, b1 = a0 + around, a1 + around
    faces = np.concatenate(
        [np.stack([a0, b0, b1], -1).reshape(-1, 3), np.stack([a0, b1, a1], -1).reshape(-1, 3)]
    )
    ring = np.arange(around)
    start, end = n * around, n * around + 1
    caps = np.concatenate(
        [
            np.stack([np.full(around, start), (ring + 1) % around, ring], 1),
            np.stack([np.full(around, end), (n - 1) * around + ring,
                      (n - 1) * around + (ring + 1) % around], 1),
        ]
    )  # fmt: skip
    vertices = np.vstack([rings.reshape(-1, 3), path[0], path[-1]])
    mesh = trimesh.Trimesh(vertices, np.concatenate([faces, caps]))
    if mesh.volume < 0:
        mesh.invert()
    return mesh


def ballpoint_pen(axis: str = "z") -> dict[str, trimesh.Trimesh]:
    """A capped ballpoint pen, tip down along z (or lying along x)."""
    parts = {
        "barrel": revolve(
            [(1.1, 0), (1.6, 0), (4.5, 12), (4.5, 120), (2.0, 120), (2.0, 8), (1.1, 8)], 48
        ),
        "refill": revolve(
            [(0, -1.5), (0.6, -1.5), (1.0, -0.8), (1.0, 10), (1.9, 10), (1.9, 115), (0, 115)], 32
        ),
        "spring": helix_spring(1.45, 0.2, 8.0, 10.0, 3),  # between the barrel's step and the
        # refill's shoulder
        "plug": revolve([(0, 115), (2.0, 115), (2.0, 120), (4.5, 120), (4.3, 123), (0, 123)], 40),
        "cap": revolve(
            [
                (0, -5),
                (5.5, -5),
                (5.5, 38),
                (5.0, 38),
                (5.0, 40),
                (4.5, 40),
                (4.5, 12),
                (1.6, 0),
                (1.6, -4),
                (0, -4),
            ],
            56,
        ),  # fmt: skip
        "clip": union(annulus(5.0, 5.8, 38, 40, 56, 48), box((5.5, -1.5, 14), (6.4, 1.5, 40))),
    }
    if axis == "x":
        turn = trimesh.transformations.rotation_matrix(np.pi / 2, (0, 1, 0))
        parts = {k: v.apply_transform(turn) for k, v in parts.items()}
    return parts


def _spur_gear(teeth: int, center, phase: float, backlash: float) -> trimesh.Trimesh:
    outline = gear_outline(teeth, 8, phase, interference=-backlash) + np.asarray(center)
    angles = np.linspace(0, 2 * np.pi, 40, endpoint=False)[::-1]  # CW hole
    bore = np.stack([6.0 * np.cos(angles), 6.0 * np.sin(angles)], 1) + np.asarray(center)
    return extrude([outline, bore], 6.0, 16.0)


def gearbox(backlash: float = 0.1) -> dict[str, trimesh.Trimesh]:
    """Two spur gears (20 and 30 teeth) meshing with ``backlash`` mm on shafts in a housing."""
    ta, tb = 20, 30
    cb = (MODULE * (ta + tb) / 2, 0.0)
    bores = [cylinder(6.02, -6, 1, 48), cylinder(6.02, -6, 1, 48, cb)]
    housing = difference(
        box((-30, -40, -10), (95, 40, 30)), box((-25, -35, 0), (90, 35, 31)), *bores
    )
    lid = difference(
        box((-30, -40, 30), (95, 40, 36)),
        cylinder(6.02, 29, 33, 48),
        cylinder(6.02, 29, 33, 48, cb),
    )

    def shaft(xy, n):  # the gear sits on its collar
        return union(cylinder(6, -6, 32, n, xy), cylinder(8, 4, 6, n, xy))

    return {
        "housing": housing,
        "lid": lid,
        "shaft_a": shaft((0, 0), 40),
        "shaft_b": shaft(cb, 44),
        "gear_a": _spur_gear(ta, (0, 0), 0.0, backlash),
        "gear_b": _spur_gear(tb, cb, np.pi + np.pi / tb, backlash),
    }


def _bore(radius: float, sections: int) -> np.ndarray:
    angles = np.linspace(0, 2 * np.pi, sections, endpoint=False)[::-1]  # CW hole
    return np.stack([radius * np.cos(angles), radius * np.sin(angles)], 1)


def _helical_gear(teeth: int, phase: float, twist: float, backlash: float, height: float):
    """A helical gear about z (z 0..height), its section turned by ``twist`` radians from
    bottom to top (the helix), bore of radius 5."""
    return extrude([gear_outline(teeth, 8, phase, -backlash), _bore(5.0, 36)], 0, height, twist)


def helical_pair(helix_deg: float = 20.0, backlash: float = 0.1) -> dict[str, trimesh.Trimesh]:
    """Gears of 15 and 25 teeth (helix ``helix_deg``, opposite hands, 14 mm wide) meshing in
    z 2..16 on the collars of two shafts standing in blind bores of a plate (top z = 0)."""
    ta, tb, width = 15, 25, 14.0
    ra, rb = MODULE * ta / 2, MODULE * tb / 2
    cb = np.array([ra + rb, 0.0])
    advance = width * np.tan(np.radians(helix_deg))  # along the pitch circles
    gear_b = _helical_gear(tb, np.pi + np.pi / tb, -advance / rb, backlash, width)
    plate = difference(box((-20, -20, -8), (cb[0] + 30, 20, 0)),
                       cylinder(5, -5, 1, 40), cylinder(5, -5, 1, 40, cb))  # fmt: skip

    def shaft(xy, n):
        return union(cylinder(5, -5, 30, n, xy), cylinder(7, 0, 2, n, xy))

    return {
        "plate": plate,
        "shaft_a": shaft((0, 0), 40),
        "shaft_b": shaft(cb, 44),
        "gear_a": _helical_gear(ta, 0.0, advance / ra, backlash, width).apply_translation(
            (0, 0, 2)
        ),
        "gear_b": gear_b.apply_translation((*cb, 2)),
    }


def planetary_stage(backlash: float = 0.1) -> dict[str, trimesh.Trimesh]:
    """Sun 12, planets 18 (three, on pins pressed into the base), ring 48 teeth, module 2,
    gears in z 0..10 on a base (top z = 0), a carrier plate z 10..14 over the planets."""
    zs, zp, zr = 12, 18, 48
    a = MODULE * (zs + zp) / 2  # 30
    spots = [a * np.array([np.cos(t), np.sin(t)]) for t in 2 * np.pi * np.arange(3) / 3]
    base = difference(
        cylinder(60, -10, 0, 96),
        cylinder(5, -6, 1, 40),
        *(cylinder(4, -6, 1, 32, c) for c in spots),
    )
    sun = union(cylinder(5, -6, 22, 40), extrude([gear_outline(zs, 8, 0.0, -backlash)], 0, 10))
    cutter = gear_outline(zr, 8, np.pi / zr, backlash, addendum=1.25, dedendum=1.0)
    ring = extrude([_bore(60.0, 96)[::-1], cutter[::-1]], 0, 10)
    carrier = difference(
        cylinder(40, 10, 14, 64),
        cylinder(5.05, 9, 15, 40),
        *(cylinder(4, 9, 15, 32, c) for c in spots),
    )
    parts = {"base": base, "sun": sun, "ring": ring, "carrier": carrier}
    for k, c in enumerate(spots):
        turn = trimesh.transformations.rotation_matrix(2 * np.pi * k / 3, (0, 0, 1))
        planet = extrude([gear_outline(zp, 8, np.pi / zp, -backlash), _bore(4.0, 32)], 0, 10)
        parts[f"planet_{k + 1}"] = planet.apply_translation((a, 0, 0)).apply_transform(turn)
        parts[f"pin_{k + 1}"] = cylinder(4, -6, 14, 32, c)
    return parts


def shear_mold(press: float = 0.01) -> dict[str, trimesh.Trimesh]:
    """A die set; guide pins, dowels and bushings interfere by ``press`` mm."""
    pins, dowels = [(-80, -55), (80, 55)], [(-80, 55), (80, -55)]
    lower = difference(
        box((-100, -75, 0), (100, 75, 30)),
        *(cylinder(8 - press, 8, 31, 48, xy) for xy in pins),
        *(cylinder(4, 15, 31, 32, xy) for xy in dowels),
        box((-25, -20, -1), (25, 20, 31)),  # slug opening
    )
    die = difference(
        box((-100, -75, 30), (100, 75, 50)),
        *(cylinder(8.5, 29, 51, 48, xy) for xy in pins),
        *(cylinder(4, 29, 51, 32, xy) for xy in dowels),
        box((-20, -15, 29), (20, 15, 51)),  # die opening
    )
    upper = difference(
        box((-100, -75, 100), (100, 75, 130)),
        *(cylinder(12 - press, 99, 131, 48, xy) for xy in pins),
        box((-25, -20, 99), (25, 20, 105)),  # pocket for the punch head
    )
    punch = union(
        box((-19.95, -14.95, 45), (19.95, 14.95, 100)), box((-25, -20, 100), (25, 20, 105))
    )
    parts = {"lower_shoe": lower, "die_plate": die, "upper_shoe": upper, "punch": punch}
    for k, xy in enumerate(pins, 1):
        parts[f"guide_pin_{k}"] = cylinder(8, 8, 125, 40, xy)
        parts[f"bushing_{k}"] = union(
            annulus(8.02, 12, 60, 130, 44, 48, xy), annulus(8.02, 15, 130, 134, 44, 48, xy)
        )
    for k, xy in enumerate(dowels, 1):
        parts[f"dowel_{k}"] = cylinder(4 + press, 15, 45, 32, xy)
    return parts
