"""Scene files: one part per mesh node, named from the file, with the file's hierarchy.

A scene (STEP through cascadio, GLB/glTF, 3MF, 3DXML) is a tree of nodes. Every node
that carries a mesh is a part; every other node with two or more parts below it is a
group of the file's hierarchy (a STEP sub-assembly, a glTF parent node).

Part ids are the names the file gives, cleaned into short unique ids (:func:`clean_name`,
:func:`unique_ids`): ``"Hex Nut M6<2>"`` -> ``hex_nut_m6``, numbered when a name repeats
(``nut_1``, ``nut_2``), in the file's order. Instance paths and numbers
(``bearing#1:23:2:16``, ``Bolt:1``, ``Part1<3>``) are cut off; names that say nothing
(``NAUO7``, ``12``, ``Open CASCADE STEP translator 7.8 1.1``, ``mesh_0``, and OCCT's
reference labels ``=>[0:1:1:7]`` that cascadio gives the shape nodes of Pro/E and Creo
exports) give way to the mesh's name or the nearest named parent (``L-BRACKET`` ->
``l_bracket_1``), else ``part``. A part's display name comes from the same node.

A file of one part whose mesh is several closed bodies (a product fused into one solid)
gives one part per body, ``<part>_body_<n>`` (:func:`cad.bodies.closed_bodies`; said in a
warning); a spec part whose file names the whole part (``truck.stp#truck``) keeps it one
rigid part.
"""

from __future__ import annotations

import re
from collections import Counter
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
import trimesh

from cad.bodies import closed_bodies
from cad.errors import GeometryError
from cad.readers import (  # noqa: F401  (re-exported: cad.scene is where callers look)
    MAX_GLTF_ASSEMBLY_M,
    MAX_INCH_ASSEMBLY_M,
    SCENE_SUFFIXES,
    STEP_CHORD_MM,
    is_format,
    is_step,
    reader_for,
)
from cad.step import document_files, solid_shells
from cad.units import canonical_unit, unit_scale

MAX_ID_LENGTH = 32
_EXTENSIONS = r"\.(stp|step|sldprt|sldasm|ipt|iam|prt|asm|stl|obj|glb|gltf|3mf)$"

_GENERIC = re.compile(
    r"^((nauo|solid|body|mesh|shape|geometry|node|object|component|compound|part|g)_?\d*|"
    r"\d+(_\d+)*|unnamed\w*|noname\w*|default\w*|world|root|scene|open_cascade_step_translator\w*|"
    r"p(_\d+)+)$"  # an instance path or label (cascadio's ``=>[0:1:1:7]``) cleaned
)

_REFERENCE_LABEL = re.compile(r"=>\[[\d:]*\]")
"""OCCT's label of a referred shape (``=>[0:1:1:7]``): an instance path, never a name."""


def clean_name(raw: str) -> str:
    """A short lowercase id from a CAD name (empty if nothing is left).

    Instance suffixes (``#...``, ``:1``, ``<2>``, ``(3)``) and file extensions are cut off,
    everything but letters and digits becomes ``_``, at most :data:`MAX_ID_LENGTH` chars:
    a longer name loses its leading words (a library's prefix), never its tail (what tells
    ``XBee-10pin-male`` from ``XBee-Chip-antenna``).
    """
    name = _full_name(raw)
    if len(name) > MAX_ID_LENGTH:  # the tail tells variants apart (``..._10pin_male``)
        words = name.split("_")
        while len(words) > 1 and len("_".join(words)) > MAX_ID_LENGTH:
            words.pop(0)
        name = "_".join(words)[-MAX_ID_LENGTH:].strip("_")
    if name and name[0].isdigit() and not name.isdigit():
        name = "p_" + name
    return name


def _full_name(raw: str) -> str:
    """:func:`clean_name` before its cut to :data:`MAX_ID_LENGTH` (and its ``p_`` prefix)."""
    name = _REFERENCE_LABEL.sub("", str(raw)).strip()
    name = re.split(r"[#<]", name, maxsplit=1)[0]
    name = re.sub(r":\d+$", "", name)
    name = re.sub(r"\(\d+\)$", "", name)
    name = re.sub(_EXTENSIONS, "", name, flags=re.IGNORECASE)
    return re.sub(r"[^0-9a-zA-Z]+", "_", name).strip("_").lower()


