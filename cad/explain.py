"""Explanations a person can act on: what blocks a part, and overlaps that are unit mistakes.

:func:`why_blocked` answers "why can this part not come out (or go in) along d?" from the
relation tables: for each direction, the parts that block it directly and its depth, the
number of layers of parts that must come out along that direction before it can (peeling
the assembly: layer 0 is free now, layer 1 once layer 0 is out, ...; ``None`` when parts
lock each other and no order frees it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cad.directions import DIRECTIONS
from cad.errors import GeometryError
from cad.relations import Relations


@dataclass(frozen=True)
class Blocking:
    """What keeps a part from moving along one direction.

    Attributes
    ----------
    direction : str
        ``+x`` ... ``-z``.
    blockers : tuple of str
        Parts in its way along ``direction`` (empty: free).
    depth : int or None
        Layers of parts to take out along ``direction`` before this part can follow (0:
        free now); None when it never comes free (parts lock each other).
    """

    direction: str
    blockers: tuple[str, ...]
    depth: int | None


def peel_depths(tt: np.ndarray, d: int) -> list[int | None]:
    """Per part, the layer in which it leaves along direction ``d`` (None: never).

    ``tt`` is the ``(n, n, 6)`` freedom table; a part leaves when it is free along ``d``
    past every part still there.
    """
    n = tt.shape[0]
    depth: list[int | None] = [None] * n
    remaining = set(range(n))
    layer = 0
    while remaining:
        free = [i for i in remaining if all(tt[i, j, d] for j in remaining if j != i)]
        if not free:
            break
        for i in free:
            depth[i] = layer
        remaining -= set(free)
        layer += 1
    return depth


def why_blocked(relations: Relations, part: str) -> tuple[Blocking, ...]:
    """For each direction, the parts blocking ``part`` and its peel depth.

    Raises
    ------
    GeometryError
        ``part`` is not one of the parts (the nearest ids suggested).
    """
    if part not in relations.parts:
        import difflib

        near = difflib.get_close_matches(part, relations.parts, n=3)
        hint = (
            f"did you mean {', '.join(near)}?"
            if near
            else f"parts: {', '.join(relations.parts[:20])}"
        )
        raise GeometryError(f"unknown part {part!r} ({hint})")
    i = relations.index(part)
    out = []
    for d, label in enumerate(DIRECTIONS):
        blockers = tuple(
            relations.parts[j]
            for j in range(len(relations.parts))
            if j != i and not relations.tt[i, j, d]
        )
        out.append(Blocking(label, blockers, peel_depths(relations.tt, d)[i]))
    return tuple(out)
