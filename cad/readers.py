"""The readers of part and scene files: one table from file suffix to reader.

As trimesh keeps ``mesh_loaders`` (suffix -> function), :data:`READERS` maps each suffix
asmplan reads to a :class:`Reader` that holds everything a format decides: the keywords
``trimesh.load`` takes for it, whether one file holds several parts, the unit the format
declares (and the one it means when it declares none), the sub-assemblies it keeps outside
trimesh's scene graph, and what a wrong unit label looks like in it. A new format is one
entry here; nothing else switches on a file's suffix.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType

import numpy as np
import trimesh

from cad.errors import GeometryError

STEP_CHORD_MM = 0.01
"""Largest distance (mm) between a STEP surface and its triangles: cascadio's (OCCT's)
linear deflection ``tol_linear``, in millimetres whatever the file's unit (OCCT reads a
STEP into millimetres; 0.01 mm is cascadio's default, its angular deflection 0.5 rad stays).
Passed explicitly and recorded in a plan (``geometry.step_chord``) so that a checker
tessellates the file into the same triangles.

The rule: an absolute 0.01 mm, well inside the tolerances the relations are computed with
(:mod:`cad.tolerances`): at most 0.2 x the smallest default pair penetration tolerance
(0.05 mm, two parts at the 0.025 mm shrink floor). A gap or overlap between two
tessellated surfaces moves by at most the chord error of the concave one (a hole's facets
cut into the hole). Not coarser: at 0.02 mm (1.7 times faster on the 26-part APLAN
clutch, 140 s -> 83 s) OCCT meshes some faces of the clutch's two disc springs as fans
across their holes (each spring's area grows by 39 %: triangles of 470 square mm on a
2 mm wide flat ring), and the stacked springs then "interpenetrate by 4.3 mm"; every
other part of the clutch and of the ten other STEP files measured keeps its area within
0.5 %."""
MAX_INCH_ASSEMBLY_M = 3.0
"""A STEP declaring inches whose parts span more than this (metres, 118 in) has millimetre
numbers under an inch label (Pro/E exports of metric models do this); it is read in mm."""
MAX_GLTF_ASSEMBLY_M = 20.0
"""A glTF (metres by its specification) whose parts span more than this has millimetre
numbers (converters that keep a CAD model's numbers, e.g. COLLADA2GLTF); read in mm."""


@dataclass(frozen=True)
class Mislabel:
    """Millimetre numbers under a wrong unit label: a file whose declared ``unit`` makes it
    span more than ``limit_m`` metres is read with its numbers times ``factor`` (to metres
    as trimesh reads them); ``label`` names the declared unit in the warning."""

    unit: str
    label: str
    limit_m: float
    factor: float


@dataclass(frozen=True)
class Reader:
    """How asmplan reads one file format.

    Attributes
    ----------
    name : str
        The format, as messages name it.
    scene : bool
        One file holds several parts (one per mesh node).
    options : mapping
        Keywords for ``trimesh.load`` (``force="scene"`` aside).
    declares_unit : bool
        The file states its unit (trimesh's ``scene.units``) or the format fixes it.
    default_unit : str or None
        The unit when a file of a declaring format states none (glTF and STEP through
        cascadio: metres; 3MF: millimetres); None: unknown.
    mislabel : Mislabel or None
        What millimetre numbers under a wrong label look like in this format.
    needs : str or None
        The optional module the format needs (``cascadio`` for STEP), with
        ``extra`` the pip extra that installs it.
    merged : bool
        trimesh merges the vertices of this format's meshes as it reads them (and drops
        the non-finite ones); False for glTF (and STEP, read as GLB), whose meshes it keeps
        as stored. :func:`load_file` reads unmerged, checks, then merges where trimesh would.
    """

    name: str
    scene: bool = False
    options: Mapping = field(default_factory=lambda: MappingProxyType({}))
    declares_unit: bool = False
    default_unit: str | None = None
    mislabel: Mislabel | None = None
    needs: str | None = None
    extra: str | None = None
    merged: bool = True

    def load(self, path: Path) -> trimesh.Scene:
        """``path`` as a trimesh scene, one-line errors for bad files (:func:`load_file`)."""
        return load_file(path, self)


def load_file(path: Path, reader: Reader) -> trimesh.Scene:
    """Read ``path`` with ``reader``'s options; a STEP through :func:`cad.step.read_step`.

    The file's meshes are read as stored (``process=False``), checked
    (:func:`check_finite`), then processed where trimesh processes them on its own
    (:attr:`Reader.merged`): the same meshes as ``trimesh.load(path, **options)``.

    Raises
    ------
    GeometryError
        A vertex with a NaN or infinite coordinate (:func:`check_finite`).
    """

    def load() -> trimesh.Scene:
        try:
            return trimesh.load(str(path), force="scene", process=False, **reader.options)
        except KeyError:  # trimesh cannot merge primitives without a material
            return trimesh.load(str(path), force="scene", process=False)

    if reader.needs == "cascadio":
        from cad.step import read_step

        scene = read_step(path, load)
    else:
        scene = load()
    check_finite(scene, path)
    if reader.merged:
        for geometry in scene.geometry.values():
            if isinstance(geometry, trimesh.Trimesh):
                geometry.process()
    return scene


def check_finite(scene: trimesh.Scene, path: Path) -> None:
    """Refuse a mesh with a NaN or infinite vertex coordinate (trimesh would drop the
    vertex and its triangles without a word: a hole, or a part of another shape).

    Raises
    ------
    GeometryError
        ``FILE: vertex K has a non-finite coordinate (x, y, z)`` (``FILE: mesh 'm':
        ...`` in a file of several), and how many such vertices there are.
    """
    meshes = [(n, g) for n, g in scene.geometry.items() if isinstance(g, trimesh.Trimesh)]
    for name, mesh in meshes:
        vertices = np.asarray(mesh.vertices, dtype=float).reshape(-1, 3)
        bad = np.flatnonzero(~np.isfinite(vertices).all(axis=1))
        if len(bad):
            k = int(bad[0])
            where = f" mesh {name!r}:" if len(meshes) > 1 else ""
            shown = ", ".join(f"{x:g}" for x in vertices[k])
            more = f" ({len(bad)} such vertices of {len(vertices)})" if len(bad) > 1 else ""
            raise GeometryError(
                f"{path}:{where} vertex {k + 1} has a non-finite coordinate ({shown}){more}"
            )


_STEP = Reader(
    name="STEP",
    scene=True,
    options=MappingProxyType({"tol_linear": STEP_CHORD_MM}),
    declares_unit=True,
    default_unit="m",
    mislabel=Mislabel("in", "inches", MAX_INCH_ASSEMBLY_M, 1.0 / 25.4),
    needs="cascadio",
    extra="asmplan[step]",
    merged=False,
)
_GLTF = Reader(
    name="glTF",
    scene=True,
    options=MappingProxyType({"merge_primitives": True}),
    declares_unit=True,
    default_unit="m",
    mislabel=Mislabel("m", "metres (glTF)", MAX_GLTF_ASSEMBLY_M, 1e-3),
    merged=False,
)

READERS: Mapping[str, Reader] = MappingProxyType(
    {
        ".stl": Reader("STL"),
        ".obj": Reader("OBJ", options=MappingProxyType({"split_objects": True})),
        ".ply": Reader("PLY"),
        ".off": Reader("OFF"),
        ".glb": _GLTF,
        ".gltf": _GLTF,
        ".3mf": Reader("3MF", scene=True, declares_unit=True, default_unit="mm"),
        ".3dxml": Reader("3DXML", scene=True, declares_unit=True),
        ".step": _STEP,
        ".stp": _STEP,
    }
)
"""Every suffix asmplan reads (lower case) -> its reader. OBJ: an OBJ's objects (``o
name``) are its parts (one file may hold a whole assembly); glTF: a mesh's primitives (one
per material, as CAD exporters write a part of several colours) are one part, under its
node's own name (unmerged, trimesh makes each a node named with a random suffix); STEP:
tessellated to within :data:`STEP_CHORD_MM` of its surfaces."""

MESH_SUFFIXES = tuple(READERS)
"""Files asmplan reads."""
SCENE_SUFFIXES = tuple(s for s, r in READERS.items() if r.scene)
"""Files that hold several parts (one per mesh node)."""

_FALLBACK = Reader("mesh")
"""Suffixes outside the table: whatever trimesh reads, with no unit and no options."""


def reader_for(path: str | Path) -> Reader:
    """The reader of ``path`` by its suffix (trimesh's own loading for any other suffix).

    Raises
    ------
    GeometryError
        The format needs an optional module that is not installed (STEP: cascadio).
    """
    reader = READERS.get(Path(path).suffix.lower(), _FALLBACK)
    if reader.needs is not None and not _importable(reader.needs):
        raise GeometryError(
            f"cannot read {reader.name} file {path}: install the optional extra "
            f"{reader.extra!r} ({reader.needs})"
        )
    return reader


def is_step(path: str | Path) -> bool:
    """Whether ``path`` is read as a STEP file."""
    return READERS.get(Path(path).suffix.lower()) is _STEP


def is_format(path: str | Path, name: str) -> bool:
    """Whether ``path`` is read by the reader named ``name`` (``"3DXML"``, ``"glTF"``)."""
    return READERS.get(Path(path).suffix.lower(), _FALLBACK).name == name


def _importable(module: str) -> bool:
    import importlib

    try:
        importlib.import_module(module)
    except ImportError:
        return False
    return True
