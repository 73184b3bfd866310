"""Specs generated from CAD: a first plan from a CAD file alone, and the geometry of a spec.

:func:`generated_spec` turns a CAD file (STEP, glTF/GLB, 3MF, 3DXML, a mesh) or a folder
of part meshes into a valid :class:`~asp.spec.AssemblySpec`; :func:`spec_text` writes the
same spec as a commented ``assembly.yaml`` for the user to edit (``asmplan init``). The
rule, fixed so that a generated spec plans the same as the file it writes:

- parts: one per mesh node of the file (ids and names from the file, :mod:`cad.scene`),
  or per mesh file of the folder (a ``bom.csv``/``bom.yaml`` in the folder still names
  them); ``shape`` is the shape class (identical parts share it, :mod:`cad.identical`);
- frame: the file's own, unless some pair of parts can never be assembled in it (each
  blocks the other along every axis direction, :func:`cad.frame.interlocked`: the Fabrica
  duct's pins lie 30 degrees off ``z``); then a few frames turning a part axis the parts
  share onto a coordinate axis are tried (:mod:`asp.fromcad.framing`), the first that leaves every
  part a way in taken; ``frame:`` in the spec, said on stderr;
- gravity: the format's own down (``-y`` for glTF/GLB, whose specification makes ``+y``
  up; ``-z`` for the others) unless another axis direction is clearly better for the
  parts' relations (:mod:`asp.fromcad.gravity`: a Y-up STEP export gets ``-y``);
  :func:`orient_generated` applies it once the relations are computed, and says why;
- the base part, placed first: the lowest of the large parts along gravity (those whose
  footprint, the bounding box's area across gravity, is at least half the largest);
- agents: one human ``H`` and one robot ``R1``;
- one placement operation per part, ids ``"1"``, ``"2"``, ... in the order base first,
  then the others from the lowest to the highest (against gravity), open to both agents;
- durations (:func:`placement_durations`): the human takes 3 s plus 1 s per 25 mm of
  the part's bounding-box diagonal, at most 60 s, in whole seconds; the robot takes 1.5
  times as long (rounded to whole seconds); the cost model is ``time``;
- every gripper approach direction, every constraint on; the units are
  those the files declare (STEP, glTF, 3MF), ``units: mm`` for the others;
- ``held: true`` on the placement of every part (the base aside) that no part there
  before it can stop falling along gravity (:func:`unsupported_parts`: its row of the
  support relation ``SP_g`` is empty, e.g. a dowel in a through hole or a shaft in a bore
  with clearance, or holds only parts that block it, with the base, along every
  direction, e.g. a standoff under the speaker it holds up, the product on its side):
  an agent holds it until a later operation fixes it. It needs the part relations, so
  :func:`hold_unsupported` applies it once they are computed (``asmplan.pipeline.load``),
  and :func:`spec_text` computes them to write it;
- subassemblies: the file's sub-assemblies that can be built on their own and inserted
  as one unit (:func:`asp.subassemblies.file_units`: not holding the base part, buildable in their
  own workspace, free from the base part along some direction) are units; the others are
  written commented with the reason. The state graph of a generated spec gives up a unit
  that leaves no complete sequence (:func:`asp.subassemblies.build_with_units`).
"""

from __future__ import annotations

import math
import os
from collections import Counter
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from asp.cad_keys import with_flex
from asp.errors import SpecError
from asp.game.turns import ALTERNATE
from asp.numbers import json_number
from asp.spec import (
    SPEC_FILE,
    AssemblySpec,
    load_spec,
    spec_from_dict,
    with_subassemblies,
    with_tolerances,
)
from cad.yamlfile import DecimalsAsText

HUMAN_BASE_S = 3.0
HUMAN_S_PER_MM = 1.0 / 25.0
MAX_DURATION_S = 60.0
ROBOT_FACTOR = 1.5


def placement_durations(diagonal_mm: float) -> tuple[float, float]:
    """``(human, robot)`` seconds to place a part of bounding-box diagonal ``diagonal_mm``."""
    human = min(MAX_DURATION_S, float(round(HUMAN_BASE_S + HUMAN_S_PER_MM * diagonal_mm)))
    return human, float(round(ROBOT_FACTOR * human))


HELD_REASON = (
    "nothing below can stop it falling (or only parts that must go in after it); an agent "
    "holds it until a later part fixes it"
)
"""Why a generated spec marks an operation ``held`` (the comment ``asmplan init`` writes)."""