def display_name(raw: str) -> str:
    """A CAD name without its instance path or number (``Washer#1:8:6`` -> ``Washer``,
    ``Bolt<2>`` -> ``Bolt``); any other ``<`` is the name's own (``Tom <b>`` stays)."""
    name = re.split(r"#|<\d+>", str(raw), maxsplit=1)[0]
    return re.sub(r"(:\d+|\(\d+\))$", "", name).strip() or str(raw)


def is_generic(name: str) -> bool:
    """True for a cleaned name that says nothing about the part (``nauo7``, ``12``, ``mesh``)."""
    return not name or bool(_GENERIC.match(name))


def best_name(candidates: list[str], fallback: str = "part") -> str:
    """The first meaningful cleaned name among ``candidates`` (raw names), else ``fallback``."""
    raw = best_raw(candidates)
    return fallback if raw is None else clean_name(raw)


def best_raw(candidates: list[str]) -> str | None:
    """The first of ``candidates`` (raw names) whose cleaned name is meaningful, or None."""
    return next((raw for raw in candidates if not is_generic(_full_name(raw))), None)


_PLAIN = re.compile(r"^(\d+(_\d+)*|(body|solid|part|component)_?\d*)$")
"""A name that is generic but the modeller's own: an item number (``3_001``, a drawing's
balloon) or a body word (``body_001``); better than the product's name or ``part``."""


def plain_raw(candidates: list[str]) -> str | None:
    """The first of ``candidates`` (raw names) that is a plain item number or body word
    (:data:`_PLAIN`; never an OCCT label, ``NAUO7`` or ``mesh_0``), or None."""
    for raw in candidates:
        if _REFERENCE_LABEL.search(str(raw)):
            continue
        digits = re.sub(r"[^0-9a-zA-Z]+", "_", str(raw)).strip("_").lower()
        if digits and _PLAIN.match(digits):
            return str(raw)
    return None


def part_id(raw: str) -> str:
    """The id of a part named ``raw``: :func:`clean_name`, an item number as ``part_3_001``."""
    name = clean_name(raw)
    return "part_" + name.removeprefix("p_") if re.fullmatch(r"(p_)?\d+(_\d+)*", name) else name


def unique_ids(names: list[str], taken: set[str] | None = None) -> list[str]:
    """Number repeated names in order (``nut`` x2 -> ``nut_1``, ``nut_2``); keep single ones.

    ``taken`` ids are avoided as well (a suffix ``_<n>`` is added until free).
    """
    taken = set() if taken is None else set(taken)
    counts = Counter(names)
    seen: Counter[str] = Counter()
    out = []
    for name in names:
        if counts[name] > 1:
            seen[name] += 1
            candidate = f"{name}_{seen[name]}"
        else:
            candidate = name
        k = 1
        base = candidate
        while candidate in taken:
            k += 1
            candidate = f"{base}_{k}"
        taken.add(candidate)
        out.append(candidate)
    return out


@dataclass(frozen=True, eq=False)
class SceneParts:
    """The parts of a scene file.

    Attributes
    ----------
    ids : tuple of str
        Cleaned unique part ids, in the file's order.
    names : tuple of str
        The node names as the file gives them, without instance paths (``#1:2:3``).
    meshes : tuple of trimesh.Trimesh
        Each part's mesh in the scene frame, in the file's unit. Shared: copy to change.
    groups : tuple of (str, tuple of str)
        The file's hierarchy: group id -> ids of the parts below it (groups of two parts
        or more, outermost first; the root is not a group).
    units : str or None
        The unit the file declares (short name), or None.
    nodes : tuple of str
        Each part's scene-graph node as trimesh names it (``trimesh.load(file,
        force="scene").graph[node]`` gives its transform and geometry): what a reader of
        ``plan.json`` looks a part up by.
    rescale : float
        Factor from the coordinates trimesh reads to ``meshes`` (1.0 unless the file holds
        millimetre numbers under a wrong unit label, :func:`_millimetre_numbers`).
    split : tuple of (str, tuple of str)
        A part of the file split into its closed bodies: its id -> the ids of its bodies
        (``truck`` -> ``truck_body_1``, ...; a one-part file only, :mod:`cad.bodies`).
    """

    ids: tuple[str, ...]
    names: tuple[str, ...]
    meshes: tuple[trimesh.Trimesh, ...]
    groups: tuple[tuple[str, tuple[str, ...]], ...]
    units: str | None
    nodes: tuple[str, ...] = ()
    rescale: float = 1.0
    split: tuple[tuple[str, tuple[str, ...]], ...] = ()

    def find(self, node: str) -> int | None:
        """Index of the part whose id, name or scene-graph node is ``node`` (None if none)."""
        for k, (pid, name) in enumerate(zip(self.ids, self.names, strict=True)):
            if node in (pid, name):
                return k
        return self.nodes.index(node) if node in self.nodes else None

    def whole(self, node: str) -> trimesh.Trimesh | None:
        """One mesh of several parts, or None: ``node`` names a part split into bodies
        (its id), a group of the file's hierarchy (its id), or parts joined by ``+``
        (``spring_link_1+spring_link_2``: one rigid part, :mod:`cad.merging`)."""
        members = dict(self.split).get(node) or dict(self.groups).get(node)
        if members is None and "+" in node:
            members = tuple(node.split("+"))
        if members is None:
            return None
        found = [self.find(m) for m in members]
        if None in found:
            return None
        return trimesh.util.concatenate([self.meshes[k] for k in found])


