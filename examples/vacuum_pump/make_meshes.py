"""Build the vacuum-pump part meshes (binary STL, millimetres, assembled pose) and ``bom.csv``.

The pump of the paper's section 4.2 (turbomolecular pump, Politecnico di Torino), drawn
from trimesh primitives with boolean holes (manifold engine) at plausible sizes. The frame
is the cell's: z up, the envelope EV standing on the table, the body BD on top of it.

- BD  body: flange r 50 (z 0..15) and core r 25 (z 15..65), holes for every screw;
- PC  plastic case: a ring r 26..40 (z 15..20) on the flange, 1 mm clear of the core;
- BC  bottom cap: a disk r 25 (z 65..71) on the core;
- EV  envelope: a 150 x 150 block (z -40..0) under the body;
- FOR foreline flange: a disk r 12 (z 0..5) on the envelope, with a bore;
- VT1 2x M3 through PC into BD, from above (op 1.4/1.6);
- VT1M 2x M3 from below through the BD flange into PC (op 4.3, manual);
- VT2 4x M4 through BC into BD (op 2.4/2.5);
- VT3 6x M5 through the BD flange into EV (op 5.3);
- VT4 4x M3 through FOR into EV (op 5.4).

Every contact is a pair of coplanar faces (heads on faces, parts on parts); screws sit in
their holes with radial clearance and a gap below the tip, so a screw touches only the face
under its head. Run ``python examples/vacuum_pump/make_meshes.py`` to regenerate.
"""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import numpy as np
import trimesh

from asp.atomic import write_bytes, write_text

HERE = Path(__file__).resolve().parent
MESHES = HERE / "meshes"
BIG = 64  # cylinder sections of the large parts
SMALL = 16  # cylinder sections of screws and holes


def cylinder(r: float, z0: float, z1: float, x: float = 0.0, y: float = 0.0, sections=SMALL):
    """A z-axis cylinder of radius ``r`` from ``z0`` to ``z1`` centred on ``(x, y)``."""
    mesh = trimesh.creation.cylinder(radius=r, height=z1 - z0, sections=sections)
    mesh.apply_translation([x, y, (z0 + z1) / 2])
    return mesh


def box(x0, x1, y0, y1, z0, z1):
    mesh = trimesh.creation.box(extents=[x1 - x0, y1 - y0, z1 - z0])
    mesh.apply_translation([(x0 + x1) / 2, (y0 + y1) / 2, (z0 + z1) / 2])
    return mesh


def minus(solid, holes):
    return trimesh.boolean.difference([solid, *holes], engine="manifold")


def union(parts):
    return trimesh.boolean.union(parts, engine="manifold")


def polar(r: float, degrees: float) -> tuple[float, float]:
    a = math.radians(degrees)
    return round(r * math.cos(a), 6), round(r * math.sin(a), 6)


# Screw positions (x, y).
VT1_AT = [polar(32.5, a) for a in (0, 180)]
VT1M_AT = [polar(32.5, a) for a in (90, 270)]
VT2_AT = [(12.0, 0.0), (-12.0, 0.0), (0.0, 12.0), (0.0, -12.0)]
VT3_AT = [polar(45.0, 30 + 60 * k) for k in range(6)]
FOR_AT = (55.0, 55.0)
VT4_AT = [(FOR_AT[0] + dx, FOR_AT[1] + dy) for dx, dy in ((8, 0), (-8, 0), (0, 8), (0, -8))]


def screws(at, head_r, head_z, shank_r, shank_z):
    """Screws at ``at``: head cylinder over ``head_z``, shank over ``shank_z``."""
    bodies = [
        union([cylinder(head_r, *head_z, x, y), cylinder(shank_r, *shank_z, x, y)]) for x, y in at
    ]
    return trimesh.util.concatenate(bodies)