def unsupported_parts(relations, gravity: str, base: str | None = None) -> tuple[str, ...]:
    """Parts that nothing there before them can keep from falling along ``gravity``.

    Part ``i`` (the base part aside: placed first, never tested) is unsupported when every
    part ``j`` with ``sp[i, j, g]`` (a drop onto ``j``, or threaded on it) *comes after it*:
    ``j`` and the base part together block ``i`` along every direction (``not tt[i, j, d]
    or not tt[i, base, d]`` for each ``d``). That covers an empty row (no drop onto any
    part: a dowel in a through hole, a shaft in a bore with clearance) and a part resting
    only on the part it holds up (a standoff between a back plate and the speaker on it,
    the product on its side: only the speaker's pocket stops it falling, and the speaker,
    with the plate, leaves it no way in).

    **Why it must be held, and why the mark is sound.** The base part is in every state
    an insertion is tested in, and blocking only grows with the parts there (DESIGN.md:
    ``TT_d(p, S)`` is the AND over ``S``). So once such a ``j`` is in, ``i`` has no free
    direction and can never go in: in every complete sequence ``i`` goes in before each
    part that could support it, and its stability test fails there whatever the order.
    ``held: true`` (an agent holds it until a later operation fixes it) is what every
    plan needs; it skips the stability test of ``i`` only, so it adds sequences (the ones
    with ``i`` held) and removes none, and the independent checker replays the plan with
    the same mark. (Inside a subassembly's workspace the base is not there; the mark then
    only lets ``i`` go in before ``j`` as well.)

    Parameters
    ----------
    relations : cad.relations.Relations
        ``parts``, ``tt`` and ``sp`` ``(n, n, 6)`` bool (``sp`` None: built by hand, none).
    gravity : str
        The spec's gravity direction, e.g. ``"-z"``.
    base : str, optional
        The base part id (None: no part is there first; a supporter must then block
        ``i`` along every direction by itself).

    Returns
    -------
    tuple of str
        Part ids, in the order of ``relations.parts``.
    """
    from cad.directions import DIRECTIONS

    if getattr(relations, "sp", None) is None:
        return ()
    ids = [str(p) for p in relations.parts]
    rests = np.asarray(relations.sp, dtype=bool)[:, :, DIRECTIONS.index(gravity)].copy()
    np.fill_diagonal(rests, False)
    tt = np.asarray(relations.tt, dtype=bool)
    open_ = tt[:, ids.index(base), :] if base in ids else np.ones((len(ids), 6), dtype=bool)
    after = ~(tt & open_[:, None, :]).any(axis=2)  # after[i, j]: j comes after i
    if base in ids:
        after[:, ids.index(base)] = False  # the base is there first
    loose = ~(rests & ~after).any(axis=1)
    return tuple(p for p, out in zip(ids, loose, strict=True) if out and p != base)


def hold_unsupported(spec: AssemblySpec, relations) -> tuple[AssemblySpec, tuple[str, ...]]:
    """A generated spec with ``held: true`` on the placement of each unsupported part.

    Only for a generated spec (``spec.generated``) with the stability constraint on; a
    user's spec is returned unchanged. Returns the spec and the parts now held (in the
    order of the operations).
    """
    if not spec.generated or not spec.constraints.stability or relations is None:
        return spec, ()
    loose = set(unsupported_parts(relations, spec.gravity, spec.base_part))
    ops = [replace(op, held=True) if set(op.parts) & loose else op for op in spec.operations]
    held = tuple(p for op in spec.operations for p in op.parts if p in loose)
    return (replace(spec, operations=tuple(ops)) if held else spec), held


def hold_refuted(spec: AssemblySpec, relations) -> tuple[AssemblySpec, bool]:
    """A generated spec with ``held: true`` also on each part whose placement the derived
    precedences refute while it is not held (or a part its proof looks at, its own first:
    the first whose mark takes that proof away), until none is refuted or no mark helps;
    and whether none is refuted then.

    Why: a part that rests only on parts which must come after it (a wheel arch resting
    on the screws that fix it: they block it along the only way it can go in) has nothing
    to rest on when it goes in, as an unsupported part has (:func:`hold_unsupported`);
    held, it needs no support, so its supports need not come first. Only ``held`` marks
    are added, each taking away a proof that the precedences give while it is loose, so a
    spec they do not refute is unchanged, and a mark is kept when another cause remains
    (two parts locking each other, which a ``flex:`` line resolves: the marks are then
    what the plan needs as well).
    """
    from asp.graph.precedences import refutation

    placing = {p: k for k, op in enumerate(spec.operations) for p in op.parts}
    proof = refutation(spec, relations)
    for _ in range(len(spec.operations)):
        if proof is None:
            return spec, True
        named = spec.operations[spec.op_index(proof.operation)].parts
        for part in dict.fromkeys((*named, *proof.parts)):  # its own part first
            k = placing.get(part)
            op = spec.operations[k] if k is not None else None
            if op is None or op.held or len(op.parts) != 1 or part == spec.base_part:
                continue
            ops = list(spec.operations)
            ops[k] = replace(op, held=True)
            marked = replace(spec, operations=tuple(ops))
            again = refutation(marked, relations)
            if again is None or again.operation != proof.operation:
                spec, proof = marked, again  # the mark took this proof away
                break
        else:
            break  # no mark helps: it is locked in, or another cause
    return spec, False


def workable_base(spec: AssemblySpec, relations) -> tuple[AssemblySpec, str]:
    """A generated spec on a base part from which the assembly is not ruled out.

    The geometric rule (:func:`base_index`) looks at bounding boxes only; when the derived
    precedences (:func:`asp.graph.precedences.infeasibility`) prove that no complete sequence starts
    from that base (with gravity as given, e.g. a drive drawn upside down whose lowest large
    part rests on parts that need the parts above it), the other parts are tried, those
    touching the most parts first (then in operation order), and the first not ruled out
    becomes the base; its placement moves to the front. ``held`` is set as
    :func:`hold_unsupported` does; when no base helps, the spec on its own base gets
    the ``held`` marks of :func:`hold_refuted` too. A user's spec is unchanged.

    Returns
    -------
    (AssemblySpec, str)
        The spec (``held`` applied) and a note naming the new base and why ("" if kept).
    """
    from dataclasses import replace

    from asp.graph.precedences import infeasibility

    held, _ = hold_unsupported(spec, relations)
    if not spec.generated or relations is None or not spec.base_part:
        return held, ""
    why = infeasibility(held, relations)
    if not why:
        return held, ""
    ids = [str(p) for p in relations.parts]
    degree = np.asarray(relations.tc, dtype=bool).any(axis=2).sum(axis=1)
    placed = [op.parts[0] for op in spec.operations if len(op.parts) == 1]
    order = sorted(
        (p for p in placed if p in ids and p != spec.base_part),
        key=lambda p: (-int(degree[ids.index(p)]), placed.index(p)),
    )
    for part in order:
        ops = sorted(spec.operations, key=lambda op: op.parts != (part,))
        candidate, _ = hold_unsupported(
            replace(spec, base_part=part, operations=tuple(ops)), relations
        )
        if not infeasibility(candidate, relations):
            note = (
                f"generated spec: base part {part} instead of {spec.base_part} (no complete "
                f"sequence can start from {spec.base_part}: {why})"
            )
            return candidate, note
    return hold_refuted(held, relations)[0], ""