def gltf_buffer_problem(path: Path) -> str:
    """Why a glTF's buffers cannot be read, in words (``""``: no such problem found): a
    buffer's ``uri`` naming a file that is not beside it, or ``data:`` whose payload is not
    the base64 of its declared ``byteLength`` (a reader asserts instead of saying so)."""
    import base64
    import binascii
    import json

    if path.suffix.lower() != ".gltf":
        return ""
    try:
        buffers = json.loads(path.read_text(encoding="utf-8")).get("buffers", [])
    except (OSError, UnicodeDecodeError, ValueError, AttributeError):
        return ""
    for k, buffer in enumerate(buffers if isinstance(buffers, list) else []):
        uri = str(buffer.get("uri", "")) if isinstance(buffer, dict) else ""
        size = buffer.get("byteLength") if isinstance(buffer, dict) else None
        shown = uri if len(uri) <= 60 else uri[:57] + "..."
        if uri.startswith("data:"):
            try:
                data = base64.b64decode(uri.partition(",")[2], validate=True)
            except (binascii.Error, ValueError):
                return f"buffer {k}'s uri {shown!r} is data that is not base64"
            if isinstance(size, int) and len(data) < size:
                return f"buffer {k}'s data holds {len(data)} bytes, its byteLength says {size}"
        elif uri and not (path.parent / uri).is_file():
            return f"buffer {k}'s file {shown!r} is not beside it"
    return ""


def load_scene_file(path: Path) -> trimesh.Scene:
    """Load a mesh or scene file as a trimesh scene (its reader, :mod:`cad.readers`);
    one-line errors for bad files."""
    if not path.is_file():
        raise FileNotFoundError(f"mesh file not found: {path}")
    reader = reader_for(path)
    if path.stat().st_size == 0:
        raise GeometryError(f"empty mesh file {path}")
    try:
        scene = reader.load(path)
    except GeometryError:
        if external_references(path):  # OCCT read nothing: the parts live elsewhere
            raise empty_scene_error(path) from None
        raise
    except Exception as exc:  # trimesh raises many types for bad files
        if external_references(path):
            raise empty_scene_error(path) from None
        why = gltf_buffer_problem(path) or f"{type(exc).__name__}: {exc}"
        raise GeometryError(f"unreadable mesh file {path}: {why}") from None
    if not isinstance(scene, trimesh.Scene):  # pragma: no cover - force="scene"
        scene = trimesh.Scene(scene)
    return scene


def load_options(path: Path) -> dict:
    """Keywords for ``trimesh.load`` of a file (its reader's, :data:`cad.readers.READERS`)."""
    return dict(reader_for(path).options)


def empty_scene_error(path: Path) -> GeometryError:
    """The one-line error for a file with no triangles; names the files a STEP refers to
    (``DOCUMENT_FILE``: an assembly whose parts live in other files, which OCCT does not
    follow)."""
    referred = external_references(path)
    if referred:
        shown = ", ".join(referred[:6]) + (", ..." if len(referred) > 6 else "")
        return GeometryError(
            f"{path} holds no geometry of its own: it references external files ({shown}); "
            "export the assembly as one STEP file with its parts embedded"
        )
    return GeometryError(f"unreadable mesh file {path}: no triangles could be read (empty mesh)")


def external_references(path: Path) -> tuple[str, ...]:
    """The files a STEP file's ``DOCUMENT_FILE`` entities name (empty for other formats)."""
    return document_files(path) if is_step(path) else ()


def declared_units(path: Path, scene: trimesh.Scene) -> str | None:
    """The unit the file format declares (short name), or None."""
    reader = reader_for(path)
    if not reader.declares_unit:
        return None
    declared = scene.units
    if declared is None:
        for geom in scene.geometry.values():
            declared = geom.units or geom.metadata.get("units")
            if declared:
                break
    declared = declared or reader.default_unit
    return None if declared is None else canonical_unit(declared)


