"""Overlaps that are unit mistakes: say which unit would fit.

:func:`unit_hint` looks at an overlap between two parts and names the unit that would fit
when the sizes look like a unit mistake: one part about 1000, 25.4 or 10 times smaller or
larger than the others (a file in metres or inches among millimetre files), nested inside
its neighbour; or the whole assembly a few millimetres (or kilometres) across.
"""

from __future__ import annotations

import numpy as np

from cad.assembly import Assembly

UNIT_FACTORS = ((1000.0, "metres"), (25.4, "inches"), (10.0, "centimetres"))
"""Scale factors that betray a unit mistake, and the unit each points to."""
MIN_PLAUSIBLE_MM = 2.0
MAX_PLAUSIBLE_MM = 10_000.0
"""Assemblies smaller or larger than this (bounding-box diagonal) suggest wrong units."""


def unit_hint(assembly: Assembly, a: int, b: int) -> str:
    """A sentence naming the unit that would fit when parts ``a``, ``b`` overlap, or ``""``.

    Checks, in order: one of the two is about 1000, 25.4 or 10 times smaller or larger than
    the median of the other parts (a file in another unit; not when both come from one
    scene file, which has one unit: a clutch's spring is 8 times a bolt); the whole
    assembly is under 2 mm across (metres or inches read as millimetres) or over 10 m
    (millimetres declared as metres).
    """
    for k in () if one_scene_file(assembly, a, b) else (a, b):
        hint = part_scale_hint(assembly, k, other=b if k == a else a)
        if hint:
            return hint
    return size_hint(assembly)


def size_hint(assembly: Assembly) -> str:
    """A sentence naming the unit that would fit when the whole assembly is implausibly
    small (under :data:`MIN_PLAUSIBLE_MM` across: metres or inches read as millimetres)
    or large (over :data:`MAX_PLAUSIBLE_MM`: millimetres declared as metres), else ``""``.
    """
    if not assembly.parts:
        return ""
    lo = np.min([p.mesh.bounds[0] for p in assembly.parts], axis=0)
    hi = np.max([p.mesh.bounds[1] for p in assembly.parts], axis=0)
    size = float(np.linalg.norm(hi - lo))
    if size < MIN_PLAUSIBLE_MM:
        return (
            f"the whole assembly is only {size:.3g} mm across: if its files are in metres "
            "use units m (--units m, or units: m in the spec); for inches, units in"
        )
    if size > MAX_PLAUSIBLE_MM:
        return (
            f"the whole assembly is {size / 1000:.3g} m across: if its numbers are "
            "millimetres, declare mm (--units mm for files that declare none, or export "
            "it in mm)"
        )
    return ""


def one_scene_file(assembly: Assembly, a: int, b: int) -> bool:
    """True when parts ``a`` and ``b`` are nodes of one scene file (``source`` ``file#node``)."""
    sources = [assembly.parts[k].source for k in (a, b)]
    files = {s.rsplit("#", 1)[0] for s in sources if "#" in s}
    return len(files) == 1 and all("#" in s for s in sources)


def part_scale_hint(
    assembly: Assembly, k: int, other: int | None = None, factors=UNIT_FACTORS
) -> str:
    """``part 'pin' is about 1000 times smaller than the others ...`` or ``""``.

    Part ``k`` is compared with the median bounding-box diagonal of the other parts; a
    ratio within a factor 2.5 of one of ``factors`` (1000, 25.4, 10) names the unit that
    would fit. With
    ``other``, a part nested in (or holding) that part is said so.
    """
    if len(assembly.parts) < 2:
        return ""
    diagonals = np.array(
        [float(np.linalg.norm(np.ptp(p.mesh.bounds, axis=0))) for p in assembly.parts]
    )
    part = assembly.parts[k]
    ratio = float(np.median(np.delete(diagonals, k))) / max(diagonals[k], 1e-12)
    where = ""
    if other is not None:
        ob = assembly.parts[other].mesh.bounds
        if _inside(part.mesh.bounds, ob) or _inside(ob, part.mesh.bounds):
            where = " and sits nested in its neighbour"
    for factor, unit in factors:
        if factor / 2.5 <= ratio <= factor * 2.5:
            return (
                f"part {part.id!r} is about {ratio:.0f} times smaller than the others{where}: "
                f"its file may be in {unit} (declare that file's unit, or export it in the "
                "others')"
            )
        if factor / 2.5 <= 1.0 / ratio <= factor * 2.5:
            return (
                f"part {part.id!r} is about {1.0 / ratio:.0f} times larger than the others"
                f"{where}: the others may be in {unit} while it is in millimetres"
            )
    return ""


def _inside(inner: np.ndarray, outer: np.ndarray) -> bool:
    return bool(np.all(inner[0] >= outer[0]) and np.all(inner[1] <= outer[1]))
