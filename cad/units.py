"""Length units: millimetres per unit, and the short name of a unit.

Meshes are stored in millimetres whatever the source unit; :func:`unit_scale` gives the
factor a file's coordinates are multiplied by.
"""

from __future__ import annotations

from cad.errors import GeometryError

_UNIT_TO_MM = {
    "mm": 1.0,
    "millimeter": 1.0,
    "millimeters": 1.0,
    "millimetre": 1.0,
    "millimetres": 1.0,
    "cm": 10.0,
    "centimeter": 10.0,
    "centimeters": 10.0,
    "centimetre": 10.0,
    "centimetres": 10.0,
    "m": 1000.0,
    "meter": 1000.0,
    "meters": 1000.0,
    "metre": 1000.0,
    "metres": 1000.0,
    "um": 1e-3,
    "micron": 1e-3,
    "microns": 1e-3,
    "micrometer": 1e-3,
    "micrometers": 1e-3,
    "in": 25.4,
    "inch": 25.4,
    "inches": 25.4,
    "ft": 304.8,
    "foot": 304.8,
    "feet": 304.8,
}

SHORT_UNITS = ("mm", "cm", "m", "um", "in", "ft")
"""The short names, one per distinct unit."""


def unit_scale(units: str) -> float:
    """Millimetres per one ``units`` (``"m"`` -> 1000.0); ValueError for unknown units."""
    key = str(units).strip().lower()
    if key not in _UNIT_TO_MM:
        raise GeometryError(f"unknown length unit {units!r}; use e.g. mm, cm, m, in")
    return _UNIT_TO_MM[key]


def canonical_unit(units: str) -> str:
    """Short name of a unit (``"millimeter"`` -> ``"mm"``)."""
    scale = unit_scale(units)
    for short in SHORT_UNITS:
        if _UNIT_TO_MM[short] == scale:
            return short
    return str(units)  # pragma: no cover
