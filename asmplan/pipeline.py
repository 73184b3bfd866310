"""The public pipeline: assembly (or CAD file) -> relations -> state graph -> game -> plan.

Every step is a function of its own that takes the previous step's value and returns a
typed one, so a notebook, a web server or a cell controller can stop at any step, change
something and go on. The command line (:mod:`asmplan.cli`) is a thin layer over these
functions; :func:`plan` runs the whole chain as ``asmplan plan`` does.

Example
-------
>>> from asmplan import pipeline
>>> assembly = pipeline.load("examples/vacuum_pump")         # spec + part relations
>>> graph = pipeline.state_graph(assembly)                    # feasible sequences (AST)
>>> dag = pipeline.game(graph, cost="time")                   # robot-vs-human game DAG
>>> solution = pipeline.solve_game(dag)                       # exact minimax
>>> solution.tct, solution.minimax                            # doctest: +SKIP
(73.0, 91.0)
>>> result = pipeline.plan("examples/vacuum_pump")            # everything, plan.json's data
>>> pipeline.write_plan(result, "results/vacuum_pump")        # doctest: +SKIP

Errors for bad input are :class:`asmplan.errors.AsmplanError` (a ``ValueError``) or an
``OSError`` for a missing or unreadable file; messages are one line naming the file, part
or operation at fault.

Heavy libraries (trimesh, OR-Tools, matplotlib) are imported inside the steps that need
them, so importing this module is cheap.
"""

from __future__ import annotations

import functools
import json
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover - types only
    from asmplan.report.plot import DagFigure
    from asp.concurrent.plan import ConcurrentPlan
    from asp.concurrent.search import Limits
    from asp.game.dag import GameDAG
    from asp.game.plan import PlanStep
    from asp.game.policy import PlayedPolicy, StateDescriber
    from asp.game.solve import Solution
    from asp.graph.game_states import AlternateStates
    from asp.graph.state_graph import StateGraph
    from asp.schedule.cpsat import BaselineResult
    from asp.spec import AssemblySpec
    from cad.relations import Relations

PLAN_FORMAT = "asmplan-plan/2"
GRAPH_SUFFIXES = (".json", ".graphml", ".xml")
"""Suffixes read as a game DAG file rather than an assembly."""

PREVIEW_MAX_STATES = 5_000
"""Largest state graph whose concurrent game an alternate plan previews (``plan.json``'s
``concurrent_preview``, drawn in ``report.html``)."""

PREVIEW_MAX_POSITIONS = 200_000
"""Positions the preview's concurrent search may expand (past them: an interval)."""

SEARCH_SECONDS = 120.0
"""Default ``--search-time-limit``: search seconds of the concurrent search before it answers
with certified intervals, counted in positions (:data:`asp.concurrent.search.POSITIONS_PER_SECOND`)
so the plan is the same at any load; the wall clock stops it only as a safety net
(:func:`asp.schedule.cpsat.wall_safety`), recorded as ``concurrent.wall_stop`` in
``timings.json``."""

Progress = Callable[[str], None]
"""A callback that shows one line of progress (e.g. prints it on stderr)."""


# --------------------------------------------------------------------------- values


@dataclass(frozen=True, eq=False)
class Assembly:
    """An assembly ready for planning: its specification and its part relations.

    Attributes
    ----------
    spec : asp.spec.AssemblySpec
        The validated specification (operations, agents, tools, parts).
    relations : cad.relations.Relations or None
        Contact (TC) and translational-freedom (TT) tables, ``(n, n, 6)`` bool each, when
        the spec has part meshes; ``None`` for a spec without geometry (e.g. ``.IN2``).
    """

    spec: AssemblySpec
    relations: Relations | None = None

    @property
    def descriptions(self) -> dict[str, str]:
        """Operation id -> description."""
        return {op.id: op.description for op in self.spec.operations}


@dataclass(frozen=True, eq=False)
class Game:
    """A game DAG and the descriptions of its operations (empty for a bare graph file).

    Attributes
    ----------
    dag : asp.game.dag.GameDAG
    descriptions : dict of str to str
        Operation id -> description, for readable plans.
    interchangeable : tuple
        The classes of interchangeable blocks of operations its state graph's reduction
        used (``graph.model.interchangeable``; empty for a bare graph file): the game knows
        one canonical order of each (:mod:`asp.game.alike` maps a physical choice onto it).
    """

    dag: GameDAG
    descriptions: dict[str, str] = field(default_factory=dict)
    interchangeable: tuple = ()


@dataclass(frozen=True, eq=False)
class Schedule:
    """The CP-SAT minimum-makespan schedule of an assembly and its state-graph bounds.

    Attributes
    ----------
    result : asp.schedule.cpsat.BaselineResult
        Status, objective (makespan), bound and the task rows.
    lower_bound, chain_bound, load_bound : float
        State-graph lower bounds of the makespan (see
        :class:`asp.schedule.assembly.AssemblySchedule`).
    """

    result: BaselineResult
    lower_bound: float
    chain_bound: float
    load_bound: float

    def to_dict(self) -> dict[str, Any]:
        """``plan.json``'s ``schedule`` object."""
        return {
            **self.result.to_dict(),
            "lower_bound": self.lower_bound,
            "chain_bound": self.chain_bound,
            "load_bound": self.load_bound,
        }


@dataclass(frozen=True, eq=False)
class PlayedGame:
    """What a plan's outputs take from its solved game (turn model ``alternate``):
    ``plan.json``'s policy, lines and values, and ``dag.png``'s figure (:func:`played_game`).

    Its size is the robust policy's, not the game's: ``plan(keep_game=False)`` (what
    ``asmplan plan`` runs) makes it and lets the game and its solution go before CP-SAT and
    the outputs, so the game's edge arrays, the state graph and CP-SAT are never all held
    at once.

    Attributes
    ----------
    policy : asp.game.policy.PlayedPolicy
        The robust policy's table, named, with the game's sizes, TCT and W*.
    describe : asp.graph.game_states.AlternateStates
        Names the game's states (done operations and tools).
    figure : asmplan.report.plot.DagFigure
        The game DAG (or its layers) with the robust plan's path.
    """

    policy: PlayedPolicy
    describe: AlternateStates
    figure: DagFigure


