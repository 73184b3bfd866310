"""Test assemblies built in code from trimesh primitives (sizes in mm)."""

from __future__ import annotations

import numpy as np
import trimesh

from cad import Assembly


def box(extents, center=(0.0, 0.0, 0.0)) -> trimesh.Trimesh:
    """Axis-aligned box with the given extents centred at ``center``."""
    mesh = trimesh.creation.box(extents=extents)
    mesh.apply_translation(center)
    return mesh


def box_between(lo, hi) -> trimesh.Trimesh:
    """Axis-aligned box from corner ``lo`` to corner ``hi``."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return box(hi - lo, (lo + hi) / 2)


def cylinder(radius, z0, z1, sections=32) -> trimesh.Trimesh:
    """Cylinder along z from ``z0`` to ``z1``, centred on the z axis."""
    mesh = trimesh.creation.cylinder(radius=radius, height=z1 - z0, sections=sections)
    mesh.apply_translation((0, 0, (z0 + z1) / 2))
    return mesh


def difference(a: trimesh.Trimesh, b: trimesh.Trimesh) -> trimesh.Trimesh:
    """Boolean ``a - b`` with manifold3d."""
    return trimesh.boolean.difference([a, b], engine="manifold")


def stacked_cubes(overlap: float = 0.0) -> Assembly:
    """``bottom`` cube [0,10]^3 and ``top`` cube on it (sunk by ``overlap``)."""
    return Assembly.from_meshes(
        {
            "bottom": box_between((0, 0, 0), (10, 10, 10)),
            "top": box_between((0, 0, 10 - overlap), (10, 10, 20 - overlap)),
        }
    )


def peg_in_plate(blind: bool = False) -> Assembly:
    """``plate`` 40x40x10 with a radius-5 hole (blind: 6 deep from the top) and a
    ``peg`` of the same polygon filling it, sticking out 5 mm above the plate."""
    plate = box_between((-20, -20, 0), (20, 20, 10))
    z_bottom = 4.0 if blind else -1.0
    hole = cylinder(5, z_bottom, 11)
    plate = difference(plate, hole)
    peg = cylinder(5, 4.0 if blind else 0.0, 15)
    return Assembly.from_meshes({"plate": plate, "peg": peg})


def thin_plate_on_path(length: float = 200.0) -> Assembly:
    """A ``block`` at the origin and a thin ``sheet`` (1% of ``length`` thick) ``length``
    away along +x, plus a far ``base`` off every path."""
    thickness = 0.01 * length
    return Assembly.from_meshes(
        {
            "block": box_between((0, 0, 0), (10, 10, 10)),
            "sheet": box_between((length, -20, -20), (length + thickness, 30, 30)),
            "far": box_between((500, 500, 500), (510, 510, 510)),
        }
    )


def boxed_container() -> Assembly:
    """An open-top ``tray`` (walls 2 mm), a ``lid`` on it, an ``item`` inside."""
    outer = box_between((0, 0, 0), (30, 30, 20))
    cavity = box_between((2, 2, 2), (28, 28, 21))
    tray = difference(outer, cavity)
    lid = box_between((0, 0, 20), (30, 30, 22))
    item = box_between((10, 10, 2), (20, 20, 12))
    return Assembly.from_meshes({"tray": tray, "lid": lid, "item": item})


def far_apart() -> Assembly:
    """Three cubes off each other's paths in every axis direction."""
    return Assembly.from_meshes(
        {
            "a": box_between((0, 0, 0), (5, 5, 5)),
            "b": box_between((20, 20, 20), (25, 25, 25)),
            "c": box_between((40, -40, 60), (45, -35, 65)),
        }
    )


def disc_spring(z0: float = 0.0, sections: int = 48) -> trimesh.Trimesh:
    """A slotless disc spring as a closed mesh: a cone annulus from radius 20 to 40 mm, the
    inner edge 4 mm higher than the outer, 2 mm thick along z, its lowest point at ``z0``."""
    angle = np.linspace(0.0, 2 * np.pi, sections, endpoint=False)
    ring = np.c_[np.cos(angle), np.sin(angle), np.zeros(sections)]
    lift = np.array([0.0, 0.0, 1.0])
    rings = [(20, 6), (40, 2), (20, 4), (40, 0)]  # top inner, top outer, bottom inner, outer
    vertices = np.vstack([r * ring + (z0 + z) * lift for r, z in rings])
    i = np.arange(sections)
    j = (i + 1) % sections
    ti, to, bi, bo = (k * sections for k in range(4))
    quads = [
        (ti + i, to + i, to + j, ti + j),  # top cone
        (bi + i, bi + j, bo + j, bo + i),  # bottom cone
        (to + i, bo + i, bo + j, to + j),  # outer rim
        (ti + i, ti + j, bi + j, bi + i),  # inner rim
    ]
    faces = np.vstack(
        [np.c_[a, b, c] for a, b, c, _ in quads] + [np.c_[a, c, d] for a, _, c, d in quads]
    )
    mesh = trimesh.Trimesh(vertices, faces, process=True)
    if mesh.volume < 0:
        mesh.invert()
    return mesh


def open_disc_springs(sink: float = 0.0) -> Assembly:
    """Two identical disc springs stacked 2 mm apart (the upper one's underside lies on the
    lower one's top, sunk into it by ``sink``), tessellated like a STEP export that lost
    their cone faces: only the rims are left, open meshes whose coincident rim bands touch
    along a free edge."""
    meshes = {}
    for name, z0 in (("lower", 0.0), ("upper", 2.0 - sink)):
        spring = disc_spring(z0)
        rims = np.abs(spring.face_normals[:, 2]) < 0.5
        meshes[name] = spring.submesh([rims], append=True)
    return Assembly.from_meshes(meshes)