def spec_geometry(spec: AssemblySpec):
    """The meshes of ``spec``'s parts as a ``cad.Assembly`` (files relative to the spec).

    Raises
    ------
    SpecError
        The spec names no parts, or a part has no mesh file (named).
    """
    from cad.loading import load_parts

    if not spec.parts:
        raise SpecError(f"{spec.source}: the spec names no parts (a 'parts:' list with files)")
    return load_parts(spec.parts, spec.folder, spec.units, frame=spec.frame)


def file_hierarchy(geometry) -> tuple[tuple[str, tuple[str, ...]], ...]:
    """The CAD file's hierarchy over its parts as read (``geometry.groups``: group id -> part
    ids, outermost first; a part joined of several nodes, :mod:`cad.merging`, stands for
    them), the groups of two parts or more: a generated spec's ``hierarchy``."""
    return tuple((gid, tuple(members)) for gid, members in geometry.groups if len(members) >= 2)


def cad_assembly(path: str | Path, units: str | None = None):
    """The geometry of a CAD file or a folder of part meshes (``cad.load_assembly``).

    A ``bom.csv``/``bom.yaml`` beside a scene file adds or overrides part data
    (:func:`cad.loading.apply_bom`); in a folder of meshes it names the parts. ``units``:
    the unit of files that declare none (default mm).
    """
    from cad.bom import read_bom
    from cad.loading import BOM_NAMES, apply_bom, load_assembly

    path = Path(path)
    assembly = load_assembly(path, units=units)
    bom = next((path.parent / n for n in BOM_NAMES if (path.parent / n).is_file()), None)
    if path.is_file() and bom is not None:
        assembly = apply_bom(assembly, read_bom(bom), path.parent)
    return assembly


def spec_data(
    path: str | Path,
    geometry,
    spec_folder: str | Path | None = None,
    gravity: str | None = None,
    frame=None,
    units: str | None = None,
) -> tuple[dict, object]:
    """The generated spec of a CAD file or folder, as the YAML mapping, and its geometry.

    ``geometry`` is the file's parts as :func:`cad_assembly` read them (in the file's
    frame): the spec is made from it, along any gravity and in any frame, with no file
    read again.

    Part files are written relative to ``spec_folder`` (default: the CAD file's folder,
    or the folder of meshes itself); ``gravity`` defaults to the format's own down
    (:func:`asp.fromcad.gravity.default_down`); ``frame`` (a rotation, :mod:`cad.frame`; None: the
    file's own) is the build frame the parts are turned into, and written as ``frame:``;
    ``units`` is the unit of mesh files that declare none (default mm; ``--units``).

    Returns
    -------
    (dict, cad.Assembly)
        The mapping :func:`asp.spec.spec_from_dict` reads, and the parts it was made from
        (in the build frame).
    """
    from asp.fromcad.gravity import base_index, default_down
    from cad.frame import frame_record, rotated
    from cad.identical import shape_classes

    path = Path(path)
    gravity = gravity or default_down(path)
    assembly = rotated(geometry, frame)
    shapes = shape_classes(assembly.parts)
    counts = Counter(shapes)
    if spec_folder is None:
        spec_folder = path if path.is_dir() else path.parent
    parts = []
    for part, shape in zip(assembly.parts, shapes, strict=True):
        source, _, node = part.source.partition("#")
        file = Path(os.path.relpath(Path(source).resolve(), Path(spec_folder).resolve()))
        record = {"id": part.id, "name": part.name}
        record["file"] = f"{file.as_posix()}#{node}" if node else file.as_posix()
        if part.quantity != 1:
            record["quantity"] = part.quantity
        if part.type:
            record["type"] = part.type
        if counts[shape] > 1:
            record["shape"] = shape
        parts.append(record)
    bounds = np.array([p.bounds for p in assembly.parts])  # (n, 2, 3) in mm
    extents = bounds[:, 1] - bounds[:, 0]
    base = base_index(bounds, gravity)
    axis, sign = "xyz".index(gravity[1]), (1.0 if gravity[0] == "-" else -1.0)
    low, high = (0, 1) if sign > 0 else (1, 0)  # the bottom and top faces along gravity
    order = [base] + sorted(
        (k for k in range(len(assembly.parts)) if k != base),
        key=lambda k: (sign * bounds[k, low, axis], sign * bounds[k, high, axis], k),
    )
    operations = []
    for number, k in enumerate(order, start=1):
        part = assembly.parts[k]
        human, robot = placement_durations(float(np.linalg.norm(extents[k])))
        operations.append(
            {
                "id": str(number),
                "description": f"place {part.id}"
                + (f" ({part.name})" if part.name != part.id else ""),
                "agents": {"H": json_number(human), "R1": json_number(robot)},
                "part": part.id,
            }
        )
    data = {
        "name": path.stem if path.is_file() else path.name,
        "units": units or "mm",  # for files without a declared unit
        "parts": parts,
        "agents": {
            "H": {"side": "human", "description": "operator"},
            "R1": {"side": "robot", "description": "robot arm with a gripper"},
        },
        "base_part": assembly.parts[base].id,
        "gravity": gravity,
        **({"frame": frame_record(frame)} if frame is not None else {}),
        "gripper_approach": ["+x", "-x", "+y", "-y", "+z", "-z"],
        "constraints": {"topological": True, "stability": True, "functional": True},
        "turn_model": ALTERNATE.name,
        "cost": "time",
        "operations": operations,
    }
    return data, assembly