@dataclass(frozen=True, eq=False)
class AssemblyPlan:
    """Everything ``asmplan plan`` computes for one assembly.

    Attributes
    ----------
    assembly : Assembly
    graph : asp.graph.state_graph.StateGraph
    sequences : int
        Number of feasible complete assembly sequences.
    game : Game or None
        The alternating game. None when :func:`plan` let it go (``keep_game=False``;
        ``played`` has what the outputs need of it), and with the turn model
        ``concurrent``, whose plan never builds it (``concurrent`` has its game).
    solution : asp.game.solve.Solution or None
        Exact solution: TCT, W* and both sides' policies (None with ``game``).
    steps : tuple of asp.game.plan.PlanStep
        The robust plan, turn by turn (robust robot against a maximising human); empty
        with the turn model ``concurrent`` (its lines are ``concurrent.cooperative`` and
        ``concurrent.worst``).
    relations_summary : list of dict
        Per part: contacts (with directions) and free directions.
    schedule : Schedule
        CP-SAT minimum makespan with the agents in parallel.
    concurrent : asp.concurrent.plan.ConcurrentPlan or None
        With the turn model ``concurrent``: the curve ``W*(k)``, the CP-SAT schedule's
        certified worst case, the timelines.
    units : list of dict
        Every unit used and every sub-assembly of the CAD file, used or why not
        (:func:`asp.subassemblies.units_report`; ``plan.json``'s ``units``).
    concurrent_preview : dict or None
        With the turn model ``alternate``: the concurrent game's preview
        (:func:`concurrent_preview`; ``plan.json``'s ``concurrent_preview``).
    played : PlayedGame or None
        What the outputs take from the alternating game, made by :func:`plan` (else from
        ``game`` and ``solution`` when first needed: :attr:`played_game`); None with the
        turn model ``concurrent``.
    """

    assembly: Assembly
    graph: StateGraph
    sequences: int
    game: Game | None
    solution: Solution | None
    steps: tuple[PlanStep, ...]
    relations_summary: list[dict]
    schedule: Schedule
    concurrent: ConcurrentPlan | None = None
    units: list[dict] = field(default_factory=list)
    played: PlayedGame | None = None
    concurrent_preview: dict | None = None

    @property
    def dag(self) -> GameDAG:
        return self.game.dag

    @functools.cached_property
    def played_game(self) -> PlayedGame:
        """``played``, or made from ``game`` and ``solution`` (once); an alternate plan's
        only (a concurrent plan has no alternating game)."""
        if self.played is not None:
            return self.played
        if self.concurrent is not None:
            raise ValueError("a concurrent plan has no alternating game (see its `concurrent`)")
        return played_game(self.graph, self.game, self.solution)

    def to_dict(self) -> dict[str, Any]:
        """The ``asmplan-plan/2`` object written as ``plan.json`` (:mod:`asmplan.planfile`;
        computed once), without the timings (:meth:`timings`)."""
        return self._documents[0]

    def timings(self) -> dict[str, Any]:
        """The times measured while planning, written as ``timings.json``
        (:func:`asmplan.planfile.split_timings`)."""
        return self._documents[1]

    @functools.cached_property
    def _documents(self) -> tuple[dict[str, Any], dict[str, Any]]:
        from asmplan.planfile import split_timings

        return split_timings(self._document())

    def _document(self) -> dict[str, Any]:
        extra = {
            "relations": self.relations_summary,
            "states": self.graph.n_states,
            "transitions": self.graph.n_transitions,
            "sequences": self.sequences,
            "schedule": self.schedule.to_dict(),
            "units": self.units,
            "fasteners_in_order": [list(f) for f in self.graph.model.fasteners_in_order],
        }
        if self.concurrent is None:
            if self.concurrent_preview is not None:
                extra["concurrent_preview"] = self.concurrent_preview
            played = self.played_game
            return played_document(
                self.assembly.spec,
                played.policy,
                played.describe,
                extra=extra,
                relations=self.assembly.relations,
                interchangeable=self.graph.model.interchangeable,
            )
        curve = self.concurrent.curve
        doc = plan_document(
            spec=self.assembly.spec,
            dag=curve.game.dag,
            solution=curve.solution,
            game=curve.game,
            extra=extra,
            relations=self.assembly.relations,
            interchangeable=self.graph.model.interchangeable,
        )
        from asp.concurrent.plan import plan_entries

        doc.update(plan_entries(self.concurrent))
        wall = self.concurrent.curve.wall_stop
        if wall is not None:  # the concurrent search's safety net stopped it: load-dependent
            doc["concurrent"]["wall_stop"] = wall  # a timing (split off to timings.json)
        doc["schedule"].update(
            chain_bound=self.schedule.chain_bound, load_bound=self.schedule.load_bound
        )
        return doc


# --------------------------------------------------------------------------- the plan document
def plan_document(
    *,
    spec,
    dag: GameDAG,
    solution: Solution,
    describe: StateDescriber | None = None,
    extra: dict | None = None,
    game=None,
    relations=None,
    interchangeable=(),
) -> dict:
    """The whole plan file of a solved game: policy, lines, metrics, operations and parts,
    plus ``extra`` (written by :func:`asmplan.planfile.document`).

    ``extra`` holds the keys computed elsewhere (relations, state graph sizes, ``schedule``);
    they are kept as given. ``game``: the :class:`asp.concurrent.build.ConcurrentGame` whose
    DAG ``dag`` is (turn model ``concurrent``; ``solution`` its exact solution, the policy
    that of its start, the largest budget). ``relations``: the part relations (``cad``
    ``Relations``, None without geometry): each line step's ``insertions`` then name the
    direction each body goes in along, and ``geometry`` the unit, scale and tolerances.
    ``interchangeable``: the classes of interchangeable blocks of operations the state
    graph's reduction used (``graph.model.interchangeable``, :mod:`asp.graph.symmetry`).
    """
    from asmplan.planfile import concurrent_policy_object
    from asp.concurrent.describe import policy_names
    from asp.game.dag import ROBOT
    from asp.game.policy import played_policy, policy_table

    if game is None:
        played = played_policy(dag, solution, describe)
        return played_document(
            spec,
            played,
            describe,
            extra=extra,
            relations=relations,
            interchangeable=interchangeable,
        )
    table = policy_table(dag, solution)
    policy = concurrent_policy_object(policy_names(game, table), table)
    sizes = (dag.cost_model, dag.n_nodes, dag.n_edges)
    values = (solution.tct, solution.minimax, float(solution.expected[dag.start, ROBOT]))
    return _plan_document(spec, policy, sizes, values, extra, relations, interchangeable)


