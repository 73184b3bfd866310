"""Read an assembly: a folder of part meshes, one multi-body scene, or an ``assembly.yaml``.

Accepted inputs of :func:`load_assembly`:

- a folder holding one mesh per part (STL, OBJ, PLY, OFF, GLB, glTF, 3MF, STEP); a
  ``bom.csv`` / ``bom.yaml`` in the folder is picked up automatically;
- one scene file (GLB, glTF, 3MF, or STEP through trimesh's cascadio-based loader):
  one part per geometry node, node transforms applied;
- an ``assembly.yaml`` whose ``parts:`` list holds ``{id, name, file, quantity, type}``
  (``file`` relative to the yaml) and optional ``units:``. Unknown top-level keys are
  ignored, so the spec can carry operations and more.

A BOM (CSV or YAML) has columns/keys ``id, name, file, quantity, type`` (only ``id`` and
``file`` are required; ``type`` e.g. ``screw``). For a scene, ``file`` names the node.

Units: a format that declares its unit wins (glTF/GLB and STEP are metres; 3MF states its
unit), else ``units`` passed in (or the yaml's ``units:``), else millimetres. Meshes are
converted to millimetres on load.
"""

from __future__ import annotations

import csv
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import trimesh
import yaml

from cad.assembly import Assembly, Part, canonical_unit, unit_scale

MESH_SUFFIXES = (".stl", ".obj", ".ply", ".off", ".glb", ".gltf", ".3mf", ".step", ".stp")
BOM_NAMES = ("bom.csv", "bom.yaml", "bom.yml")
_DECLARED_METRES = (".glb", ".gltf", ".step", ".stp")


def load_assembly(
    path: str | Path, units: str | None = None, *, bom: str | Path | None = None
) -> Assembly:
    """Read an assembly from a folder, a scene file or an ``assembly.yaml``.

    Parameters
    ----------
    path : str or Path
        Folder of part meshes, multi-body scene file, or assembly spec (``.yaml``).
    units : str, optional
        Length unit of files that do not declare one (default: the spec's ``units:``,
        else ``"mm"``).
    bom : str or Path, optional
        Explicit BOM file (CSV or YAML); in a folder ``bom.csv``/``bom.yaml`` is found
        automatically.

    Returns
    -------
    Assembly
        Parts in the BOM's (or sorted file/node name) order, meshes in millimetres.

    Raises
    ------
    FileNotFoundError
        The path or a file the BOM names does not exist.
    ValueError
        Unreadable or empty mesh, duplicate part ids, a BOM row without a mesh, unknown
        unit, STEP without the ``cascadio`` extra.
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"assembly not found: {path}")
    if path.is_dir():
        return _load_folder(path, units, bom)
    if path.suffix.lower() in (".yaml", ".yml"):
        return _load_spec(path, units)
    return _load_scene(path, units, bom)


def read_bom(path: str | Path) -> list[dict[str, Any]]:
    """Rows of a BOM file (CSV with a header row, or YAML list / ``{parts: [...]}``).

    Returns
    -------
    list of dict
        One dict per row with keys ``id, name, file, quantity, type`` (strings, quantity
        an int); ``name`` defaults to ``id``.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"BOM not found: {path}")
    try:
        if path.suffix.lower() == ".csv":
            with path.open(newline="", encoding="utf-8-sig") as handle:
                raw = [
                    {str(k).strip().lower(): v for k, v in row.items() if k}
                    for row in csv.DictReader(handle)
                ]
        else:
            data = yaml.safe_load(path.read_text(encoding="utf-8"))
            raw = data.get("parts", []) if isinstance(data, dict) else data
    except (OSError, UnicodeDecodeError, yaml.YAMLError, csv.Error) as exc:
        raise ValueError(f"unreadable BOM {path}: {exc}") from None
    if not isinstance(raw, list):
        raise ValueError(f"BOM {path} must be a list of parts")
    return [_bom_row(row, path, k) for k, row in enumerate(raw)]