def is_cad_input(path: str | os.PathLike[str]) -> bool:
    """True for a CAD scene file or a folder of part meshes without an ``assembly.yaml``."""
    from cad.loading import MESH_SUFFIXES

    path = Path(path)
    if path.is_dir():
        return not (path / SPEC_FILE).is_file() and any(
            f.suffix.lower() in MESH_SUFFIXES for f in path.iterdir() if f.is_file()
        )
    return path.is_file() and path.suffix.lower() in MESH_SUFFIXES


@dataclass(frozen=True, eq=False)
class Source:
    """An assembly's input, read once: its spec and the geometry of its parts.

    Attributes
    ----------
    spec : AssemblySpec
        Read (``assembly.yaml``, a Scholl ``.IN2``) or generated from a CAD file or a
        folder of part meshes (``spec.generated``).
    geometry : cad.Assembly or None
        The meshes of the spec's parts in its build frame (None: the spec places no part
        with a mesh). Of a CAD file: its parts as read (the file's frame, a ``bom``
        applied, ``groups`` the file's hierarchy), the value the spec was generated from
        and, along another gravity or in another frame, is generated again from
        (:func:`decide_generated`); nothing below reads the file again.
    size_note : str
        What the geometry's size says of its unit (:func:`cad.unit_hints.size_hint`: an
        assembly implausibly small or large for it), else "".
    """

    spec: AssemblySpec
    geometry: object | None = None
    size_note: str = ""


def read_source(
    path: str | os.PathLike[str],
    *,
    units: str | None = None,
    gravity: str | None = None,
    contact_tol: float | None = None,
    penetration_tol: float | None = None,
) -> Source:
    """The spec of ``path`` (as :func:`load_any` reads it) and its parts' geometry.

    A CAD file or folder of meshes is read once (:func:`cad_assembly`) and the spec
    generated from that geometry; a spec's part files are read once
    (:func:`spec_geometry`). The tolerances given (mm) replace the spec's
    (:func:`asp.spec.with_tolerances`), as ``units`` and ``gravity`` do.
    """
    from cad.unit_hints import size_hint

    check_overrides(units, gravity)
    if not is_cad_input(path):
        spec = with_tolerances(_read_spec(path, units, gravity), contact_tol, penetration_tol)
        if not spec.has_geometry:
            return Source(spec)
        geometry = spec_geometry(spec)
        return Source(spec, geometry, size_hint(geometry))
    geometry = cad_assembly(path, units)
    if Path(path).is_file():  # what reading a scene's parts as part files warns of
        from cad.loading import warn_part_scales

        warn_part_scales(geometry)
    note = size_hint(geometry)
    spec = spec_from_geometry(path, geometry, gravity=gravity, units=units)
    return Source(with_tolerances(spec, contact_tol, penetration_tol), geometry, note)


def load_any(
    path: str | os.PathLike[str], *, units: str | None = None, gravity: str | None = None
) -> AssemblySpec:
    """The spec of ``path``: generated for a CAD file or a folder of part meshes without an
    ``assembly.yaml`` (:func:`generated_spec`), else read (:func:`asp.spec.load_spec`).

    ``units`` (the unit of mesh files that declare none) and ``gravity`` (``--units``,
    ``--gravity``) replace the spec's own when given; a generated spec's gravity given so
    is kept (:func:`decide_generated` is told by the caller).
    """
    check_overrides(units, gravity)
    if is_cad_input(path):
        return generated_spec(path, gravity=gravity, units=units)
    return _read_spec(path, units, gravity)


def _read_spec(path, units: str | None, gravity: str | None) -> AssemblySpec:
    """The spec file of ``path`` with ``--units`` and ``--gravity`` in place of its own."""
    spec = load_spec(path)
    changes = {"units": units, "gravity": gravity}
    return replace(spec, **{k: v for k, v in changes.items() if v is not None})


def check_overrides(units: str | None, gravity: str | None) -> None:
    """One-line errors for an unknown ``--units`` or a ``--gravity`` that is no direction."""
    from asp.spec import DIRECTIONS
    from cad.units import unit_scale

    if units is not None:
        unit_scale(units)
    if gravity is not None and gravity not in DIRECTIONS:
        raise SpecError(f"--gravity: expected one of {' '.join(DIRECTIONS)}, got {gravity!r}")


def generated_spec(
    path: str | Path, gravity: str | None = None, frame=None, units: str | None = None
) -> AssemblySpec:
    """The spec generated from a CAD file or a folder of part meshes (``generated=True``):
    :func:`spec_from_geometry` of the file read (:func:`cad_assembly`)."""
    return spec_from_geometry(path, cad_assembly(path, units), gravity, frame, units)