def played_document(
    spec,
    played: PlayedPolicy,
    describe: StateDescriber | None = None,
    *,
    extra: dict | None = None,
    relations=None,
    interchangeable=(),
) -> dict:
    """The whole plan file of a solved ``alternate`` game from its
    :class:`asp.game.policy.PlayedPolicy` (the game itself no longer needed; arguments as
    :func:`plan_document`'s)."""
    from asmplan.planfile import played_policy_object

    policy = played_policy_object(played, describe)
    sizes = (played.cost_model, played.n_nodes, played.n_edges)
    values = (played.tct, played.minimax, played.avg_random)
    return _plan_document(spec, policy, sizes, values, extra, relations, interchangeable)


def _plan_document(spec, policy, sizes, values, extra, relations, interchangeable) -> dict:
    """The plan file around its ``policy``: each line replayed by the relation checker
    (:func:`asp.graph.checker.line_directions`), then :func:`asmplan.planfile.document`."""
    from asmplan import planfile
    from asp.graph.checker import line_directions

    operations = planfile.operation_records(spec)
    lines = planfile.policy_lines(policy, operations)
    checks = {
        name: line_directions(spec, relations, planfile.line_operations(steps))
        for name, steps in lines.items()
    }
    return planfile.document(
        spec,
        policy,
        sizes,
        values,
        operations,
        lines,
        checks,
        extra=extra,
        geometry=geometry_record(spec, relations),
        part_sources={p.file: part_source(spec, p.file) for p in spec.parts if p.file},
        interchangeable=interchangeable,
    )


def geometry_record(spec, relations) -> dict | None:
    """``plan.json``'s ``geometry``: the length unit, scale, frame, tolerances and mesh
    rules of the geometry (None without it): what a checker replaying a line from the
    meshes alone needs (the part files are read for their scale, :func:`file_scale`).

    Coordinates: the source file's own frame (its node transforms applied, no axis
    changed) times ``scale`` (millimetres per coordinate as trimesh reads the files, a
    file's millimetre numbers under a wrong unit label included; null when the files
    differ, each part's ``source.scale`` then says), turned by ``build_rotation`` into the
    build frame (below); tolerances are in millimetres; a
    pair ``(i, j)`` tolerates an overlap of ``part_shrink[i] + part_shrink[j]``
    (:mod:`cad.tolerances`), and counts a gap of ``min(contact_reach[i],
    contact_reach[j])`` as touching (``contact_tol`` for every pair when ``contact_reach``
    is null). ``step_chord``: a STEP source is tessellated to within this many mm of its
    surfaces (:data:`cad.scene.STEP_CHORD_MM`, OCCT's ``tol_linear``), so a checker reads
    the same meshes. ``merge_vertices``: each mesh's coincident
    vertices are merged before anything (a STEP or 3DXML tessellation gives every face its
    own vertices; eroding such a mesh leaves its edges where they were). ``erosion``: how a
    part is shrunk. ``fits``: pairs whose inner part is shrunk further for that pair only
    (:mod:`cad.fits`). ``support_travel_factor``: a part is supported if a fall of that
    many times the pair's tolerance meets a part below; ``support``: the rules a part is
    supported by (:data:`cad.support.SUPPORT_RULES`). ``open_parts``: parts not closed after
    merging (their relations are approximate: a closed part has an inside, a part lying
    wholly in it collides with it; an open one has none).
    ``frame``: ``"file"`` (the file's own axes) or ``"build"`` (the parts turned as the
    product is fixtured, :mod:`cad.frame`); ``build_rotation``: the 3x3 rotation ``R``, row
    by row, taking file coordinates (times ``scale``) to build coordinates, ``x_build = R @
    x_file`` (the identity for ``"file"``). Directions, gravity and every tolerance are in
    the build frame.
    """
    if relations is None:
        return None
    from asmplan.planfile import build_rotation
    from cad.relations import replay_rules
    from cad.scene import STEP_CHORD_MM
    from cad.units import unit_scale

    file_unit = str(getattr(relations, "units", "mm"))
    shrink = tuple(getattr(relations, "part_shrink", ()))
    if len(shrink) != len(relations.parts):
        shrink = (float(relations.penetration_tol) / 2,) * len(relations.parts)
    scales = {file_scale(spec, p.file) for p in spec.parts if p.file}
    if len(scales) == 1 and None not in scales:
        scale = scales.pop()  # millimetre numbers under a wrong unit label included
    else:
        try:
            scale = unit_scale(file_unit)
        except ValueError:
            scale = None  # "mixed": the files declare different units
    return {
        "unit": "mm",
        "file_unit": file_unit,
        "scale": scale,
        "step_chord": STEP_CHORD_MM,
        "frame": "file" if spec.frame is None else "build",
        "build_rotation": [list(row) for row in build_rotation(spec)],
        "contact_tol": float(relations.contact_tol),
        "penetration_tol": float(relations.penetration_tol),
        "part_shrink": dict(zip(map(str, relations.parts), map(float, shrink), strict=True)),
        **replay_rules(relations),
    }


