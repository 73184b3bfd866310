"""The assembly model: parts in their assembled pose, in millimetres."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh


@dataclass(frozen=True, eq=False)
class Part:
    """One part of an assembly, in its assembled pose.

    Attributes
    ----------
    id : str
        Unique identifier (from the BOM, else the file or node name).
    name : str
        Human-readable name (defaults to ``id``).
    mesh : trimesh.Trimesh
        Triangle mesh in the assembled pose, in millimetres, outward-facing normals.
    quantity : int
        BOM quantity (informative; each BOM row is one part in the relations).
    type : str
        Optional part type from the BOM, e.g. ``"screw"``; empty if not given.
    source : str
        File (and node, for scenes) the mesh came from.
    """

    id: str
    name: str
    mesh: trimesh.Trimesh
    quantity: int = 1
    type: str = ""
    source: str = ""

    @property
    def bounds(self) -> np.ndarray:
        """Axis-aligned bounds ``[[xmin, ymin, zmin], [xmax, ymax, zmax]]``, shape (2, 3)."""
        return np.asarray(self.mesh.bounds, dtype=float)


@dataclass(frozen=True, eq=False)
class Assembly:
    """Parts in assembled pose.

    Attributes
    ----------
    parts : tuple[Part, ...]
        The parts; their order is the row/column order of every relation table.
    units : str
        Length unit of the source files (``"mm"``, ``"m"``, ...; ``"mixed"`` if they
        differ). Meshes are always stored in millimetres, whatever the source unit.
    source : str
        Path the assembly was read from (empty if built in code).
    """

    parts: tuple[Part, ...]
    units: str = "mm"
    source: str = ""

    def __post_init__(self) -> None:
        seen: set[str] = set()
        for part in self.parts:
            if part.id in seen:
                raise ValueError(f"duplicate part id {part.id!r}")
            seen.add(part.id)

    @property
    def ids(self) -> tuple[str, ...]:
        """Part ids in table order."""
        return tuple(p.id for p in self.parts)

    def __len__(self) -> int:
        return len(self.parts)

    @classmethod
    def from_meshes(cls, meshes: dict[str, trimesh.Trimesh], *, units: str = "mm") -> Assembly:
        """Build an assembly from ``{id: mesh}`` given in ``units`` (converted to mm)."""
        from cad.loading import prepare_part

        parts = tuple(
            prepare_part(pid, mesh, scale=unit_scale(units), source="<memory>")
            for pid, mesh in meshes.items()
        )
        return cls(parts=parts, units=units)


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


def unit_scale(units: str) -> float:
    """Millimetres per one ``units`` (``"m"`` -> 1000.0); ValueError for unknown units."""
    key = str(units).strip().lower()
    if key not in _UNIT_TO_MM:
        raise ValueError(f"unknown length unit {units!r}; use e.g. mm, cm, m, in")
    return _UNIT_TO_MM[key]


def canonical_unit(units: str) -> str:
    """Short name of a unit (``"millimeter"`` -> ``"mm"``)."""
    scale = unit_scale(units)
    for short in ("mm", "cm", "m", "um", "in", "ft"):
        if _UNIT_TO_MM[short] == scale:
            return short
    return str(units)  # pragma: no cover
