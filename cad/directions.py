"""The six axis directions, in the order every table, array and JSON document uses.

The order is fixed by the design notes: ``+x, -x, +y, -y, +z, -z``. Direction index ``d``
moves along axis ``d // 2`` with sign ``+1`` for even ``d`` and ``-1`` for odd ``d``; the
opposite of ``d`` is ``d ^ 1``.
"""

from __future__ import annotations

import numpy as np

from cad.errors import GeometryError

DIRECTIONS: tuple[str, ...] = ("+x", "-x", "+y", "-y", "+z", "-z")
"""Direction labels, in table order."""

DIRECTION_VECTORS: np.ndarray = np.array(
    [
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
    ]
)
"""Unit vector of each direction, shape ``(6, 3)``, rows in :data:`DIRECTIONS` order."""
DIRECTION_VECTORS.setflags(write=False)


def direction_index(label: str) -> int:
    """Index of a direction label such as ``"+z"`` in :data:`DIRECTIONS`."""
    try:
        return DIRECTIONS.index(label)
    except ValueError:
        raise GeometryError(f"unknown direction {label!r}; expected one of {DIRECTIONS}") from None


def opposite(d: int) -> int:
    """Index of the direction opposite to direction index ``d``."""
    return d ^ 1


def axis_direction(axis: int, sign: int) -> int:
    """Direction index that moves along ``axis`` (0, 1, 2) with ``sign`` (+1 or -1)."""
    return 2 * axis + (0 if sign > 0 else 1)
