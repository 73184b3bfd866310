"""The assembly model: parts in their assembled pose, in millimetres."""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass

import numpy as np
import trimesh

from cad.units import unit_scale


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
    shape : str
        Shape class from the spec or BOM (empty: not given; see :mod:`cad.identical`).
    """

    id: str
    name: str
    mesh: trimesh.Trimesh
    quantity: int = 1
    type: str = ""
    source: str = ""
    shape: str = ""

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
    groups : tuple of (str, tuple of str)
        The hierarchy the file gives (a STEP sub-assembly, a glTF parent node): group id
        -> ids of the parts below it, outermost first. Empty when the source has none.
    frame : tuple of tuple of float, or None
        The build frame the meshes are in (:mod:`cad.frame`): the rotation ``R`` with
        ``x_build = R @ x_file``, row by row; None: the file's own frame.
    """

    parts: tuple[Part, ...]
    units: str = "mm"
    source: str = ""
    groups: tuple[tuple[str, tuple[str, ...]], ...] = ()
    frame: tuple[tuple[float, float, float], ...] | None = None

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
        parts = tuple(
            prepare_part(pid, mesh, scale=unit_scale(units), source="<memory>")
            for pid, mesh in meshes.items()
        )
        return cls(parts=parts, units=units)


def prepare_part(
    pid: str,
    mesh: trimesh.Trimesh,
    *,
    scale: float,
    source: str,
    name: str | None = None,
    quantity: int = 1,
    type: str = "",
    shape: str = "",
    warn: bool = True,
) -> Part:
    """Validate a mesh, scale it to millimetres and wrap it as a :class:`Part`.

    The mesh is copied, duplicate vertices merged and, for a closed mesh with inward
    normals, the winding flipped. An empty mesh is a ValueError; a mesh that is not
    watertight gives a warning naming the part (unless ``warn`` is false: a loader of many
    parts says it once for all, :func:`warn_not_watertight`).
    """
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise ValueError(f"part {pid!r} ({source}): empty mesh")
    mesh = trimesh.Trimesh(
        vertices=np.asarray(mesh.vertices, dtype=float) * scale,
        faces=np.asarray(mesh.faces),
        process=True,
    )
    mesh.remove_unreferenced_vertices()
    if len(mesh.faces) == 0 or not np.all(np.isfinite(mesh.vertices)):
        raise ValueError(f"part {pid!r} ({source}): empty or invalid mesh")
    if mesh.is_watertight:
        if mesh.volume < 0:
            mesh.invert()
    elif warn:
        warnings.warn(
            f"part {pid!r} ({source}) is not watertight; its relations may be unreliable",
            stacklevel=3,
        )
    return Part(
        id=pid,
        name=name or pid,
        mesh=mesh,
        quantity=quantity,
        type=type,
        source=source,
        shape=shape,
    )


_SAID: set[str] = set()
"""Part sources (``file#node``) already named in a not-watertight warning this process."""


def warn_not_watertight(parts, where: str) -> None:
    """One warning naming every part of ``where`` whose mesh is not watertight (the first
    ten); a part already named (the same file and node, read again: a spec generated from
    a file, then its parts loaded) is not named again."""
    fresh = []
    for p in parts:
        if p.mesh.is_watertight:
            continue
        file, _, nodes = p.source.partition("#")
        file = os.path.realpath(file) if file and not file.startswith("<") else file
        sources = {f"{file}#{n}" for n in nodes.split("+")} if nodes else {file}
        if not sources <= _SAID:
            fresh.append(repr(p.id))
            _SAID.update(sources)
    if not fresh:
        return
    more = f" and {len(fresh) - 10} more" if len(fresh) > 10 else ""
    which = f"part {fresh[0]}" if len(fresh) == 1 else f"{len(fresh)} parts"
    verb = "is" if len(fresh) == 1 else f"({', '.join(fresh[:10])}{more}) are"
    its = "its" if len(fresh) == 1 else "their"
    warnings.warn(
        f"{which} ({where}) {verb} not watertight; {its} relations may be unreliable",
        stacklevel=1,
    )