def spec_from_geometry(
    path: str | Path, geometry, gravity: str | None = None, frame=None, units: str | None = None
) -> AssemblySpec:
    """The spec generated from the parts of a CAD file or folder as read (``geometry``).

    Its ``source`` is the spec file it stands for (``assembly.yaml`` beside the CAD file,
    which need not exist), so that part files resolve as in the written spec. ``gravity``,
    ``frame`` and ``units``: as :func:`spec_data` takes them.
    """
    path = Path(path)
    data, _ = spec_data(path, geometry, gravity=gravity, frame=frame, units=units)
    folder = path if path.is_dir() else path.parent
    spec = spec_from_dict(data, source=str(folder / SPEC_FILE))
    return replace(spec, generated=True, source=str(path), hierarchy=file_hierarchy(geometry))


def gravity_choice(relations, geometry, default: str):
    """:func:`asp.fromcad.gravity.choose_gravity` for parts ``geometry`` (a ``cad.Assembly``)."""
    from asp.fromcad.gravity import choose_gravity

    box = {p.id: p.bounds for p in geometry.parts}
    bounds = np.array([box[str(pid)] for pid in relations.parts], dtype=float)
    return choose_gravity(relations, bounds, default)


def orient_generated(spec: AssemblySpec, relations, geometry, turn=None, given: bool = False):
    """A generated spec with the gravity :mod:`asp.fromcad.gravity` chooses, and the choice.

    When the choice differs from the spec's (the format's own down), the spec is
    generated again along it (base part and operation order follow gravity) by
    ``turn(gravity, frame)`` (default: :func:`generated_spec` of the spec's source), in the
    spec's build frame. ``given``: the spec's gravity was given (``--gravity``): it is
    kept, and the choice says what the geometry would have chosen. A user's spec, or one
    without relations, is returned unchanged with None.
    """
    import warnings

    if not spec.generated or relations is None or getattr(relations, "sp", None) is None:
        return spec, None
    from asp.fromcad.gravity import default_down

    own = default_down(spec.source) if given else spec.gravity  # the format's down
    choice = gravity_choice(relations, geometry, own)
    if given:
        return spec, replace(choice, given=spec.gravity)
    if choice.gravity == spec.gravity:
        return spec, choice
    with warnings.catch_warnings():  # the same files again: their warnings were given
        warnings.simplefilter("ignore")
        turned = (turn or _regenerate(spec, geometry))(choice.gravity, spec.frame)
    tolerances = {"contact_tol": spec.contact_tol, "penetration_tol": spec.penetration_tol}
    return replace(turned, **tolerances), choice


def _regenerate(spec: AssemblySpec, geometry):
    """``turn(gravity, frame)``: ``spec``'s source generated again along another gravity
    or in another build frame from ``geometry`` (its parts as read, in the file's frame;
    tolerances are kept by the callers)."""
    return lambda gravity, frame: spec_from_geometry(
        spec.source, geometry, gravity=gravity, frame=frame, units=spec.units
    )


@dataclass(frozen=True)
class Decisions:
    """What a generated spec decides once its part relations are known.

    Attributes
    ----------
    spec : AssemblySpec
        The spec in the chosen build frame, along the chosen gravity, on a workable base,
        ``held`` applied.
    gravity : asp.fromcad.gravity.GravityChoice or None
        The gravity choice and its reason (None: a user's spec, or no support table).
    rebased : str
        Why another base part was taken ("" when the lowest large part was kept).
    relations : cad.relations.Relations or None
        The part relations in the spec's build frame (those given, unless another frame
        was chosen).
    geometry : cad.Assembly or None
        The parts in the spec's build frame.
    frame : asp.fromcad.framing.FrameChoice or None
        Why another build frame was taken, or why none helped (None: the file's frame
        leaves every pair of parts a way in, or a user's spec).
    """

    spec: AssemblySpec
    gravity: object | None
    rebased: str
    relations: object | None = None
    geometry: object | None = None
    frame: object | None = None

    @property
    def held(self) -> tuple[str, ...]:
        """The parts whose placement is ``held`` (in operation order)."""
        return tuple(p for op in self.spec.operations if op.held for p in op.parts)

    def notes(self) -> list[str]:
        """One line per decision, as a person reads them."""
        out = []
        if self.frame is not None:
            out.append(f"generated spec: frame: {self.frame.text}")
        if self.gravity is not None:
            out.append(f"generated spec: gravity {self.spec.gravity}: {self.gravity.reason}")
        if self.rebased:
            out.append(self.rebased)
        if self.held and self.spec.generated:
            out.append(f"generated spec: held: true for {', '.join(self.held)} ({HELD_REASON})")
        return out