def read_scene(path: str | Path) -> SceneParts:
    """The named parts and hierarchy of a scene file (cached while the file is unchanged)."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"mesh file not found: {path}")
    stat = path.stat()
    return _read_scene_cached(str(path.resolve()), stat.st_mtime_ns, stat.st_size)


@lru_cache(maxsize=4)
def _read_scene_cached(path: str, _mtime: int, _size: int) -> SceneParts:
    file = Path(path)
    scene = load_scene_file(file)
    graph = scene.graph
    children: dict[str, list[str]] = {}
    for parent, child in graph.transforms.edge_data:
        children.setdefault(str(parent), []).append(str(child))
    all_nodes = set(graph.nodes)

    def original(node: str) -> str:
        """Undo trimesh's renaming of a repeated node name (``Cap_1`` next to ``Cap``)."""
        match = re.match(r"^(.*)_\d+$", node)
        return match.group(1) if match and match.group(1) in all_nodes else node

    part_nodes: list[tuple[str, list[str]]] = []  # (node, ancestors nearest first)
    group_nodes: list[tuple[str, list[str]]] = []  # (node, part nodes below)

    def walk(node: str, ancestors: list[str]) -> list[str]:
        below: list[str] = []
        geom_name = graph.transforms.node_data.get(node, {}).get("geometry")
        geom = scene.geometry.get(geom_name) if geom_name is not None else None
        if isinstance(geom, trimesh.Trimesh) and len(geom.faces):
            part_nodes.append((node, ancestors))
            below.append(node)
        slot = len(group_nodes)
        for child in sorted(children.get(node, []), key=_natural):
            below += walk(child, [node, *ancestors])
        if geom_name is None and ancestors and len(below) >= 2:
            group_nodes.insert(slot, (node, list(below)))
        return below

    walk(graph.base_frame, [])
    # a node over every part is the product itself: its name is no part's name while a
    # part has a plain name of its own (a pen's ``body_001``, a mold's item ``3_001``)
    whole = {g for g, below in group_nodes if len(below) == len(part_nodes) > 1}
    if is_format(file, "3DXML"):  # trimesh flattens the tree into the node names
        group_nodes = _3dxml_groups(file, [node for node, _ in part_nodes])
    # the node holding every part (the product itself) is not a group
    group_nodes = [(g, b) for g, b in group_nodes if len(b) < len(part_nodes)]

    rescale = _millimetre_numbers(file, scene)
    references = _3dxml_reference_names(file) if is_format(file, "3DXML") else {}
    names, meshes, bases, generic = [], [], [], []
    for node, graph_anc in part_nodes:
        transform, geom_name = graph[node]
        mesh = scene.geometry[geom_name].copy().apply_transform(transform)
        meshes.append(mesh.apply_scale(rescale) if rescale != 1.0 else mesh)
        own = [original(node), str(geom_name)]
        anc = _3dxml_ancestors(node, references) if references else graph_anc
        # never the product's own name (the node over every part): no such part is in
        # the tree; a part named by nothing is named by its shape (``alike_a``)
        raw = best_raw(own + [original(a) for a in anc if a not in whole]) or plain_raw(own)
        names.append(display_name(original(node) if raw is None else raw))
        bases.append("part" if raw is None else part_id(raw))
        generic.append(raw is None or bool(_BODY_WORD.match(clean_name(raw))))
    bases = _alike_bases(bases, generic, meshes)
    ids = unique_ids(bases)
    check_solid(file, ids, meshes)
    split = ()
    shells = solid_shells(file) if len(meshes) == 1 and is_format(file, "STEP") else None
    if len(meshes) == 1 and (bodies := closed_bodies(meshes[0], shells)) is not None:
        split = ((ids[0], tuple(f"{ids[0]}_body_{n}" for n in range(1, len(bodies) + 1))),)
        meshes, names = list(bodies), [f"{names[0]} body {n}" for n in range(1, len(bodies) + 1)]
        part_nodes, ids = part_nodes * len(bodies), list(split[0][1])
    id_of = {node: pid for (node, _), pid in zip(part_nodes, ids, strict=True)}
    group_ids = unique_ids(
        [best_name([original(g)], fallback="group") for g, _ in group_nodes], taken=set(ids)
    )
    groups = tuple(
        (gid, tuple(id_of[n] for n in below))
        for gid, (_, below) in zip(group_ids, group_nodes, strict=True)
    )
    return SceneParts(
        ids=tuple(ids),
        names=tuple(names),
        meshes=tuple(meshes),
        groups=groups,
        units=declared_units(file, scene),
        nodes=tuple(str(node) for node, _ in part_nodes),
        rescale=rescale,
        split=split,
    )


