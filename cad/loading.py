"""Read an assembly's geometry: a folder of part meshes, one scene file, or part records.

Accepted inputs of :func:`load_assembly`:

- a folder holding one mesh per part (STL, OBJ, PLY, OFF, GLB, glTF, 3MF, STEP); a
  ``bom.csv`` / ``bom.yaml`` in the folder is picked up automatically;
- one scene file (GLB, glTF, 3MF, 3DXML, or STEP through trimesh's cascadio-based
  loader): one part per mesh node, node transforms applied, part ids and groups from the
  file's names and tree (:mod:`cad.scene`).

:func:`load_parts` reads the meshes that part records name (:mod:`cad.bom`): this is how
the parts of an ``assembly.yaml`` get their geometry (the spec itself is read by
``asp.spec``; cad takes parts, not YAML). A record's ``file`` is a mesh file relative to
the base folder, or ``scene.step#node`` for one part of a scene file.

Units: a format that declares its unit wins (glTF/GLB and STEP are metres; 3MF states its
unit), else ``units`` passed in, else millimetres. Meshes are converted to millimetres on
load.

Frame: ``frame`` (a rotation, :mod:`cad.frame`; a spec's ``frame:``) turns every part into
the build frame once, here, after the unit conversion; None keeps the file's own frame.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import trimesh

from cad.assembly import Assembly, prepare_part, warn_not_watertight
from cad.bom import PartRecord, read_bom
from cad.errors import GeometryError
from cad.frame import Rotation, rotated
from cad.merging import merge_overlapping
from cad.readers import MESH_SUFFIXES
from cad.scene import empty_scene_error, read_scene, warn_split
from cad.unit_hints import part_scale_hint
from cad.units import unit_scale

BOM_NAMES = ("bom.csv", "bom.yaml", "bom.yml")
METRES_ONLY = ((1000.0, "metres"),)
"""Size ratios warned about on load (small parts are often 10-60 times smaller)."""


def load_assembly(
    path: str | Path,
    units: str | None = None,
    *,
    bom: str | Path | None = None,
    frame: Rotation | None = None,
) -> Assembly:
    """Read an assembly from a folder of part meshes or a scene file.

    Parameters
    ----------
    path : str or Path
        Folder of part meshes, or multi-body scene file.
    units : str, optional
        Length unit of files that do not declare one (default ``"mm"``).
    bom : str or Path, optional
        Explicit BOM file (CSV or YAML); in a folder ``bom.csv``/``bom.yaml`` is found
        automatically.
    frame : 3x3 rotation, optional
        The build frame (:mod:`cad.frame`): every mesh is turned by it (None: the file's).

    Returns
    -------
    Assembly
        Parts in the BOM's order (else sorted file names, or the scene's order), meshes in
        millimetres; ``groups`` from a scene's hierarchy.

    Raises
    ------
    FileNotFoundError
        The path or a file the BOM names does not exist.
    GeometryError
        Unreadable or empty mesh, duplicate part ids, a BOM row without a mesh, unknown
        unit, STEP without the ``cascadio`` extra, an ``assembly.yaml`` (read it with
        ``asp.spec.load_spec``).
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"assembly not found: {path}")
    if units is not None:
        unit_scale(units)  # validate early
    if path.is_dir():
        if bom is None:
            bom = next((path / n for n in BOM_NAMES if (path / n).is_file()), None)
        records = read_bom(bom) if bom is not None else folder_records(path)
        return load_parts(records, path, units, frame=frame)
    if path.suffix.lower() in (".yaml", ".yml"):
        raise GeometryError(
            f"{path}: an assembly spec is read by asp.spec.load_spec (cad.load_parts takes "
            "its parts)"
        )
    if bom is None:
        return rotated(_scene_assembly(path, units), frame)
    records = [
        PartRecord(**{**r.__dict__, "file": f"{path.name}#{r.file or r.id}"}) for r in read_bom(bom)
    ]
    return load_parts(records, path.parent, units, frame=frame)