def decide_generated(
    spec: AssemblySpec,
    relations,
    geometry,
    turn=None,
    *,
    say=None,
    progress: bool = False,
    given_gravity: bool = False,
) -> Decisions:
    """The decisions of a generated spec that need its relations, in this order: the build
    frame (:func:`asp.fromcad.framing.choose_frame`: only when some pair of parts can never be
    assembled in the file's frame), gravity (:func:`orient_generated`), then the base part
    and ``held`` (:func:`workable_base`).

    ``asmplan plan`` (:func:`asmplan.pipeline.load`) and ``asmplan init``
    (:func:`spec_text`) both take them here, so the file written plans as the file read.
    A user's spec comes back unchanged. ``geometry``: the parts as read (:class:`Source`).
    ``turn(gravity, frame)``: the spec generated again along another gravity or in another
    frame (default: from ``geometry``, no file read again). Use the
    returned ``relations`` (in the chosen frame) from then on. ``say`` is called with a line
    before each candidate frame's relations are computed (``progress``: their bars).
    ``given_gravity``: the spec's gravity was given (``--gravity``) and is kept.
    """
    from asp.fromcad.framing import choose_frame

    turn = turn or _regenerate(spec, geometry)
    decided = _decide_in_frame(spec, relations, geometry, turn, given_gravity)

    def in_frame(rotation) -> Decisions:
        """The decisions in another build frame (its relations computed afresh)."""
        from asp.graph.feasibility import spec_relations
        from cad.frame import frame_text, rotated

        geo = rotated(geometry, rotation)
        if say is not None:
            say(f"trying another build frame ({frame_text(rotation)}): part relations ...")
        rel = spec_relations(spec, geo, progress=progress)
        tolerances = {"contact_tol": spec.contact_tol, "penetration_tol": spec.penetration_tol}
        framed = replace(turn(spec.gravity if given_gravity else None, rotation), **tolerances)
        return _decide_in_frame(framed, rel, geo, turn, given_gravity)

    choice, chosen = choose_frame(decided, geometry, in_frame)
    return replace(chosen or decided, frame=choice)


def _decide_in_frame(
    spec: AssemblySpec, relations, geometry, turn, given_gravity: bool = False
) -> Decisions:
    """Gravity, base part and ``held`` of a generated spec, its frame as given."""
    oriented, choice = orient_generated(spec, relations, geometry, turn, given_gravity)
    decided, rebased = workable_base(oriented, relations)
    return Decisions(decided, choice, rebased, relations, geometry)


def spec_text(
    path: str | Path,
    spec_folder: str | Path | None = None,
    *,
    contact_tol: float | None = None,
    penetration_tol: float | None = None,
    on_note=None,
    decide_units=None,
    units: str | None = None,
    gravity: str | None = None,
) -> str:
    """The generated spec of a CAD file or folder as a commented ``assembly.yaml``.

    Part files are relative to ``spec_folder``, where the file will be written. Tolerances
    given (mm) are written as the spec's ``contact_tol`` / ``penetration_tol`` and used for
    the ``held`` marks; else both keys are written commented out. ``on_note`` (optional) is
    called with a line for each decision of :func:`decide_generated` (build frame,
    gravity, base part, ``held``). ``decide_units(spec,
    relations)`` (:func:`asp.subassemblies.file_units`, given by the caller: it sits above this
    module) decides which of the file's sub-assemblies are written as ``subassemblies:``;
    without it they are all written commented. ``units`` (of mesh files that declare
    none) and ``gravity`` (kept, not chosen): ``--units`` and ``--gravity``.
    """
    from dataclasses import replace

    import cad
    from cad.errors import Interpenetration
    from cad.relations import with_nearest
    from cad.unit_hints import size_hint

    check_overrides(units, gravity)
    read = cad_assembly(path, units)  # the file, read once: every turn below starts from it
    data, assembly = spec_data(path, read, spec_folder, gravity=gravity, units=units)
    size_note = size_hint(assembly)
    if size_note and on_note is not None:
        on_note(f"units: {size_note}")
    overlapping: tuple = ()  # pairs the file overlaps: the spec names them, commented
    flexing: tuple = ()  # parts that lock another once those are accepted: named likewise
    try:
        relations = cad.compute_relations(
            assembly, contact_tol=contact_tol, penetration_tol=penetration_tol
        )
    except Interpenetration as exc:
        overlapping = exc.pairs
        relations = exc.relations  # computed with the pairs accepted
        if relations is None:  # the message blames the unit: accepted all the same
            relations = cad.compute_relations(
                assembly,
                contact_tol=contact_tol,
                penetration_tol=penetration_tol,
                overlap_ok=overlapping,
            )
        flexing = exc.flex
        if on_note is not None:
            on_note(
                f"overlaps: {len(overlapping)} pair(s) overlap deeper than their tolerance; "
                "the spec's `overlap_ok:` line is written commented: uncomment it if they "
                "overlap as modelled"
                + (" (and the `flex:` line after it: parts that then lock)" if flexing else "")
            )
    relations = with_nearest(relations)  # as the plan reads them
    turned: dict = {(data["gravity"], None): (data, assembly)}

    def turn(gravity: str | None, frame) -> AssemblySpec:
        """The spec along another gravity or in another frame, keeping its records."""
        records = spec_data(path, read, spec_folder, gravity=gravity, frame=frame, units=units)
        turned[(records[0]["gravity"], frame)] = records
        return replace(spec_from_dict(records[0], source=str(path)), generated=True)

    tolerances = {"contact_tol": contact_tol, "penetration_tol": penetration_tol}
    generated = replace(
        spec_from_dict(data, source=str(path)),
        generated=True,
        overlap_ok=tuple(overlapping),
        **tolerances,
    )
    decided = decide_generated(generated, relations, assembly, turn, given_gravity=bool(gravity))
    spec, relations = decided.spec, decided.relations
    # the records along the chosen gravity, in the chosen frame
    data, assembly = turned.get((spec.gravity, spec.frame), (data, assembly))
    if on_note is not None:
        for line in decided.notes():
            on_note(line)
    data["base_part"] = spec.base_part
    first = [op for op in data["operations"] if op["part"] == spec.base_part]
    data["operations"] = first + [op for op in data["operations"] if op not in first]
    reason = decided.gravity.reason if decided.gravity is not None else "the format's own down"
    path = Path(path)
    lines = [
        f"# Assembly spec generated by `asmplan init` from {path.name}: edit it, then run",
        "#   asmplan plan assembly.yaml -o plan/",
        "# Format: see asp/spec.py. Every key below may be changed; what usually needs a look:",
        "#   - part names (ids are used in operations: rename both together);",
        "#   - durations in seconds, generated from part size: human "
        f"{HUMAN_BASE_S:g} s + 1 s per {1 / HUMAN_S_PER_MM:g} mm",
        f"#     of bounding-box diagonal (at most {MAX_DURATION_S:g} s), robot x{ROBOT_FACTOR:g};",
        "#   - which agent may do what (remove H or R1 from an operation), tool changes;",
        "#   - `held: true` for a part an agent must hold until a later part fixes it;",
        "#   - `after:` for precedences the geometry cannot see (glue, screws to tighten).",
        f"name: {_scalar(data['name'])}",
        f"units: {data['units']}   # of mesh files that declare none (STL, OBJ, PLY); "
        "STEP, glTF, 3MF declare their own",
        *([f"#   {size_note}"] if size_note else []),
        "",
        "parts:   # id: used in operations; file: the mesh (file#part: one part of a scene);",
        "         # shape: shared by identical parts (the same shape up to a rigid motion)",
    ]
    counts = Counter(r["shape"] for r in data["parts"] if "shape" in r)
    for record in data["parts"]:
        fields = ", ".join(f"{k}: {_scalar(v)}" for k, v in record.items())
        lines.append(f"  - {{{fields}}}")
    if counts:
        lines.append(
            "# identical parts: " + ", ".join(f"{n} x {s}" for s, n in sorted(counts.items()))
        )
    lines += _alike_lines(assembly)
    folder = spec_folder or (path if path.is_dir() else path.parent)
    lines += _hierarchy_lines(data, assembly, relations, folder, decide_units, flexing)
    lines += [
        "",
        "agents:   # name -> side (human, robot); add R2, H2, ... as the cell has them",
        "  H: {side: human, description: operator}",
        "  R1: {side: robot, description: robot arm with a gripper}",
        "",
        f"base_part: {_scalar(data['base_part'])}      # placed first: "
        + (
            f"no complete sequence starts from {generated.base_part}, the lowest large part"
            if decided.rebased
            else "the lowest of the large parts"
        ),
        *_frame_lines(decided),
        f"gravity: {data['gravity']}                # direction of gravity in the build frame:",
        f"#   {reason} (asp/fromcad/gravity.py)",
        "gripper_approach: [+x, -x, +y, -y, +z, -z]   # directions a part may be inserted from",
        "constraints: {topological: true, stability: true, functional: true}",
        "turn_model: alternate",
        "cost: time                 # or steps (1 per operation)",
        _tolerance_line("contact_tol", contact_tol, "largest gap that counts as touching"),
        _tolerance_line("penetration_tol", penetration_tol, "largest overlap that still touches"),
        *_overlap_lines(overlapping, flexing),
        "",
        "operations:   # one placement per part: base first, then from the lowest part up",
    ]
    for op in spec.operations:
        agents = ", ".join(f"{a}: {json_number(d)}" for a, d in op.durations)
        if op.held:
            lines.append(f"    # held: {HELD_REASON}")
        lines.append(
            f"  - {{id: {_scalar(op.id)}, description: {_scalar(op.description)}, "
            f"agents: {{{agents}}}, part: {_scalar(op.parts[0])}"
            + (", held: true}" if op.held else "}")
        )
    return "\n".join(lines) + "\n"