def part_source(spec, file: str | None) -> dict | None:
    """Where a part's mesh is: ``file`` (relative to :func:`source_folder`),
    ``node`` (the part's scene-graph node, as trimesh names it, in a scene file; else
    null), ``path`` (absolute, when it exists), ``scale`` (millimetres per coordinate as
    trimesh reads the file, :func:`file_scale`)."""
    from asmplan.planfile import source_folder, split_file

    if not file:
        return None
    name, node = split_file(file)
    folder = source_folder(spec.source)
    path = (folder / name).resolve()
    if node is not None and path.is_file():
        node = _scene_node(path, node)
    return {
        "file": name,
        "node": node,
        "path": str(path) if path.is_file() else None,
        "scale": file_scale(spec, file),
    }


def file_scale(spec, file: str) -> float | None:
    """Millimetres per coordinate of a part's file as trimesh reads it (its declared unit,
    else the spec's; millimetre numbers under a wrong label read as mm); None when the
    file cannot be read."""
    from asmplan.planfile import source_folder, split_file
    from cad.scene import coordinate_scale

    path = (source_folder(spec.source) / split_file(file)[0]).resolve()
    if not path.is_file():
        return None
    try:
        return coordinate_scale(path, spec.units)
    except (OSError, ValueError):
        return None


def _scene_node(path: Path, part: str) -> str:
    """The scene-graph node (as trimesh names it) of the part ``part`` of a scene file."""
    from cad.scene import read_scene

    try:
        scene = read_scene(path)
    except (OSError, ValueError):
        return part
    k = scene.find(part)
    return scene.nodes[k] if k is not None and k < len(scene.nodes) else part


# --------------------------------------------------------------------------- steps


def load_assembly(
    source: str | os.PathLike[str], *, units: str | None = None, gravity: str | None = None
) -> AssemblySpec:
    """Read and validate an assembly specification.

    Parameters
    ----------
    source : path
        A folder holding ``assembly.yaml``, the YAML itself, a Scholl ``.IN2`` graph, or a
        CAD file (STEP, glTF/GLB, 3MF, 3DXML) or folder of part meshes, whose spec is
        generated (``spec.generated``; :mod:`asp.fromcad.generate`).
    units, gravity : str, optional
        ``--units`` (of mesh files that declare none) and ``--gravity``: replace the spec's.

    Returns
    -------
    asp.spec.AssemblySpec

    Raises
    ------
    asmplan.errors.AsmplanError
        One line naming the file, the key and the offending operation or part.
    FileNotFoundError
        ``source`` does not exist.
    """
    from asp.fromcad.generate import load_any

    return load_any(source, units=units, gravity=gravity)


def relations(spec: AssemblySpec, *, progress: bool = False) -> Relations | None:
    """Contact and freedom tables of the parts ``spec`` places (``None``: no geometry).

    Parameters
    ----------
    spec : asp.spec.AssemblySpec
    progress : bool
        Show a progress bar on stderr.

    Returns
    -------
    cad.relations.Relations or None
        ``tc``, ``tt``: ``(n_parts, n_parts, 6)`` bool.
    """
    from asp.graph.feasibility import load_relations

    return load_relations(spec, progress=progress)


def load(
    source: str | os.PathLike[str],
    *,
    progress: bool = False,
    on_step: Progress | None = None,
    contact_tol: float | None = None,
    penetration_tol: float | None = None,
    units: str | None = None,
    gravity: str | None = None,
) -> Assembly:
    """:func:`load_assembly` and, when the spec has meshes, its :func:`relations`.

    A generated spec (no ``assembly.yaml``) is announced through ``on_step``, else as a
    warning; the decisions that need its relations (:func:`asp.fromcad.generate.decide_generated`:
    build frame, gravity, base part, ``held`` placements of parts nothing can keep from
    falling) are each said in a note. ``contact_tol`` and
    ``penetration_tol`` (mm) replace the spec's tolerances when given; ``units`` and
    ``gravity`` replace the spec's (a given gravity is kept, not chosen). An assembly
    implausibly small or large for its unit gets a note (:func:`cad.unit_hints.size_hint`).

    The source is read once (:func:`asp.fromcad.generate.read_source`: the spec and its
    parts' meshes, one value); the relations and the decisions take that geometry, and no
    step below reads a file again.
    """
    from asp.fromcad.generate import decide_generated, read_source
    from asp.graph.feasibility import spec_relations

    read = read_source(
        source,
        units=units,
        gravity=gravity,
        contact_tol=contact_tol,
        penetration_tol=penetration_tol,
    )
    spec = read.spec

    def note(text: str) -> None:
        if on_step is not None:
            on_step(text)
        else:
            import warnings

            warnings.warn(text, stacklevel=3)

    if spec.generated:
        note(
            f"no assembly.yaml: generated a spec from {source} ({len(spec.parts)} parts, one "
            "placement each, agents H and R1, durations from part size); "
            f"`asmplan init {source} -o assembly.yaml` writes it for editing"
        )
    if len(spec.parts) == 1:
        note(f"one part only ({spec.parts[0].id}): the plan places it; nothing is assembled")
    rel = None
    if spec.has_geometry:
        if on_step is not None:
            on_step(f"computing part relations of {len(spec.parts)} parts ...")
        if read.size_note:
            note(f"units: {read.size_note}")
        rel = spec_relations(spec, read.geometry, progress=progress)
        decided = decide_generated(
            spec, rel, read.geometry, say=on_step, progress=progress, given_gravity=bool(gravity)
        )
        spec, rel = decided.spec, decided.relations
        for line in decided.notes():
            note(line)
    return Assembly(spec=spec, relations=rel)


