"""Build the finger-jointed box's part meshes (binary STL, millimetres, assembled pose).

A wooden storage box as a cell builds it: a base board, four walls joined at the corners
by finger joints, four corner blocks (glued gussets) and a lid, drawn here from boxes
united with the manifold engine, so the files are this project's own. The frame is the
cell's: z up, the base on the table.

- ``base``: 160 x 100 x 6 board (z 0..6);
- ``front``, ``back``: 6 mm long walls (y 0..6 and 94..100), x 6..154 and, at each end,
  three fingers (z 6..15, 24..33, 42..51) in the corner columns;
- ``left``, ``right``: 6 mm short walls (x 0..6 and 154..160), y 6..94 and, at each end,
  the three fingers between (z 15..24, 33..42, 51..60); walls stand on the base, z 6..60;
- ``gusset_fl``, ``gusset_fr``, ``gusset_bl``, ``gusset_br``: 14 x 14 x 30 corner blocks
  inside the corners, on the base (z 6..36);
- ``lid``: 160 x 100 x 6 board on the walls (z 60..66).

The fingers interlock: a wall whose neighbour is in place can only slide in horizontally,
from outside, and a corner block goes in from above only while the lid is off, so the order
matters. Run ``python examples/finger_box/make_meshes.py`` to regenerate.
"""

from __future__ import annotations

from pathlib import Path

import trimesh

from asp.atomic import write_bytes

HERE = Path(__file__).resolve().parent
MESHES = HERE / "meshes"
L, W, T = 160.0, 100.0, 6.0  # outer length (x), width (y), board thickness
Z0, Z1 = T, 60.0  # walls stand on the base, up to the lid
BAND = (Z1 - Z0) / 6  # six finger bands of 9 mm
GUSSET, GUSSET_H = 14.0, 30.0


def block(x0, x1, y0, y1, z0, z1) -> trimesh.Trimesh:
    """An axis-aligned box from its bounds (mm)."""
    box = trimesh.creation.box(extents=(x1 - x0, y1 - y0, z1 - z0))
    box.apply_translation(((x0 + x1) / 2, (y0 + y1) / 2, (z0 + z1) / 2))
    return box


def union(pieces: list[trimesh.Trimesh]) -> trimesh.Trimesh:
    return trimesh.boolean.union(pieces, engine="manifold")


def long_wall(y0: float) -> trimesh.Trimesh:
    """A long wall (front or back): its body and three fingers in each corner column."""
    pieces = [block(T, L - T, y0, y0 + T, Z0, Z1)]
    for band in (0, 2, 4):
        z = Z0 + band * BAND
        for x0 in (0.0, L - T):
            pieces.append(block(x0, x0 + T, y0, y0 + T, z, z + BAND))
    return union(pieces)


def short_wall(x0: float) -> trimesh.Trimesh:
    """A short wall (left or right): its body and the fingers between the long wall's."""
    pieces = [block(x0, x0 + T, T, W - T, Z0, Z1)]
    for band in (1, 3, 5):
        z = Z0 + band * BAND
        for y0 in (0.0, W - T):
            pieces.append(block(x0, x0 + T, y0, y0 + T, z, z + BAND))
    return union(pieces)


def gusset(x0: float, y0: float) -> trimesh.Trimesh:
    return block(x0, x0 + GUSSET, y0, y0 + GUSSET, Z0, Z0 + GUSSET_H)


def parts() -> dict[str, trimesh.Trimesh]:
    inner_x, inner_y = (T, L - T - GUSSET), (T, W - T - GUSSET)
    return {
        "base": block(0, L, 0, W, 0, T),
        "front": long_wall(0.0),
        "back": long_wall(W - T),
        "left": short_wall(0.0),
        "right": short_wall(L - T),
        "gusset_fl": gusset(inner_x[0], inner_y[0]),
        "gusset_fr": gusset(inner_x[1], inner_y[0]),
        "gusset_bl": gusset(inner_x[0], inner_y[1]),
        "gusset_br": gusset(inner_x[1], inner_y[1]),
        "lid": block(0, L, 0, W, Z1, Z1 + T),
    }


def main() -> None:
    for name, mesh in parts().items():
        if not mesh.is_watertight:
            raise RuntimeError(f"{name}: the union is not watertight")
        write_bytes(MESHES / f"{name}.stl", mesh.export(file_type="stl"))
        print(f"wrote meshes/{name}.stl: {len(mesh.faces)} faces")


if __name__ == "__main__":
    main()