def _bom_row(row: Any, path: Path, k: int) -> dict[str, Any]:
    if not isinstance(row, dict):
        raise ValueError(f"BOM {path} row {k + 1} is not a mapping")
    pid = str(row.get("id") or "").strip()
    if not pid:
        raise ValueError(f"BOM {path} row {k + 1} has no id")
    quantity = row.get("quantity")
    try:
        quantity = int(quantity) if quantity not in (None, "") else 1
    except (TypeError, ValueError):
        raise ValueError(
            f"BOM {path} part {pid!r}: quantity {quantity!r} is not an integer"
        ) from None
    return {
        "id": pid,
        "name": str(row.get("name") or pid).strip(),
        "file": str(row.get("file") or "").strip(),
        "quantity": quantity,
        "type": str(row.get("type") or "").strip(),
    }


def prepare_part(
    pid: str,
    mesh: trimesh.Trimesh,
    *,
    scale: float,
    source: str,
    name: str | None = None,
    quantity: int = 1,
    type: str = "",
) -> Part:
    """Validate a mesh, scale it to millimetres and wrap it as a :class:`Part`.

    The mesh is copied, duplicate vertices merged and, for a closed mesh with inward
    normals, the winding flipped. An empty mesh is a ValueError; a mesh that is not
    watertight gives a warning naming the part.
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
    else:
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
    )


def _load_file(path: Path) -> trimesh.Scene:
    """Load any supported file as a scene; clear errors for missing/unreadable files."""
    if not path.is_file():
        raise FileNotFoundError(f"mesh file not found: {path}")
    suffix = path.suffix.lower()
    if suffix not in MESH_SUFFIXES:
        raise ValueError(f"unsupported mesh file {path} (use one of {', '.join(MESH_SUFFIXES)})")
    if suffix in (".step", ".stp"):
        try:
            import cascadio  # noqa: F401
        except ImportError:
            raise ValueError(
                f"cannot read STEP file {path}: install the optional extra "
                "'asmplan[step]' (cascadio)"
            ) from None
    try:
        scene = trimesh.load(str(path), force="scene")
    except Exception as exc:  # trimesh raises many types for bad files
        raise ValueError(f"unreadable mesh file {path}: {type(exc).__name__}: {exc}") from None
    if not isinstance(scene, trimesh.Scene):  # pragma: no cover - force="scene"
        scene = trimesh.Scene(scene)
    return scene


def _declared_units(path: Path, scene: trimesh.Scene) -> str | None:
    """Unit the file format declares, or None."""
    suffix = path.suffix.lower()
    if suffix == ".3mf" or suffix in _DECLARED_METRES:
        declared = scene.units
        if declared is None:
            for geom in scene.geometry.values():
                declared = geom.units or geom.metadata.get("units")
                if declared:
                    break
        if declared is None:
            declared = "mm" if suffix == ".3mf" else "m"
        return canonical_unit(declared)
    return None


def _scene_nodes(scene: trimesh.Scene) -> list[tuple[str, trimesh.Trimesh]]:
    """``(node name, mesh in scene frame)`` for every mesh node, sorted by node name."""
    nodes = []
    for node in sorted(scene.graph.nodes_geometry):
        transform, geom_name = scene.graph[node]
        geom = scene.geometry.get(geom_name)
        if isinstance(geom, trimesh.Trimesh):
            nodes.append((str(node), geom.copy().apply_transform(transform)))
    return nodes


def _file_mesh(path: Path, units: str | None) -> tuple[trimesh.Trimesh, str]:
    """All meshes of one file, merged, with the unit they are in."""
    scene = _load_file(path)
    meshes = [m for _, m in _scene_nodes(scene) if len(m.faces)]
    if not meshes:
        raise ValueError(_no_triangles(path))
    mesh = meshes[0] if len(meshes) == 1 else trimesh.util.concatenate(meshes)
    return mesh, _declared_units(path, scene) or units or "mm"


def _no_triangles(path: Path) -> str:
    if path.stat().st_size == 0:
        return f"empty mesh file {path}"
    return f"unreadable mesh file {path}: no triangles could be read (empty mesh)"


def _combine_units(units: list[str]) -> str:
    distinct = sorted(set(units))
    return distinct[0] if len(distinct) == 1 else "mixed"


def _parts_from_rows(rows: list[dict[str, Any]], base: Path, units: str | None) -> Assembly:
    parts, used = [], []
    for row in rows:
        if not row["file"]:
            raise ValueError(f"BOM part {row['id']!r} has no mesh file")
        file = base / row["file"]
        if not file.exists():
            raise FileNotFoundError(f"mesh file of part {row['id']!r} not found: {file}")
        mesh, unit = _file_mesh(file, units)
        used.append(unit)
        parts.append(
            prepare_part(
                row["id"],
                mesh,
                scale=unit_scale(unit),
                source=str(file),
                name=row["name"],
                quantity=row["quantity"],
                type=row["type"],
            )
        )
    _check_unique([p.id for p in parts], base)
    return Assembly(parts=tuple(parts), units=_combine_units(used), source=str(base))


def _check_unique(ids: list[str], where: Path) -> None:
    seen: set[str] = set()
    for pid in ids:
        if pid in seen:
            raise ValueError(f"duplicate part id {pid!r} in {where}")
        seen.add(pid)


def _load_folder(folder: Path, units: str | None, bom: str | Path | None) -> Assembly:
    if bom is None:
        bom = next((folder / n for n in BOM_NAMES if (folder / n).is_file()), None)
    if bom is not None:
        return _parts_from_rows(read_bom(bom), folder, units)
    files = sorted(f for f in folder.iterdir() if f.is_file() and f.suffix.lower() in MESH_SUFFIXES)
    if not files:
        raise ValueError(f"no mesh files ({', '.join(MESH_SUFFIXES)}) in folder {folder}")
    rows = [
        {"id": f.stem, "name": f.stem, "file": f.name, "quantity": 1, "type": ""} for f in files
    ]
    return _parts_from_rows(rows, folder, units)


def _load_spec(path: Path, units: str | None) -> Assembly:
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as exc:
        raise ValueError(f"unreadable assembly spec {path}: {exc}") from None
    if not isinstance(data, dict) or not isinstance(data.get("parts"), list):
        raise ValueError(f"assembly spec {path} needs a 'parts:' list")
    spec_units = units or data.get("units") or "mm"
    unit_scale(spec_units)  # validate early
    rows = [_bom_row(row, path, k) for k, row in enumerate(data["parts"])]
    return _parts_from_rows(rows, path.parent, spec_units)


def _load_scene(path: Path, units: str | None, bom: str | Path | None) -> Assembly:
    scene = _load_file(path)
    unit = _declared_units(path, scene) or units or "mm"
    scale = unit_scale(unit)
    nodes = _scene_nodes(scene)
    if not nodes:
        raise ValueError(_no_triangles(path))
    if bom is None:
        parts = [prepare_part(n, m, scale=scale, source=f"{path}#{n}") for n, m in nodes]
    else:
        by_name = dict(nodes)
        parts = []
        for row in read_bom(bom):
            node = row["file"] or row["id"]
            if node not in by_name:
                raise ValueError(f"BOM part {row['id']!r}: no mesh node {node!r} in {path}")
            parts.append(
                prepare_part(
                    row["id"],
                    by_name[node],
                    scale=scale,
                    source=f"{path}#{node}",
                    name=row["name"],
                    quantity=row["quantity"],
                    type=row["type"],
                )
            )
    _check_unique([p.id for p in parts], path)
    return Assembly(parts=tuple(parts), units=unit, source=str(path))