def part_relations(
    source: str | os.PathLike[str],
    *,
    units: str | None = None,
    contact_tol: float | None = None,
    penetration_tol: float | None = None,
    progress: bool = False,
) -> Relations:
    """Contact and freedom tables of every pair of parts of a folder, scene or spec.

    A folder holding an ``assembly.yaml`` is read through that file (its parts, files and
    units), as every other command reads it; any other folder is read mesh by mesh.

    Parameters
    ----------
    source : path
        Folder of part meshes, multi-body scene (GLB/glTF/3MF/STEP) or ``assembly.yaml``.
    units : str, optional
        Unit of mesh files that declare none (default: the spec's, else mm).
    contact_tol, penetration_tol : float, optional
        Tolerances in mm (defaults: :mod:`cad.tolerances`).
    progress : bool
        Show a progress bar on stderr.

    Returns
    -------
    cad.relations.Relations
    """
    import cad

    spec = _spec_file(source)
    if spec is not None:  # the spec's own tolerances unless others are given
        contact_tol = spec.contact_tol if contact_tol is None else contact_tol
        penetration_tol = spec.penetration_tol if penetration_tol is None else penetration_tol
    return cad.compute_relations(
        part_geometry(source, units=units),
        contact_tol=contact_tol,
        penetration_tol=penetration_tol,
        progress=progress,
    )


def _spec_file(source: str | os.PathLike[str]) -> AssemblySpec | None:
    """The spec of a YAML file or of a folder holding ``assembly.yaml`` (else None)."""
    from asp.spec import SPEC_FILE, load_spec

    path = Path(source)
    if path.suffix.lower() in (".yaml", ".yml") or (path.is_dir() and (path / SPEC_FILE).is_file()):
        return load_spec(path)
    return None


def part_geometry(source: str | os.PathLike[str], *, units: str | None = None):
    """The part meshes of a spec (a YAML, or a folder holding ``assembly.yaml``), a folder
    of meshes or a scene file, as a ``cad.Assembly`` (millimetres).

    ``units`` overrides the spec's unit for files that declare none.
    """
    from dataclasses import replace

    import cad
    from asp.fromcad.generate import spec_geometry

    spec = _spec_file(source)
    if spec is not None:
        return spec_geometry(spec if units is None else replace(spec, units=units))
    return cad.load_assembly(Path(source), units=units)


def state_graph(
    assembly: Assembly,
    *,
    progress: bool = False,
    max_states: int | None = None,
    on_step: Progress | None = None,
    concurrent: bool = False,
    max_memory: int | None = None,
) -> StateGraph:
    """The assembly state graph: every feasible partial assembly and operation.

    One call of :func:`asp.subassemblies.build_with_units`: a spec generated from a CAD
    file builds the file's sub-assemblies that can be built and inserted as units
    (:func:`asp.subassemblies.cad_units`), except those the derived precedences prove leave
    no complete sequence (:func:`asp.subassemblies.refuted_units`: given up in
    milliseconds, said on ``on_step``). The spec, with those units, is reduced
    (:func:`asp.graph.symmetry.reduced_state_graph`: the precedences every complete
    sequence keeps, interchangeable parts in a fixed order or, for blocks of parts that
    cannot be, only the first of equal blocks moving; same TCT and W*, far fewer states;
    a unit is one body of the main assembly there, and the alike parts of its workspace
    are reduced in it). When that has no complete sequence and a part can never be
    inserted alone, subassemblies are added automatically, each round reduced alike; the
    graph's ``spec`` holds all of it. An infeasible assembly's graph is built once.

    Parameters
    ----------
    assembly : Assembly
    progress : bool
        Show progress on stderr.
    max_states : int, optional
        State limit (default: the spec's ``max_states``, else 20,000,000).
    on_step : callable, optional
        Called with a line for each round of automatic subassemblies.
    concurrent : bool
        Reduce so that the compiled concurrent game keeps its values too: alike parts in a
        loose order, not a fixed one (more states; :func:`asp.graph.symmetry.symmetry_reduction`;
        the alternate plan's concurrent preview). The CP-SAT schedule and the concurrent
        plan's search keep their values either way (they undo a fixed order,
        :mod:`asp.graph.fixed_order`, :mod:`asp.concurrent.rules`), so :func:`plan` builds
        the fixed order for both turn models.
    max_memory : int, optional
        Bytes each build may use (default :func:`asp.heap.memory_budget`, the one rule;
        ``train --max-memory``).

    Returns
    -------
    asp.graph.state_graph.StateGraph
    """
    from asp.subassemblies import build_with_units

    return build_with_units(
        assembly.spec,
        assembly.relations,
        hierarchy=assembly.spec.generated,
        reduce=True,
        concurrent=concurrent,
        on_unit=on_step,
        progress=progress,
        max_states=max_states,
        max_memory=max_memory,
    )


def game(graph: StateGraph, *, cost: str | None = None) -> GameDAG:
    """The robot-vs-human game DAG of a state graph.

    Parameters
    ----------
    graph : asp.graph.state_graph.StateGraph
    cost : {"steps", "time"}, optional
        Cost of a move (default: the spec's ``cost:``).

    Returns
    -------
    asp.game.dag.GameDAG
    """
    from asp.graph.game_dag import game_dag

    return game_dag(graph, cost=cost)


def load_game(source: str | os.PathLike[str], *, cost: str | None = None) -> Game:
    """The game of a game DAG file (``.json``/``.graphml``) or of an assembly.

    Parameters
    ----------
    source : path
        Game DAG file, or an assembly as :func:`load_assembly` reads it.
    cost : {"steps", "time"}, optional
        Cost model of an assembly; a graph file has its own costs.

    Returns
    -------
    Game
    """
    from asp.errors import GraphError

    path = Path(source)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file or folder")
    if path.is_file() and path.suffix.lower() in GRAPH_SUFFIXES:
        from asp.game.io import load_dag

        if cost is not None:
            raise GraphError("--cost applies to assemblies only: a graph file has its costs")
        return Game(load_dag(path))
    assembly = load(path)
    graph = state_graph(assembly)
    return Game(game(graph, cost=cost), assembly.descriptions, graph.model.interchangeable)


def solve_game(dag: GameDAG) -> Solution:
    """Solve the game exactly (backward induction): TCT, W* and both policies."""
    from asp.game.solve import solve

    return solve(dag)