def folder_records(folder: Path) -> tuple[PartRecord, ...]:
    """One record per mesh file of ``folder`` (sorted by name), id = the file's stem."""
    files = sorted(f for f in folder.iterdir() if f.is_file() and f.suffix.lower() in MESH_SUFFIXES)
    if not files:
        raise GeometryError(f"no mesh files ({', '.join(MESH_SUFFIXES)}) in folder {folder}")
    return tuple(PartRecord(id=f.stem, name=f.stem, file=f.name) for f in files)


def load_parts(
    records: Sequence[PartRecord],
    base: str | Path,
    units: str | None = None,
    *,
    frame: Rotation | None = None,
) -> Assembly:
    """The geometry of part records: each record's mesh, in millimetres.

    Parameters
    ----------
    records : sequence of PartRecord
        Parts with a ``file`` (relative to ``base``; ``scene#node`` for one node of a
        scene file, the node's cleaned id or its name in the file).
    base : str or Path
        Folder the files are relative to.
    units : str, optional
        Unit of files that do not declare one (default ``"mm"``).
    frame : 3x3 rotation, optional
        The build frame (:mod:`cad.frame`): every mesh is turned by it (None: the file's).

    Returns
    -------
    Assembly
        One part per record, in order; ``units`` ``"mixed"`` if the files differ.
    """
    base = Path(base)
    parts, used = [], []
    for row in records:
        if not row.file:
            raise GeometryError(f"BOM part {row.id!r} has no mesh file")
        mesh, unit, source = _record_mesh(row, base, units)
        used.append(unit)
        parts.append(
            prepare_part(
                row.id,
                mesh,
                scale=unit_scale(unit),
                source=source,
                name=row.name,
                quantity=row.quantity,
                type=row.type,
                shape=row.shape,
                warn=False,
            )
        )
    warn_not_watertight(parts, str(base))
    _check_unique([p.id for p in parts], base)
    distinct = sorted(set(used))
    combined = distinct[0] if len(distinct) == 1 else ("mixed" if distinct else units or "mm")
    assembly = Assembly(parts=tuple(parts), units=combined, source=str(base))
    warn_part_scales(assembly)
    return rotated(assembly, frame)


def warn_part_scales(assembly: Assembly) -> None:
    """A warning for each part of three or more about 1000 times smaller or larger than
    the others (its file in metres, read as millimetres: :func:`cad.unit_hints.part_scale_hint`)."""
    for k in range(len(assembly.parts) if len(assembly.parts) > 2 else 0):
        hint = part_scale_hint(assembly, k, factors=METRES_ONLY)
        if hint:
            warnings.warn(hint, stacklevel=3)


def _record_mesh(row: PartRecord, base: Path, units: str | None):
    """``(mesh in file units, unit, source text)`` of one record (``file#node``: one node
    of a scene, unless a file of that whole name exists: ``bearing#1.stl``)."""
    whole = _is_file(base / str(row.file))
    name, _, node = (str(row.file), "", "") if whole else str(row.file).partition("#")
    file = base / name
    if not file.exists():
        raise FileNotFoundError(f"mesh file of part {row.id!r} not found: {file}")
    scene = read_scene(file)
    unit = scene.units or units or "mm"
    if node:
        k = scene.find(node)
        entire = scene.whole(node)
        if entire is not None:  # a part split into its bodies, named whole
            return entire, unit, f"{file}#{node}"
        if k is None:
            raise GeometryError(
                f"part {row.id!r}: no part {node!r} in {file} (its parts: "
                f"{', '.join(scene.ids[:12])}{', ...' if len(scene.ids) > 12 else ''})"
            )
        return scene.meshes[k], unit, f"{file}#{scene.ids[k]}"
    if not scene.meshes:
        raise empty_scene_error(file)
    meshes = scene.meshes
    mesh = meshes[0] if len(meshes) == 1 else trimesh.util.concatenate(list(meshes))
    return mesh, unit, str(file)