def build() -> dict[str, trimesh.Trimesh]:
    """All part meshes in assembled pose, keyed by part id."""
    core_top = 65.0
    bd = union([cylinder(50, 0, 15, sections=BIG), cylinder(25, 15, core_top, sections=BIG)])
    bd = minus(
        bd,
        [cylinder(1.75, 9, 15.01, x, y) for x, y in VT1_AT]  # blind, 3 mm below the tip
        + [cylinder(1.75, -0.01, 15.01, x, y) for x, y in VT1M_AT]
        + [cylinder(2.25, 55, core_top + 0.01, x, y) for x, y in VT2_AT]
        + [cylinder(2.75, -0.01, 15.01, x, y) for x, y in VT3_AT],
    )
    pc = minus(cylinder(40, 15, 20, sections=BIG), [cylinder(26, 14.9, 20.1, sections=BIG)])
    pc = minus(
        pc,
        [cylinder(1.75, 14.9, 20.1, x, y) for x, y in VT1_AT]
        + [cylinder(1.75, 14.99, 19, x, y) for x, y in VT1M_AT],  # blind from below
    )
    bc = minus(
        cylinder(25, core_top, core_top + 6, sections=BIG),
        [cylinder(2.25, core_top - 0.1, core_top + 6.1, x, y) for x, y in VT2_AT],
    )
    ev = minus(
        box(-75, 75, -75, 75, -40, 0),
        [cylinder(2.75, -8, 0.01, x, y) for x, y in VT3_AT]
        + [cylinder(3.5, -3, 0.01, x, y) for x, y in VT1M_AT]  # pockets for VT1M heads
        + [cylinder(1.75, -6, 0.01, x, y) for x, y in VT4_AT],
    )
    flange = minus(
        cylinder(12, 0, 5, *FOR_AT, sections=BIG),
        [cylinder(6, -0.1, 5.1, *FOR_AT, sections=BIG)]
        + [cylinder(1.75, -0.1, 5.1, x, y) for x, y in VT4_AT],
    )
    return {
        "BD": bd,
        "PC": pc,
        "BC": bc,
        "EV": ev,
        "FOR": flange,
        "VT1": screws(VT1_AT, 2.75, (20, 22), 1.5, (12, 20)),
        "VT1M": screws(VT1M_AT, 2.75, (-2, 0), 1.5, (0, 18)),
        "VT2": screws(VT2_AT, 3.5, (core_top + 6, core_top + 8.8), 2.0, (61, core_top + 6)),
        "VT3": screws(VT3_AT, 4.25, (15, 18.5), 2.5, (-5, 15)),
        "VT4": screws(VT4_AT, 2.75, (5, 7), 1.5, (-3, 5)),
    }


BOM = [
    # id, name, quantity, type
    ("BD", "Main body", 1, "component"),
    ("PC", "Plastic case", 1, "component"),
    ("BC", "Bottom cap", 1, "component"),
    ("VT1", "Screw VT1 M3x8 (case, robot)", 2, "screw"),
    ("VT2", "Screw VT2 hex M4x10 (bottom cap)", 4, "screw"),
    ("VT1M", "Screw VT1 M3 (case, manual, from below)", 2, "screw"),
    ("EV", "Envelope", 1, "component"),
    ("VT3", "Screw VT3 hex M5x20 (envelope)", 6, "screw"),
    ("FOR", "Foreline flange", 1, "component"),
    ("VT4", "Screw VT4 hex M3x8 (foreline flange)", 4, "screw"),
]


def main() -> None:
    meshes = build()
    for pid, mesh in meshes.items():
        if not mesh.is_watertight:
            raise SystemExit(f"{pid}: mesh is not watertight")
        mesh.vertices = np.round(mesh.vertices, 9)
        write_bytes(MESHES / f"{pid}.stl", mesh.export(file_type="stl"))
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["id", "name", "file", "quantity", "type"])
    for pid, name, qty, kind in BOM:
        writer.writerow([pid, name, f"meshes/{pid}.stl", qty, kind])
    write_text(HERE / "bom.csv", buffer.getvalue())
    for pid in meshes:
        size = (MESHES / f"{pid}.stl").stat().st_size
        print(f"{pid:5s} {len(meshes[pid].faces):6d} faces {size / 1024:7.1f} KB")


if __name__ == "__main__":
    main()