def played_game(graph: StateGraph, game: Game, solution: Solution) -> PlayedGame:
    """What the outputs of a plan take from its solved game (:class:`PlayedGame`)."""
    from asmplan.report.plot import dag_figure
    from asp.game.policy import played_policy
    from asp.game.solve import play
    from asp.graph.game_states import alternate_states

    dag = game.dag
    every_state = alternate_states(graph, dag)
    policy = played_policy(dag, solution, every_state)
    describe = every_state.only(policy.table.node)  # the plan file names no other state
    del every_state
    path, _ = play(dag, solution.robot_policy, solution.human_policy)
    return PlayedGame(policy, describe, dag_figure(dag, path_edges(dag, path)))


def robust_plan(game: Game, solution: Solution) -> tuple[PlanStep, ...]:
    """The robust robot policy against the maximising human, turn by turn."""
    from asp.game.plan import robust_plan as steps

    return tuple(steps(game.dag, solution, game.descriptions))


def schedule(
    assembly: Assembly,
    graph: StateGraph,
    *,
    time_limit: float | None = None,
    workers: int = 1,
    seed: int = 0,
    sequence: list[str] | None = None,
) -> Schedule:
    """CP-SAT minimum makespan with the agents working in parallel, physically feasible.

    Every schedule is replayed through the state graph and cut until one passes
    (:func:`asp.schedule.assembly_makespan.assembly_makespan`); the status is ``OPTIMAL`` only for a
    proven optimum that passed, ``FEASIBLE`` for the best passing schedule when time ran
    out (a list schedule along a state-graph path is always there to fall back on).

    Parameters
    ----------
    assembly : Assembly
    graph : asp.graph.state_graph.StateGraph
        Gives the implied precedences and the lower bounds.
    time_limit : float or None
        Seconds for CP-SAT's search. ``None`` (the default): the automatic budget of
        :func:`asp.schedule.assembly_makespan.assembly_makespan`, the whole stage within
        :data:`asp.schedule.assembly_makespan.AUTO_TIME_LIMIT` seconds, stopping once
        neither a better schedule nor a new cut has come for
        :data:`asp.schedule.assembly_makespan.AUTO_PATIENCE` seconds.
    workers : int
        CP-SAT workers (1: repeatable).
    seed : int
        CP-SAT random seed.
    sequence : list of str, optional
        A complete sequence of operation ids along the state graph (the robust plan's
        line): a list schedule along it is one more starting point.

    Returns
    -------
    Schedule
    """
    from asp.schedule.assembly_makespan import assembly_makespan

    sched, result = assembly_makespan(
        assembly.spec,
        graph,
        time_limit=time_limit,
        workers=workers,
        seed=seed,
        sequence=sequence,
    )
    return Schedule(result, sched.lower_bound, sched.chain_bound, sched.load_bound)