def _is_file(path: Path) -> bool:
    """Whether ``path`` is a file; a name that cannot be a file name on this system (a
    ``file#node`` listing a joined part's nodes may be longer than a name may be) is never
    asked of the system: it is no file."""
    return could_be_file_name(path) and path.is_file()


def could_be_file_name(path: Path) -> bool:
    """Whether every component of ``path`` fits the system's longest file name and the
    whole its longest path (``NAME_MAX``, ``PATH_MAX`` of the file system holding the
    path's root, or the working folder for a relative path; 255 and 4096 bytes where the
    system does not say): past them the system refuses the name (ENAMETOOLONG) rather
    than saying no such file exists."""
    folder = Path(path.anchor or ".")
    name_max, path_max = _limit(folder, "PC_NAME_MAX", 255), _limit(folder, "PC_PATH_MAX", 4096)
    parts = [os.fsencode(part) for part in path.parts]
    return all(len(p) <= name_max for p in parts) and len(os.fsencode(str(path))) < path_max


def _limit(folder: Path, name: str, default: int) -> int:
    try:
        return int(os.pathconf(folder, name))
    except (OSError, ValueError, AttributeError):  # not a POSIX system, or no such limit
        return default


def _scene_assembly(path: Path, units: str | None) -> Assembly:
    scene = read_scene(path)
    if not scene.meshes:
        raise empty_scene_error(path)
    warn_split(path, scene)
    unit = scene.units or units or "mm"
    scale = unit_scale(unit)
    parts = tuple(
        prepare_part(pid, mesh, scale=scale, source=f"{path}#{pid}", name=name, warn=False)
        for pid, name, mesh in zip(scene.ids, scene.names, scene.meshes, strict=True)
    )
    warn_not_watertight(parts, str(path))
    _check_unique([p.id for p in parts], path)
    assembly = Assembly(parts=parts, units=unit, source=str(path), groups=scene.groups)
    return merge_overlapping(assembly, path.name)


def apply_bom(assembly: Assembly, records: Sequence[PartRecord], base: Path) -> Assembly:
    """A scene's parts with a BOM's data: a row naming a part (by id, or ``file`` naming
    its node) overrides its id, name, quantity, type and shape; a row with a mesh file of
    its own adds a part.
    """
    parts = list(assembly.parts)
    renamed: dict[str, str] = {}
    added: list[PartRecord] = []
    for row in records:
        node = str(row.file or "").rpartition("#")[2] or row.id
        hits = [k for k, p in enumerate(parts) if node in (p.id, p.name) or row.id == p.id]
        if not hits:
            if not row.file or not (base / str(row.file).partition("#")[0]).is_file():
                raise GeometryError(
                    f"BOM part {row.id!r}: no part {node!r} in {assembly.source} and no mesh "
                    "file of its own"
                )
            added.append(row)
            continue
        k = hits[0]
        old = parts[k]
        renamed[old.id] = row.id
        parts[k] = replace(
            old,
            id=row.id,
            name=row.name if row.name != row.id or old.name == old.id else old.name,
            quantity=row.quantity,
            type=row.type or old.type,
            shape=row.shape or old.shape,
        )
    if added:
        parts += load_parts(added, base, frame=assembly.frame).parts
    _check_unique([p.id for p in parts], base)
    groups = tuple(
        (gid, tuple(renamed.get(m, m) for m in members)) for gid, members in assembly.groups
    )
    return replace(assembly, parts=tuple(parts), groups=groups)


def _check_unique(ids: list[str], where: Path) -> None:
    seen: set[str] = set()
    for pid in ids:
        if pid in seen:
            raise GeometryError(f"duplicate part id {pid!r} in {where}")
        seen.add(pid)