def _overlap_lines(pairs, flexing=()) -> list[str]:
    """The commented ``overlap_ok:`` line of the pairs the file overlaps and the ``flex:``
    line of the parts that lock another once they are accepted (none: no lines)."""
    if not pairs:
        return []
    from cad.freedom import flex_line, overlap_line

    lines = [
        f"# {len(pairs)} pair(s) overlap deeper than their tolerance in the file: uncomment if",
        "# as modelled (a press fit, a thread, a visual asset's pieces): each pair touches",
        f"# {overlap_line(pairs)}",
    ]
    if flexing:
        lines += [
            "# with them accepted, these parts lock another (each blocks the other along",
            "# every direction): uncomment if each flexes in (a snap fit, a clip, a connector)",
            f"# {flex_line(flexing)}",
        ]
    return lines


def _alike_lines(assembly) -> list[str]:
    """One comment per class of parts the file names generically (``alike_a_1``, ...:
    :mod:`cad.scene`): how many, their bounding box and the file's names."""
    import re

    classes: dict[str, list] = {}
    for part in assembly.parts:
        found = re.fullmatch(r"(alike_[a-z]+)(_\d+)?", part.id)
        if found:
            classes.setdefault(found.group(1), []).append(part)
    lines = []
    for cls, members in classes.items():
        box = " x ".join(f"{x:.3g}" for x in members[0].mesh.extents)
        names = ", ".join(dict.fromkeys(p.name for p in members))
        lines.append(f"# {cls}: {len(members)} part(s), each {box} mm (the file names {names})")
    return lines