def plan(
    source: str | os.PathLike[str] | Assembly,
    *,
    cost: str | None = None,
    time_limit: float | None = None,
    seed: int = 0,
    turn_model: str | None = None,
    max_k: int | None = None,
    duration_step: float | None = 1.0,
    on_step: Progress | None = None,
    max_states: int | None = None,
    contact_tol: float | None = None,
    penetration_tol: float | None = None,
    keep_game: bool = True,
    units: str | None = None,
    gravity: str | None = None,
    search_time_limit: float | None = SEARCH_SECONDS,
    max_nodes: int | None = None,
    max_memory: float | None = None,
) -> AssemblyPlan:
    """Plan an assembly end to end, as ``asmplan plan`` does.

    Parameters
    ----------
    source : path or Assembly
        An assembly (see :func:`load_assembly`) or one already loaded.
    cost : {"steps", "time"}, optional
        Cost model of the game (default: the spec's).
    time_limit : float or None
        Seconds for CP-SAT's search (default: the automatic budget, see :func:`schedule`).
    seed : int
        CP-SAT random seed.
    turn_model : {"alternate", "concurrent"}, optional
        Default: the spec's. ``alternate``: the alternating game, solved, then CP-SAT and
        the concurrent preview (:func:`alternate_preview`). ``concurrent``: CP-SAT, then the
        concurrent game (:func:`asp.concurrent.plan.plan_concurrent`); the alternating game
        is never built (the result's ``game``, ``solution`` and ``played`` are None, its
        ``steps`` empty).
    max_k : int, optional
        Largest deviation budget of the concurrent curve (default
        :data:`asp.concurrent.robustness.DEFAULT_MAX_K`).
    duration_step : float or None
        Grid of a person's duration range in the concurrent game (None: its end points).
    search_time_limit, max_nodes, max_memory : optional
        The concurrent search's limits (:func:`search_limits`): seconds (None: none),
        positions expanded and GB; past them ``W*(k)`` is a certified interval.
    on_step : callable, optional
        Called with one line before each step (progress for a person): ``[1/5]`` to
        ``[4/5]``, each once and in order (``asmplan plan`` says ``[5/5]`` as it writes).
    max_states : int, optional
        State graph limit (default: the spec's ``max_states``, else 20,000,000).
    contact_tol, penetration_tol : float, optional
        Tolerances in mm for every pair (default: the spec's, else the per-part rule of
        :mod:`cad.tolerances`); ignored when ``source`` is an :class:`Assembly`.
    units, gravity : str, optional
        ``--units`` and ``--gravity`` (:func:`load`); ignored for an :class:`Assembly`.
    keep_game : bool
        Keep the game DAG and its solution in the result. ``False`` (``asmplan plan``):
        once solved, what the outputs need of them is taken (:class:`PlayedGame`) and they
        are let go before CP-SAT, so a game of tens of millions of edges is not held with
        the state graph and CP-SAT's model; the result's ``game`` and ``solution`` are None.

    Returns
    -------
    AssemblyPlan
        ``to_dict()`` is the ``plan.json`` object.
    """
    from asp.game.plan import relations_summary
    from asp.heap import map_large_blocks, release_memory

    map_large_blocks()  # a freed array of a few MB goes back to the system at once
    say = on_step or (lambda _message: None)
    say("[1/5] reading the assembly and computing part relations ...")
    loaded = assembly = (
        source
        if isinstance(source, Assembly)
        else load(
            source,
            progress=True,
            on_step=say,
            contact_tol=contact_tol,
            penetration_tol=penetration_tol,
            units=units,
            gravity=gravity,
        )
    )
    summary = relations_summary(assembly.relations) if assembly.relations is not None else []
    release_memory()  # the meshes and collision objects of the relations
    say("[2/5] building the assembly state graph ...")
    turn = assembly.spec.turn_model if turn_model is None else turn_model
    from asp.game.turns import CONCURRENT, expected_names
    from asp.spec import TURN_MODELS

    if turn not in TURN_MODELS:
        from asp.errors import GraphError

        raise GraphError(f"--turn-model: expected {expected_names()}, got {turn!r}")
    # Alike parts in a fixed order for both turn models: the concurrent rules undo it
    # exactly (:mod:`asp.concurrent.rules`), and the loose order's graph is larger.
    graph = state_graph(assembly, progress=True, max_states=max_states, on_step=on_step)
    from asp.subassemblies import units_report

    unit_rows = units_report(assembly.spec, assembly.relations, graph.spec.subassemblies)
    if graph.spec is not assembly.spec:  # subassemblies found: their insertions are operations
        assembly = Assembly(graph.spec, assembly.relations)
    sequences = graph.count_sequences()
    release_memory()  # the layers and tables of the build
    if turn == CONCURRENT.name:  # CP-SAT first: its optimum bounds the concurrent game's W*(k)
        from asp.concurrent.plan import plan_concurrent
        from asp.concurrent.robustness import DEFAULT_MAX_K

        say("[3/5] CP-SAT minimum-makespan schedule ...")
        sched = schedule(assembly, graph, time_limit=time_limit, seed=seed)
        release_memory()  # CP-SAT's model and the replay tables
        say("[4/5] solving the concurrent game, W*(k) until flat ...")
        concurrent = plan_concurrent(
            assembly.spec,
            graph,
            max_k=DEFAULT_MAX_K if max_k is None else max_k,
            step=duration_step,
            limits=search_limits(search_time_limit, max_nodes, max_memory),
            schedule=(sched.result, sched.lower_bound),
            progress=on_step is not None,
        )
        return AssemblyPlan(
            assembly, graph, sequences, None, None, (), summary, sched, concurrent, unit_rows
        )
    say("[3/5] solving the robot-vs-human game ...")
    the_game = Game(game(graph, cost=cost), assembly.descriptions)
    release_memory()  # the game's per-edge temporaries
    solution = solve_game(the_game.dag)
    steps = robust_plan(the_game, solution)
    played = None
    if not keep_game:
        played = played_game(graph, the_game, solution)
        the_game = solution = None
    release_memory()  # the game, unless kept
    say("[4/5] CP-SAT minimum-makespan schedule ...")
    line = [step.operation for step in steps if step.operation]
    sched = schedule(assembly, graph, time_limit=time_limit, seed=seed, sequence=line)
    release_memory()  # CP-SAT's model and the replay tables
    preview = alternate_preview(
        loaded, graph, schedule=(sched.result, sched.lower_bound), progress=on_step is not None
    )
    return AssemblyPlan(
        assembly,
        graph,
        sequences,
        the_game,
        solution,
        steps,
        summary,
        sched,
        None,
        unit_rows,
        played,
        preview,
    )


def alternate_preview(
    assembly: Assembly, graph: StateGraph, *, schedule: tuple | None = None, progress: bool = False
) -> dict:
    """``plan.json``'s ``concurrent_preview`` of an alternate plan: the concurrent game that
    ``--turn-model concurrent`` would play, on the state graph that plan would use.

    The alternate plan's ``graph`` puts alike parts in a fixed order, which keeps the
    alternating game's values but not the concurrent game's: two alike parts could not go
    in at once there (the Fabrica duct: W*(0) 26 on it, beside a CP-SAT optimum of 20). The
    concurrent plan's graph (:func:`state_graph` with ``concurrent=True``: alike parts in a
    loose order, the concurrent rules doing the rest) keeps both, so the preview's W*(0)
    equals the CP-SAT optimum where both are exact. It is built from ``assembly`` (as
    loaded, before any subassembly) up to :data:`PREVIEW_MAX_STATES` states.

    Parameters
    ----------
    assembly : Assembly
        The assembly as :func:`load` gives it.
    graph : asp.graph.state_graph.StateGraph
        The alternate plan's graph (larger than :data:`PREVIEW_MAX_STATES`: no preview).
    schedule : (BaselineResult, float), optional
        The plan's CP-SAT schedule and its lower bound (its value is the same on either
        graph: :mod:`asp.graph.fixed_order`); not used when the concurrent graph's
        operations differ (other subassemblies), CP-SAT then runs again.
    progress : bool
        Say the search's progress (and a first run's compile of its kernels) on stderr.

    Returns
    -------
    dict
        :func:`concurrent_preview` of the concurrent graph, or ``{"why": reason}``.
    """
    if graph.n_states > PREVIEW_MAX_STATES:
        return {"why": _too_large(f"{graph.n_states:,} assembly states")}
    try:
        loose = state_graph(assembly, max_states=PREVIEW_MAX_STATES, concurrent=True)
    except ValueError as exc:  # over the limit (StateLimit), or any reason it cannot be built
        from asp.errors import StateLimit

        if isinstance(exc, StateLimit):
            return {
                "why": _too_large(
                    f"over {PREVIEW_MAX_STATES:,} assembly states with alike parts in any order"
                )
            }
        return {"why": str(exc).splitlines()[0]}
    if loose.spec.op_ids != graph.spec.op_ids:
        schedule = None
    return concurrent_preview(loose.spec, loose, schedule=schedule, progress=progress)


def _too_large(what: str) -> str:
    return f"{what} (the report solves the concurrent game up to {PREVIEW_MAX_STATES:,})"