ZERO_AREA = 1e-12
"""A mesh has no area when its triangles' area is at most this times its largest extent
squared (every triangle collapsed to a line or a point, up to rounding)."""


def check_solid(file: Path, ids: list[str], meshes: list[trimesh.Trimesh]) -> None:
    """Refuse a part whose triangles all have zero area (:data:`ZERO_AREA`): it has no
    surface, so no size, contact or motion; planned, it is a part of size 0.

    Raises
    ------
    GeometryError
        ``FILE: no solid geometry: all N triangles have zero area`` (``FILE: part 'x':
        ...`` in a file of several).
    """
    for pid, mesh in zip(ids, meshes, strict=True):
        extent = float(np.max(mesh.extents)) if len(mesh.vertices) else 0.0
        if mesh.area <= ZERO_AREA * extent**2:
            part = f" part {pid!r}:" if len(meshes) > 1 else ""
            n = len(mesh.faces)
            each = "its one triangle has" if n == 1 else f"all {n:,} triangles have"
            raise GeometryError(f"{file}:{part} no solid geometry: {each} zero area (degenerate)")


def warn_split(file: Path, scene: SceneParts) -> None:
    """Say that the one part of ``file`` is planned as its closed bodies (when it is):
    called where the bodies become parts (a bare scene file), never where a spec names
    the file's part (then it is one rigid part and nothing is split)."""
    import warnings

    if not scene.split:
        return
    part, bodies = scene.split[0]
    count = len(bodies)
    warnings.warn(
        f"{file.name}: its one part {part} is {count} separate closed bodies: planned as "
        f"{count} parts {part}_body_1..{count} (cad/bodies.py); a spec part with "
        f"file: {file.name}#{part} keeps it one rigid part",
        stacklevel=3,
    )


def coordinate_scale(path: str | Path, units: str | None = None) -> float:
    """Millimetres per coordinate of ``path`` as ``trimesh.load`` reads it.

    The unit is the one the file declares, else ``units`` (a spec's), else millimetres;
    times the factor of millimetre numbers under a wrong unit label (:class:`SceneParts`
    ``rescale``). A checker multiplies what trimesh reads by it to get the parts in mm.
    """
    scene = read_scene(path)
    return unit_scale(scene.units or units or "mm") * scene.rescale


def step_length_unit(path: Path) -> str | None:
    """The length unit of a STEP file's first ``GLOBAL_UNIT_ASSIGNED_CONTEXT`` (``"in"``,
    ``"mm"``, ``"m"``, ...), read from the text; None when there is none or it is unknown.

    The unit is a ``CONVERSION_BASED_UNIT('INCH' | 'FOOT', ...)`` or an
    ``SI_UNIT(prefix, .METRE.)``, among the context's units the one that is a
    ``LENGTH_UNIT``.
    """
    if not is_step(path):
        return None
    try:
        text = path.read_text(encoding="latin-1")
    except OSError:
        return None
    context = re.search(r"GLOBAL_UNIT_ASSIGNED_CONTEXT\s*\(\s*\(([^)]*)\)", text)
    for ref in re.findall(r"#\d+", context.group(1)) if context else []:
        entity = re.search(rf"{ref}\s*=([^;]*);", text)
        if entity is None or "LENGTH_UNIT" not in entity.group(1):
            continue
        body = entity.group(1)
        named = re.search(r"CONVERSION_BASED_UNIT\s*\(\s*'([A-Za-z ]+)'", body)
        if named:
            return {"inch": "in", "foot": "ft"}.get(named.group(1).strip().lower())
        si = re.search(r"SI_UNIT\s*\(\s*(\$|\.\w+\.)\s*,\s*\.METRE\.", body)
        if si:
            prefix = si.group(1).strip(".").upper()
            return {"$": "m", "MILLI": "mm", "CENTI": "cm", "MICRO": "um"}.get(prefix)
    return None


