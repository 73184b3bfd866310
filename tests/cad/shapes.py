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