def _hierarchy_lines(
    data: dict, assembly, relations, spec_folder, decide, flex: tuple = ()
) -> list[str]:
    """The ``subassemblies:`` of a written spec: the file's sub-assemblies that ``decide``
    accepts, and the others commented with the reason.

    ``relations`` accept the file's overlaps and ``flex`` names the parts of the commented
    ``flex:`` line: the units are decided for the spec as it plans once those lines are
    uncommented (without them the file has no complete sequence at all, so no unit could be
    judged by it; the FM1 satellite's XBee with its adapter, free of the base plate only
    while the XBee's pins flex in, was written commented and never planned)."""
    if not assembly.groups:
        return []
    if decide is None:
        lines = [
            "# The file's sub-assemblies: uncomment to build each on its own",
            "# subassemblies:",
        ]
        return lines + [f"#   {_scalar(gid)}: {_id_list(ms)}" for gid, ms in assembly.groups]
    folder = os.path.abspath(spec_folder)  # it may not exist yet: join the paths as text
    parts = []
    for record in data["parts"]:
        file, hash_, node = record["file"].partition("#")
        parts.append(
            {**record, "file": os.path.normpath(os.path.join(folder, file)) + hash_ + node}
        )
    spec = spec_from_dict({**data, "parts": parts}, source=os.path.join(folder, SPEC_FILE))
    spec = replace(spec, generated=True, hierarchy=file_hierarchy(assembly), flex=tuple(flex))
    relations = with_flex(relations, spec.flex)  # as the plan reads them (spec_relations)
    spec, _ = hold_unsupported(spec, relations)
    choices = decide(spec, relations)
    used = [u for u in choices if u.used]
    lines = [
        "# The file's sub-assemblies (asp/subassemblies.py): each one listed is built on its",
        "# own and inserted as one unit; delete a line to place its parts one by one. Commented:",
        "# the ones that cannot be units, and why.",
        "subassemblies:" if used else "# subassemblies:",
    ]
    turned, loose = _unit_ways(spec, relations, used)
    for u in choices:
        entry = f"{_scalar(u.id)}: {_id_list(u.members)}"
        if u.id in turned or u.id in loose:
            more = f", gravity: {turned[u.id]}" if u.id in turned else ""
            more += ", held: true" if u.id in loose else ""
            entry = f"{_scalar(u.id)}: {{parts: {_id_list(u.members)}{more}}}"
            if u.id in turned:
                entry += "   # built upside down, then turned over and inserted"
            if u.id in loose:
                entry += "   # held: nothing outside it keeps it from falling"
        lines.append(f"  {entry}" if u.used else f"#   {entry}   # not used: {u.reason}")
    return lines


def _unit_ways(spec, relations, used) -> tuple[dict[str, str], set[str]]:
    """For the used units: those built upside down (unit id -> the gravity of its
    workspace) and those held while inserted (:func:`asp.fromcad.orientation.loose_units`), as the
    planner decides them."""
    from asp.fromcad.orientation import loose_units, unit_orientation

    if relations is None or getattr(relations, "sp", None) is None or not used:
        return {}, set()
    try:
        with_units = with_subassemblies(spec, [(u.id, u.members) for u in used])
    except ValueError:
        return {}, set()
    turned = {}
    for u in used:
        o = unit_orientation(with_units, relations, u.id)
        if o.upside_down:
            turned[u.id] = o.gravity
    return turned, loose_units(with_units, relations)


def _frame_lines(decided: Decisions) -> list[str]:
    """The ``frame:`` of a written spec (commented out when it is the file's own)."""
    from cad.frame import frame_record

    record = frame_record(decided.spec.frame)
    if record is None:
        lines = [
            "# frame: file   # the build frame (the product as fixtured): the file's own, or",
            "#   {axis: [x, y, z], degrees: a} turns it (cad/frame.py)",
        ]
        if decided.frame is not None:
            lines.append(f"#   {decided.frame.text}")
        return lines
    axis = ", ".join(str(json_number(x)) for x in record["axis"])
    return [
        f"frame: {{axis: [{axis}], degrees: {json_number(record['degrees'])}}}"
        "   # the build frame: the product as fixtured (cad/frame.py)",
        f"#   {decided.frame.text} (asp/fromcad/framing.py)",
    ]


def _tolerance_line(key: str, value: float | None, meaning: str) -> str:
    """``key: value`` with a comment, or commented out when the default rule applies."""
    if value is None:
        return f"# {key}: 0.1   # mm, {meaning} (default: per part, cad/tolerances.py)"
    return f"{key}: {json_number(float(value))}   # mm, {meaning}, every pair"


def _scalar(value) -> str:
    """A YAML flow scalar that reads back as ``value``: plain when safe, else double-quoted.

    A string is written plain only when YAML reads it back as that same string (not
    ``01``, ``yes``, ``null``, ``1e3``, ``1.10``: those would come back as numbers,
    booleans or None) and it holds no flow or comment syntax; every id written goes
    through here.
    """
    import json

    import yaml

    if isinstance(value, int | float) and not isinstance(value, bool):
        return str(value) if math.isfinite(value) else json.dumps(str(value))
    text = str(value)
    plain = (
        text
        and text[0].isalpha()
        and all(c.isalnum() or c in " _-./()#" for c in text)
        and text.isascii()
        and not text.endswith(" ")
        and " #" not in text
        and _reads_as(text, yaml.SafeLoader)
        and _reads_as(text, DecimalsAsText)
    )
    return text if plain else json.dumps(text)


def _reads_as(text: str, loader) -> bool:
    """Whether ``text`` written plain reads back as the string ``text`` under ``loader``."""
    import yaml

    try:
        return yaml.load(f"k: {text}", Loader=loader) == {"k": text}  # noqa: S506
    except yaml.YAMLError:
        return False


def _id_list(ids) -> str:
    """A YAML flow list of ids, each quoted where needed (``[a, "01"]``)."""
    return "[" + ", ".join(_scalar(i) for i in ids) + "]"