def search_limits(
    time_limit: float | None, max_nodes: int | None, max_memory: float | None
) -> Limits:
    """The concurrent search's :class:`~asp.concurrent.search.Limits` from ``plan``'s
    ``--search-time-limit`` (seconds, None: none), ``--max-nodes`` (positions expanded) and
    ``--max-memory`` (GB); None keeps the search's default."""
    from asp.concurrent.search import Limits

    given = {"time_limit": time_limit}
    if max_nodes is not None:
        given["max_nodes"] = int(max_nodes)
    if max_memory is not None:
        given["memory"] = int(max_memory * 2**30)
    return Limits(**given)


def concurrent_preview(
    spec: AssemblySpec, graph: StateGraph, *, schedule=None, progress: bool = False
) -> dict:
    """The concurrent game of ``spec`` on ``graph``, solved for the report when the graph
    is small (:func:`alternate_preview` gives it the graph the concurrent plan would use).

    Parameters
    ----------
    spec : asp.spec.AssemblySpec
    graph : asp.graph.state_graph.StateGraph
    schedule : (BaselineResult, float), optional
        The plan's CP-SAT schedule and its lower bound (spares solving it again).
    progress : bool
        Say the search's progress (and a first run's compile of its kernels) on stderr.

    Returns
    -------
    dict
        The concurrent plan's ``robustness``, ``concurrent`` (without its ``seconds``) and
        ``schedule`` (its ``objective`` and ``status`` only) keys
        (:func:`asp.concurrent.plan.plan_entries`), with ``states`` and ``sequences`` of
        ``graph``, when the graph has at most :data:`PREVIEW_MAX_STATES` states and the game
        could be solved, else ``{"why": reason}``. No timings: two runs give the same
        preview.
    """
    if graph.n_states > PREVIEW_MAX_STATES:
        return {"why": _too_large(f"{graph.n_states:,} assembly states")}
    from asp.concurrent.plan import plan_concurrent, plan_entries

    try:
        preview = plan_concurrent(
            spec,
            graph,
            limits=search_limits(None, PREVIEW_MAX_POSITIONS, None),
            schedule=schedule,
            progress=progress,
        )
    except (ValueError, MemoryError) as exc:
        return {"why": str(exc).splitlines()[0]}
    entries = plan_entries(preview)
    game = {k: v for k, v in entries["concurrent"].items() if k != "seconds"}
    sched = {k: entries["schedule"][k] for k in ("objective", "status")}
    return {
        "robustness": entries["robustness"],
        "concurrent": game,
        "schedule": sched,
        "states": graph.n_states,
        "sequences": graph.count_sequences(),
    }


def build_plan(
    assembly: str | os.PathLike[str], *, cost: str | None = None, turn_model: str | None = None
) -> dict:
    """The plan document of an assembly (folder, ``assembly.yaml`` or ``.IN2``), for a
    service that plans on start.

    Turn model ``alternate``: the relations, state graph, game and exact solution, then
    :func:`plan_document`, without the CP-SAT schedule. ``concurrent``
    (``turn_model``, default the spec's): :func:`plan`, the curve ``W*(k)`` and the CP-SAT
    comparison included.
    """
    from asp.game.turns import CONCURRENT
    from asp.graph.game_states import alternate_states

    loaded = load(assembly)
    if (turn_model or loaded.spec.turn_model) == CONCURRENT.name:
        return plan(loaded, cost=cost, turn_model=CONCURRENT.name).to_dict()
    graph = state_graph(loaded)
    dag = game(graph, cost=cost)
    solution = solve_game(dag)
    return plan_document(
        spec=loaded.spec,
        dag=dag,
        solution=solution,
        describe=alternate_states(graph, dag),
        relations=loaded.relations,
        interchangeable=graph.model.interchangeable,
    )


def write_plan(
    result: AssemblyPlan,
    output: str | os.PathLike[str],
    *,
    on_step: Progress | None = None,
    force: bool = False,
) -> tuple[Path, ...]:
    """Write ``plan.json``, ``timings.json`` and ``report.html``, with the turn model
    ``alternate`` the game DAG picture ``dag.png``, with ``concurrent`` the curve and
    timeline PNGs of its game instead, into ``output`` as one unit: each report shows the
    figures of its own game only.

    ``plan.json`` holds no time measured while planning (those are ``timings.json``'s), so
    two runs on the same input write the same ``plan.json``.

    The files of one run are named by ``manifest.json``; the previous run's files (only
    those its manifest names) are removed once this run is complete, and a folder holding
    files asmplan did not write is refused unless ``force`` (see
    :class:`asp.atomic.OutputSet`). A failure removes what this run wrote.

    Returns
    -------
    tuple of Path
        The files written (the manifest last).
    """
    from asmplan.report.html import plan_report
    from asp.atomic import OutputSet

    with OutputSet(output, force=force) as out:
        doc = result.to_dict()
        out.write_text("plan.json", json.dumps(doc, separators=(",", ":"), allow_nan=False) + "\n")
        out.write_text("timings.json", json.dumps(result.timings(), indent=1) + "\n")
        dag_png = None
        if result.concurrent is None:
            from asmplan.report.plot import draw_dag

            played = result.played_game
            game = played.policy
            draw_dag(
                played.figure,
                out.path("dag.png"),
                title=f"{result.assembly.spec.name}: game DAG ({game.cost_model}), robust plan "
                f"in red, TCT {game.tct:g}, W* {game.minimax:g}",
            )
            dag_png = out.path("dag.png").read_bytes()
        else:
            from asmplan.report.gantt import write_figures

            write_figures(doc, out.path)
        if on_step is not None:
            on_step("  writing report.html ...")
        out.write_text("report.html", plan_report(doc, dag_png))
    return out.written


def path_edges(dag: GameDAG, path: list[int]) -> list[int]:
    """Edge indices along a node path (a pass repeats no node, so consecutive nodes differ)."""
    edges = []
    for u, v in zip(path, path[1:], strict=False):
        hits = [e for e in dag.out_edges(u) if dag.targets[e] == v]
        edges.append(hits[0])
    return edges