def _millimetre_numbers(path: Path, scene: trimesh.Scene) -> float:
    """The factor that reads a file's millimetre numbers under a wrong unit label as mm
    (1.0 when the label is plausible), with a warning.

    A STEP declaring inches whose parts, read so, span more than
    :data:`MAX_INCH_ASSEMBLY_M`: 1 / 25.4; a glTF/GLB in metres (glTF's default: it
    declares no other unit) spanning more than :data:`MAX_GLTF_ASSEMBLY_M`: 1 / 1000.
    """
    mislabel = reader_for(path).mislabel
    if scene.bounds is None or mislabel is None:
        return 1.0
    size = float(np.linalg.norm(np.ptp(scene.bounds, axis=0)))  # metres (cascadio, glTF)
    declared = step_length_unit(path) if is_step(path) else declared_units(path, scene)
    if declared != mislabel.unit:
        return 1.0  # the file says another unit: no default to doubt
    label, limit, factor = mislabel.label, mislabel.limit_m, mislabel.factor
    if size <= limit:
        return 1.0
    import warnings

    warnings.warn(
        f"{path.name} declares {label}, but read so it is {size:.3g} m across: its numbers "
        f"are taken as millimetres ({size * factor * 1000:.0f} mm across; rule in "
        "cad/scene.py)",
        stacklevel=2,
    )
    return factor


_BODY_WORD = re.compile(r"^((body|solid|part|component)_?\d*)$")
"""A cleaned name that is a CAD tool's default for a body (FreeCAD's ``Body001``)."""


def _alike_bases(bases: list[str], generic: list[bool], meshes: list) -> list[str]:
    """Ids for parts the file names generically (a default body name, or none): when two or
    more are, each is named by its class of identical parts (:mod:`cad.identical`),
    ``alike_a``, ``alike_b``, ... in the file's order (numbered by :func:`unique_ids`)."""
    from cad.identical import alike_labels

    which = [k for k, g in enumerate(generic) if g]
    if len(which) < 2:
        return bases
    labels = alike_labels([meshes[k] for k in which])
    out = list(bases)
    for k, label in zip(which, labels, strict=True):
        out[k] = f"alike_{_letters(label)}"
    return out


def _letters(number: int) -> str:
    """``0`` -> ``a``, ``25`` -> ``z``, ``26`` -> ``aa``: a class's letter."""
    text = ""
    number += 1
    while number:
        number, rest = divmod(number - 1, 26)
        text = chr(ord("a") + rest) + text
    return text


def _3dxml_reference_names(file: Path) -> dict[str, str]:
    """The names of a 3DXML's ``Reference3D`` elements by id (empty if unreadable)."""
    import zipfile
    from xml.etree import ElementTree

    names: dict[str, str] = {}
    try:
        with zipfile.ZipFile(file) as archive:
            for member in archive.namelist():
                if not member.lower().endswith(".3dxml"):
                    continue
                root = ElementTree.fromstring(archive.read(member))
                for element in root.iter():
                    if element.tag.rsplit("}", 1)[-1] == "Reference3D":
                        names[element.get("id", "")] = element.get("name", "")
    except (OSError, zipfile.BadZipFile, ElementTree.ParseError):
        return {}
    return names


def _3dxml_ancestors(node: str, references: dict[str, str]) -> list[str]:
    """The names of the sub-assemblies above a 3DXML part node, nearest first: the
    references of its path between the root (the product itself, never a part's name)
    and the part's own (:func:`_3dxml_groups`)."""
    path = node.rpartition("#")[2].split(":")
    return [references.get(path[j], "") for j in range(len(path) - 5, 1, -2)]


def _3dxml_groups(file: Path, nodes: list[str]) -> list[tuple[str, list[str]]]:
    """The sub-assemblies of a 3DXML from its part nodes' paths (``name#1:3:2:9:8:...``).

    A path alternates Reference3D and Instance3D ids from the root (``1``) down to the
    part's own reference (third from last); every reference in between is a
    sub-assembly, named from the file's ``Reference3D`` elements.
    """
    names = _3dxml_reference_names(file)
    if not names:
        return []
    below: dict[tuple[str, ...], list[str]] = {}
    for node in nodes:
        path = node.rpartition("#")[2].split(":")
        for j in range(2, len(path) - 3, 2):
            below.setdefault(tuple(path[: j + 1]), []).append(node)
    groups, seen = [], set()
    for prefix, members in below.items():  # outermost first; a chain of wrappers counts once
        if len(members) >= 2 and frozenset(members) not in seen:
            seen.add(frozenset(members))
            groups.append((names.get(prefix[-1], "group"), members))
    return groups


def _natural(name: str) -> list:
    """Sort key that puts ``part9`` before ``part10``."""
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", name)]
