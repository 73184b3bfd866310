"""The assembly specification: parts, agents, operations, tools and switches (``assembly.yaml``).

An ``assembly.yaml`` names everything the planner needs besides the part geometry::

    name: vacuum pump                  # free text
    units: mm                          # read by cad/ (ignored here)
    parts:                             # part records (cad.bom)
      - {id: BD, name: Main body, file: meshes/BD.stl, quantity: 1, type: component}
      - {id: NUT, file: model.step#nut_2}   # one part of a scene file (its cleaned id)
    agents:                            # name -> side (human, robot; any for open tasks)
      H: {side: human}
      R1: {side: robot, description: UR3e with screwdriver}
    tools:                             # tool state: initial value, time to change it
      R1.bit: {initial: hex, change_time: 0}
    base_part: BD                      # placed first (or there from the start)
    gravity: -z                        # one of +x -x +y -y +z -z
    frame: {axis: [0, -1, 0], degrees: 30}   # the build frame: the product as fixtured,
                                       # the file's frame turned so (or a 3x3 matrix R,
                                       # x_build = R x_file; default: the file's own);
                                       # directions and gravity are its axes (cad/frame.py)
    gripper_approach: [+z, -z]         # directions d a part may leave along (inserted along -d)
    constraints: {topological: true, stability: true, functional: true}
    turn_model: alternate              # or concurrent (asp/concurrent/)
    cost: steps                        # or time
    max_states: 20000000               # state graph limit (asmplan plan --max-states)
    contact_tol: 0.1                   # mm, largest gap that counts as touching, every pair
    penetration_tol: 0.3               # mm, largest overlap that counts as touching
    flex: [lever_housing]              # snap fits: flexes over the parts it locks with
                                       # while inserted (asp/cad_keys.py)
    overlap_ok: [[pin, block]]         # pairs overlapping as modelled (press fit, thread,
                                       # visual asset): taken as touching (cad/fits.py)
                                       # (both default to cad/tolerances.py's per-part rule;
                                       # --contact-tol / --penetration-tol override them)
    subassemblies:                     # built on their own, then inserted as one unit
      motor_unit: [MT, PC]             # an operation "motor_unit" inserting it is added
      upper_die: {parts: [TP, PH], gravity: +z, held: true}   # built upside down
                                       # (gravity +z in its workspace; default: the spec's),
                                       # turned over, inserted held (it rests on nothing)
    operations:
      - id: "1.2"                      # ids are strings (1.10 stays "1.10")
        description: Replace hex bit with cross bit on R1
        agents: {H: 15}                # allowed agents and their durations; a person's
                                       # may be a range [min, max] (turn_model concurrent)
        requires: {R1.bit: hex}        # tool state needed (optional)
        sets: {R1.bit: cross}          # tool state after the operation (optional)
        after: ["1.1"]                 # explicit predecessors (optional)
      - id: "1.4"
        agents: {H: 12}
        part: [PC, VT1]                # part(s) placed, in this order (optional)
        held: false                    # true: an agent holds the part, no stability check

Semantics:

- An operation may start when all its ``after`` operations are done, every ``requires``
  tool has the value named, and every part it places is a feasible insertion
  (:mod:`asp.graph.feasibility`). Afterwards the ``sets`` tools have their new values.
- Under ``cost: time`` a move costs the agent's duration plus the tool's ``change_time``
  for every tool whose value the operation actually changes.
- If no operation places the base part, it is on the fixture from the start.

:func:`load_spec` validates everything and raises a one-line ``ValueError`` naming the
file, the key and the offending operation or part. An unknown key is refused with the
nearest known one suggested (``gravty`` -> ``gravity``); YAML aliases that expand past
a limit are refused (:mod:`cad.yamlfile`). For a CAD file or a folder of part meshes,
:func:`asp.fromcad.generate.load_any` generates the spec. To add a top-level key, add it to
:data:`TOP_KEYS` and read it in ``_Parser.parse``.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass, field, replace
from pathlib import Path

import networkx as nx

from asp.cad_keys import parse_flex, parse_overlap_ok
from asp.game.dag import MAX_COST
from asp.game.rules import COST_MODELS
from asp.game.turns import DEFAULT_TURN, TURNS, expected_names
from cad.bom import PartRecord, part_records, refuse_unknown_keys
from cad.directions import DIRECTIONS
from cad.frame import parse_frame
from cad.numbers import WRITTEN_PLAINLY, plain_number
from cad.texts import MAX_NAME, MAX_TEXT, bounded, text_value
from cad.tolerances import checked_tolerance
from cad.units import unit_scale
from cad.yamlfile import read_yaml

SIDES = ("human", "robot", "any")
TURN_MODELS = tuple(TURNS)
"""The turn models' names (:data:`asp.game.turns.TURNS`, where each says what differs)."""
CONSTRAINT_KEYS = ("topological", "stability", "functional")
SPEC_FILE = "assembly.yaml"
TOP_KEYS = (
    "name", "units", "parts", "agents", "tools", "base_part", "gravity", "gripper_approach",
    "constraints", "turn_model", "cost", "operations", "credit", "max_states", "subassemblies",
    "contact_tol", "penetration_tol", "frame", "flex", "overlap_ok",
)  # fmt: skip
"""The top-level keys of ``assembly.yaml``; any other is refused."""
OPERATION_KEYS = (
    "id", "description", "agents", "part", "parts", "requires", "sets", "after", "held",
)  # fmt: skip
AGENT_KEYS = ("name", "id", "side", "description")
TOOL_KEYS = ("initial", "change_time")

Part = PartRecord
"""A ``parts:`` entry: the one part record model, shared with BOM files (:mod:`cad.bom`)."""


@dataclass(frozen=True)
class Agent:
    """An agent: ``H``, ``R1``, ... with its side (``human``, ``robot`` or ``any``)."""

    name: str
    side: str
    description: str = ""


@dataclass(frozen=True)
class Tool:
    """A tool state variable such as ``R1.bit``: its initial value and change time."""

    name: str
    initial: str
    change_time: float = 0.0


@dataclass(frozen=True)
class Operation:
    """One assembly operation.

    Attributes
    ----------
    id, description : str
    durations : tuple of (agent, duration)
        The agents allowed to do it and how long each takes (for a range, its ``max``: the
        alternating game and the CP-SAT schedule use it).
    ranges : tuple of (agent, min, max)
        Durations given as a range ``[min, max]`` (the concurrent game's adversary picks
        within it, :func:`asp.concurrent.concurrent_model`).
    parts : tuple of str
        Parts placed, in order (may be empty).
    requires, sets : tuple of (tool, value)
        Tool states needed before / set after the operation.
    after : tuple of str
        Explicit predecessor operation ids.
    held : bool
        An agent holds the placed part: the stability constraint does not apply.
    unit : str
        The subassembly this operation inserts as one rigid unit (its members were placed in
        the unit's own workspace by earlier operations); empty for other operations.
    """

    id: str
    description: str
    durations: tuple[tuple[str, float], ...]
    parts: tuple[str, ...] = ()
    requires: tuple[tuple[str, str], ...] = ()
    sets: tuple[tuple[str, str], ...] = ()
    after: tuple[str, ...] = ()
    held: bool = False
    ranges: tuple[tuple[str, float, float], ...] = ()
    unit: str = ""

    @property
    def agents(self) -> tuple[str, ...]:
        return tuple(a for a, _ in self.durations)

    def duration_range(self, agent: str) -> tuple[float, float]:
        """``(min, max)`` duration of ``agent`` (``min == max`` unless a range is given)."""
        for a, lo, hi in self.ranges:
            if a == agent:
                return lo, hi
        d = self.duration(agent)
        return d, d

    def duration(self, agent: str) -> float:
        for a, d in self.durations:
            if a == agent:
                return d
        raise ValueError(f"operation {self.id!r}: agent {agent!r} may not do it")


@dataclass(frozen=True)
class Constraints:
    """Switches of the optimisation constraints (RTC and RTT are always applied)."""

    topological: bool = True
    stability: bool = True
    functional: bool = True


@dataclass(frozen=True)
class AssemblySpec:
    """A validated assembly specification (see the module docstring for the YAML)."""

    name: str
    operations: tuple[Operation, ...]
    agents: tuple[Agent, ...]
    parts: tuple[Part, ...] = ()
    tools: tuple[Tool, ...] = ()
    base_part: str | None = None
    gravity: str = "-z"
    gripper_approach: tuple[str, ...] = DIRECTIONS
    constraints: Constraints = field(default_factory=Constraints)
    turn_model: str = DEFAULT_TURN.name
    cost: str = "steps"
    source: str = ""
    units: str | None = None
    credit: str = ""
    max_states: int | None = None
    generated: bool = False
    hierarchy: tuple[tuple[str, tuple[str, ...]], ...] = ()
    """A generated spec's CAD hierarchy: the file's sub-assemblies over its parts (group id,
    member part ids; outermost first, two parts or more), taken from the file as it was read
    (:func:`asp.fromcad.generate.file_hierarchy`); empty for a spec read from a file."""
    subassemblies: tuple[tuple[str, tuple[str, ...]], ...] = ()
    """Units built in their own workspace and inserted whole: (unit id, member part ids)."""
    unit_gravity: tuple[tuple[str, str], ...] = ()
    """(unit id, direction): a unit built in another orientation than it has in the product
    (a die set's upper half built upside down, then turned over and inserted). Its members
    are tested for support along that direction (product frame) in its workspace; units
    not listed are built as they sit in the product (``gravity``). See
    :mod:`asp.fromcad.orientation`."""
    contact_tol: float | None = None
    """Contact tolerance (mm) for every pair; None: the per-part rule of cad.tolerances."""
    penetration_tol: float | None = None
    """Penetration tolerance (mm) for every pair; None: the per-part rule of cad.tolerances."""
    frame: tuple[tuple[float, float, float], ...] | None = None
    """The build frame (``frame:``, :mod:`cad.frame`): the rotation ``R`` (row by row) with
    ``x_build = R @ x_file``, applied to every part where it is loaded; directions and
    gravity are axes of the build frame. None: the file's own frame."""
    flex: tuple[str, ...] = ()
    """Parts that flex while inserted (``flex:``, :mod:`asp.cad_keys`)."""
    overlap_ok: tuple[tuple[str, str], ...] = ()
    """Pairs of parts whose overlap in the file is as modelled, taken as touching
    (``overlap_ok:``, :mod:`asp.cad_keys`)."""

    @property
    def op_ids(self) -> tuple[str, ...]:
        return tuple(op.id for op in self.operations)

    def op_index(self, op_id: str) -> int:
        for i, op in enumerate(self.operations):
            if op.id == str(op_id):
                return i
        raise ValueError(f"unknown operation {op_id!r}")

    def operation(self, op_id: str) -> Operation:
        return self.operations[self.op_index(op_id)]

    def build_gravity(self, unit: str) -> str:
        """The gravity in the workspace of ``unit`` (product frame; ``""``: main)."""
        return dict(self.unit_gravity).get(unit, self.gravity) if unit else self.gravity

    def agent(self, name: str) -> Agent:
        for a in self.agents:
            if a.name == name:
                return a
        raise ValueError(f"unknown agent {name!r}")

    def tool(self, name: str) -> Tool:
        for t in self.tools:
            if t.name == name:
                return t
        raise ValueError(f"unknown tool {name!r}")

    @property
    def part_ids(self) -> tuple[str, ...]:
        return tuple(p.id for p in self.parts)

    @property
    def placed_parts(self) -> tuple[str, ...]:
        """Parts placed by some operation, in operation order."""
        return tuple(p for op in self.operations for p in op.parts)

    @property
    def has_geometry(self) -> bool:
        """True when some operation places a part that has a mesh file."""
        files = {p.id for p in self.parts if p.file}
        return any(p in files for p in self.placed_parts)

    @property
    def folder(self) -> Path | None:
        """The folder part files are relative to (the spec's, or the CAD file's)."""
        if not self.source:
            return None
        path = Path(self.source)
        return path if path.is_dir() else path.parent


# --------------------------------------------------------------------------- loading


def resolve_spec_path(path: str | os.PathLike[str]) -> Path:
    """The ``assembly.yaml`` of ``path`` (a folder holding one, or the file itself)."""
    path = Path(path)
    if path.is_dir():
        candidate = path / SPEC_FILE
        if not candidate.is_file():
            raise FileNotFoundError(f"{path}: no {SPEC_FILE} in this folder")
        return candidate
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file or folder")
    return path


def load_spec(path: str | os.PathLike[str]) -> AssemblySpec:
    """Load and validate an assembly spec: a folder with ``assembly.yaml``, the YAML, a ``.IN2``.

    A CAD file or a folder of part meshes has no spec to load: see
    :func:`asp.fromcad.generate.generated_spec` (:func:`asp.fromcad.generate.load_any` picks).

    Raises
    ------
    FileNotFoundError
        The path does not exist.
    ValueError
        One line naming the file, the key and the offending operation or part.
    """
    path = Path(path)
    if path.suffix.lower() == ".in2":
        from asp.salbp import in2_assembly

        return spec_from_dict(in2_assembly(path), source=str(path))
    path = resolve_spec_path(path)
    data = read_yaml(path, what="assembly spec", decimals_as_text=True)
    return spec_from_dict(data, source=str(path))


def spec_from_dict(data: dict, source: str = "<dict>") -> AssemblySpec:
    """Build and validate an :class:`AssemblySpec` from a parsed YAML mapping."""
    return _Parser(source).parse(data)


class _Parser:
    def __init__(self, source: str):
        self.source = source

    def fail(self, key: str, message: str) -> ValueError:
        return ValueError(f"{self.source}: {key}: {message}")

    # ------------------------------------------------------------------ scalars
    def number(self, value, key: str, *, minimum: float = 0.0) -> float:
        """``value`` as a number (:func:`cad.numbers.plain_number`: ``010``, ``1_000``,
        ``1:30`` and ``true`` are refused) in ``[minimum, MAX_COST]``."""
        x = plain_number(value)
        if x is None:
            raise self.fail(key, f"expected a number {WRITTEN_PLAINLY}, got {value!r}")
        if not x >= minimum or x == float("inf"):
            raise self.fail(key, f"expected a finite number >= {minimum:g}, got {value!r}")
        if x > MAX_COST:
            raise self.fail(key, f"expected a number up to {MAX_COST:g}, got {value!r}")
        return x

    def text(self, value, key: str) -> str:
        if value is None or isinstance(value, dict | list):
            raise self.fail(key, f"expected a name, got {value!r}")
        out = self.bounded(str(value).strip(), key)
        if not out:
            raise self.fail(key, "expected a non-empty name")
        return out

    def bounded(self, text: str, key: str, limit: int = MAX_NAME) -> str:
        """``text`` within :func:`cad.texts.bounded`'s limit (a name's by default)."""
        return bounded(text, f"{self.source}: {key}", limit)

    def prose(self, value, key: str) -> str:
        """A free description (empty when absent), at most :data:`cad.texts.MAX_TEXT`."""
        return text_value(value, f"{self.source}: {key}", MAX_TEXT, strip=False)

    def mapping(self, value, key: str, known: tuple[str, ...] = ()) -> dict:
        """A mapping (None: empty); with ``known``, any other key is refused."""
        if value is None:
            return {}
        if not isinstance(value, dict):
            raise self.fail(key, f"expected a mapping, got {type(value).__name__}")
        if known:
            refuse_unknown_keys(value, known, f"{self.source}: {key}")
        return value

    def direction(self, value, key: str) -> str:
        d = str(value).strip().lower()
        if d in ("x", "y", "z"):
            d = "+" + d
        if d not in DIRECTIONS:
            raise self.fail(key, f"expected one of {' '.join(DIRECTIONS)}, got {value!r}")
        return d

    # ------------------------------------------------------------------ sections
    def parse(self, data) -> AssemblySpec:
        if not isinstance(data, dict):
            raise ValueError(f"{self.source}: expected a YAML mapping at the top level")
        refuse_unknown_keys(data, TOP_KEYS, self.source)
        units = data.get("units")
        if units is not None:
            try:
                unit_scale(units)
            except ValueError as exc:
                raise self.fail("units", str(exc)) from None
        parts = self.parts(data.get("parts"))
        agents = self.agents(data.get("agents"))
        tools = self.tools(data.get("tools"))
        ops = self.operations(data.get("operations"), parts, agents, tools)
        part_ids = {p.id for p in parts}
        base = data.get("base_part")
        if base is not None:
            base = self.text(base, "base_part")
            if base not in part_ids:
                raise self.fail("base_part", f"unknown part {base!r}")
        elif parts and any(op.parts for op in ops):
            base = parts[0].id
        gravity = self.direction(data.get("gravity", "-z"), "gravity")
        approach_raw = data.get("gripper_approach", list(DIRECTIONS))
        if isinstance(approach_raw, str):
            approach_raw = [approach_raw]
        if not isinstance(approach_raw, list) or not approach_raw:
            raise self.fail("gripper_approach", "expected a non-empty list of directions")
        approach = tuple(dict.fromkeys(self.direction(d, "gripper_approach") for d in approach_raw))
        cons = self.mapping(data.get("constraints"), "constraints")
        refuse_unknown_keys(cons, CONSTRAINT_KEYS, f"{self.source}: constraints", "switch")
        flags = {}
        for key in CONSTRAINT_KEYS:
            value = cons.get(key, True)
            if not isinstance(value, bool):
                raise self.fail(f"constraints.{key}", f"expected true or false, got {value!r}")
            flags[key] = value
        turn = str(data.get("turn_model", DEFAULT_TURN.name))
        if turn not in TURN_MODELS:
            raise self.fail("turn_model", f"expected {expected_names(quote=True)}, got {turn!r}")
        cost = str(data.get("cost", "steps"))
        if cost not in COST_MODELS:
            raise self.fail("cost", f"expected 'steps' or 'time', got {cost!r}")
        max_states = data.get("max_states")
        if max_states is not None and (
            isinstance(max_states, bool) or not isinstance(max_states, int) or max_states < 1
        ):
            raise self.fail("max_states", f"expected a positive integer, got {max_states!r}")
        tols = {}
        for key in ("contact_tol", "penetration_tol"):
            try:
                tols[key] = checked_tolerance(data.get(key), key)
            except ValueError as exc:
                raise ValueError(f"{self.source}: {exc}") from None
        try:
            frame = parse_frame(data.get("frame"))
        except ValueError as exc:
            raise self.fail("frame", str(exc)) from None
        spec = AssemblySpec(
            name=(
                self.text(data["name"], "name")
                if data.get("name") not in (None, "")
                else self.bounded(Path(self.source).parent.name or "assembly", "name")
            ),
            operations=ops,
            agents=agents,
            parts=parts,
            tools=tools,
            base_part=base,
            gravity=gravity,
            gripper_approach=approach,
            constraints=Constraints(**flags),
            turn_model=turn,
            cost=cost,
            source=self.source,
            units=None if units is None else str(units),
            credit=self.prose(data.get("credit", ""), "credit"),
            max_states=max_states,
            frame=frame,
            flex=parse_flex(data.get("flex"), part_ids, self.source),
            overlap_ok=parse_overlap_ok(data.get("overlap_ok"), part_ids, self.source),
            **tols,
        )
        raw_units = self.mapping(data.get("subassemblies"), "subassemblies")
        if not raw_units:
            return spec
        units, turned, held = [], [], set()
        for uid, members in raw_units.items():
            where = f"subassemblies.{uid}"
            if isinstance(members, dict):
                keys = ("parts", "gravity", "held")
                refuse_unknown_keys(members, keys, f"{self.source}: {where}")
                if "gravity" in members:
                    g = self.direction(members["gravity"], f"{where}.gravity")
                    if g != spec.gravity:
                        turned.append((str(uid), g))
                if members.get("held", False) not in (True, False):
                    raise self.fail(f"{where}.held", "expected true or false")
                if members.get("held"):
                    held.add(str(uid))
                members = members.get("parts")
            if not isinstance(members, list):
                raise self.fail(where, "expected a list of part ids or {parts: [...], gravity}")
            units.append((str(uid), tuple(self.text(m, where) for m in members)))
        spec = with_subassemblies(spec, units)
        ops = tuple(replace(op, held=True) if op.unit in held else op for op in spec.operations)
        return replace(spec, operations=ops, unit_gravity=tuple(turned))

    def parts(self, raw) -> tuple[Part, ...]:
        if raw is None:
            return ()
        return part_records(raw, f"{self.source}: parts")

    def agents(self, raw) -> tuple[Agent, ...]:
        if isinstance(raw, list):
            items = []
            for k, item in enumerate(raw):
                if not isinstance(item, dict) or not ({"name", "id"} & set(item)):
                    raise self.fail(f"agents[{k}]", "expected a mapping with a 'name'")
                items.append((item.get("name", item.get("id")), item))
        else:
            items = list(self.mapping(raw, "agents").items())
        if not items:
            raise self.fail("agents", "expected at least one agent")
        out, seen = [], set()
        for name, item in items:
            name = self.text(name, "agents")
            if name in seen:
                raise self.fail("agents", f"duplicate agent {name!r}")
            seen.add(name)
            if isinstance(item, str):
                item = {"side": item}
            item = self.mapping(item, f"agents.{name}", AGENT_KEYS)
            side = str(item.get("side", "")).lower()
            if side not in SIDES:
                raise self.fail(
                    f"agents.{name}.side", f"expected human, robot or any, got {item.get('side')!r}"
                )
            description = self.prose(item.get("description", ""), f"agents.{name}.description")
            out.append(Agent(name=name, side=side, description=description))
        return tuple(out)

    def tools(self, raw) -> tuple[Tool, ...]:
        out = []
        for name, item in self.mapping(raw, "tools").items():
            name = self.text(name, "tools")
            item = self.mapping(item, f"tools.{name}", TOOL_KEYS)
            if "initial" not in item:
                raise self.fail(f"tools.{name}", "missing 'initial' value")
            out.append(
                Tool(
                    name=name,
                    initial=self.text(item["initial"], f"tools.{name}.initial"),
                    change_time=self.number(
                        item.get("change_time", 0), f"tools.{name}.change_time"
                    ),
                )
            )
        return tuple(out)

    def operations(self, raw, parts, agents, tools) -> tuple[Operation, ...]:
        if not isinstance(raw, list) or not raw:
            raise self.fail("operations", "expected a non-empty list")
        agent_names = {a.name for a in agents}
        part_ids = {p.id for p in parts}
        tool_names = {t.name for t in tools}
        ops: list[Operation] = []
        seen: set[str] = set()
        placed_by: dict[str, str] = {}
        for k, item in enumerate(raw):
            if not isinstance(item, dict) or "id" not in item:
                raise self.fail(f"operations[{k}]", "expected a mapping with an 'id'")
            oid = self.text(item["id"], f"operations[{k}].id")
            where = f"operations[{oid}]"
            if oid in seen:
                raise self.fail("operations", f"duplicate operation id {oid!r}")
            seen.add(oid)
            refuse_unknown_keys(item, OPERATION_KEYS, f"{self.source}: {where}")
            agents_raw = self.mapping(item.get("agents"), f"{where}.agents")
            if not agents_raw:
                raise self.fail(f"{where}.agents", "no agent may do this operation")
            durations, ranges = [], []
            for a, d in agents_raw.items():
                a = str(a)
                if a not in agent_names:
                    raise self.fail(f"{where}.agents", f"unknown agent {a!r}")
                key = f"{where}.agents.{a}"
                if isinstance(d, list):
                    if len(d) != 2:
                        raise self.fail(key, f"expected a duration or [min, max], got {d!r}")
                    lo, hi = self.number(d[0], key), self.number(d[1], key)
                    if lo > hi:
                        raise self.fail(key, f"range [min, max] with min > max: {d!r}")
                    ranges.append((a, lo, hi))
                    durations.append((a, hi))
                else:
                    durations.append((a, self.number(d, key)))
            if "part" in item and "parts" in item:
                raise self.fail(where, "both part and parts: give one (a list goes in either)")
            placed = item.get("part", item.get("parts"))
            if placed is None:
                placed = []
            elif not isinstance(placed, list):
                placed = [placed]
            placed = tuple(self.text(p, f"{where}.part") for p in placed)
            for p in placed:
                if p not in part_ids:
                    raise self.fail(f"{where}.part", f"unknown part {p!r}")
                if p in placed_by:
                    raise self.fail(
                        f"{where}.part", f"part {p!r} is already placed by operation "
                        f"{placed_by[p]!r}"
                    )  # fmt: skip
                placed_by[p] = oid
            tool_pairs = {}
            for key in ("requires", "sets"):
                pairs = []
                for t, v in self.mapping(item.get(key), f"{where}.{key}").items():
                    t = str(t)
                    if t not in tool_names:
                        raise self.fail(f"{where}.{key}", f"unknown tool {t!r}")
                    pairs.append((t, self.text(v, f"{where}.{key}.{t}")))
                tool_pairs[key] = tuple(pairs)
            after_raw = item.get("after") or []
            if not isinstance(after_raw, list):
                after_raw = [after_raw]
            held = item.get("held", False)
            if not isinstance(held, bool):
                raise self.fail(f"{where}.held", f"expected true or false, got {held!r}")
            ops.append(
                Operation(
                    id=oid,
                    description=self.prose(item.get("description") or "", f"{where}.description"),
                    durations=tuple(durations),
                    parts=placed,
                    requires=tool_pairs["requires"],
                    sets=tool_pairs["sets"],
                    after=tuple(dict.fromkeys(self.text(a, f"{where}.after") for a in after_raw)),
                    held=held,
                    ranges=tuple(ranges),
                )
            )
        self.check_predecessors(ops)
        self.check_tools(ops, tools)
        return tuple(ops)

    def check_predecessors(self, ops: list[Operation]) -> None:
        check_predecessors(ops, self.source)

    def check_tools(self, ops: list[Operation], tools: tuple[Tool, ...]) -> None:
        values = {t.name: {t.initial} for t in tools}
        for op in ops:
            for t, v in op.sets:
                values[t].add(v)
        for op in ops:
            for t, v in op.requires:
                if v not in values[t]:
                    raise self.fail(
                        f"operations[{op.id}].requires",
                        f"tool value {t} = {v!r} is needed but never set nor initial",
                    )


def with_tolerances(
    spec: AssemblySpec, contact_tol: float | None = None, penetration_tol: float | None = None
) -> AssemblySpec:
    """``spec`` with the tolerances given (mm) in place of its own; None keeps the spec's."""
    changes = {
        key: checked_tolerance(value, key)
        for key, value in (("contact_tol", contact_tol), ("penetration_tol", penetration_tol))
        if value is not None
    }
    return replace(spec, **changes) if changes else spec


def with_subassemblies(
    spec: AssemblySpec, units: Iterable[tuple[str, Iterable[str]]]
) -> AssemblySpec:
    """``spec`` with the subassemblies ``units`` (unit id, member part ids) and their
    insertion operations added.

    Raises
    ------
    ValueError
        One line naming the unit: an unknown or repeated member, the base part as a member,
        fewer than two members, an id already used, or an operation placing members of the
        unit and other parts.
    """
    units = [(str(u), tuple(dict.fromkeys(str(m) for m in ms))) for u, ms in units]
    known = set(spec.part_ids) | set(spec.placed_parts)
    taken = {m for _, ms in spec.subassemblies for m in ms}
    ids = set(spec.op_ids) | known | {u for u, _ in spec.subassemblies}
    ops = list(spec.operations)
    for uid, members in units:
        where = f"{spec.source}: subassemblies.{uid}"
        if uid in ids:
            raise ValueError(f"{where}: the id is already used by an operation or part")
        if len(members) < 2:
            raise ValueError(f"{where}: a subassembly needs at least two parts")
        for m in members:
            if m not in known:
                raise ValueError(f"{where}: unknown part {m!r}")
            if m in taken:
                raise ValueError(f"{where}: part {m!r} is already in another subassembly")
            if m == spec.base_part:
                raise ValueError(f"{where}: the base part {m!r} cannot be in a subassembly")
        member_ops = [op for op in ops if set(op.parts) & set(members)]
        for op in member_ops:
            if not set(op.parts) <= set(members):
                raise ValueError(
                    f"{where}: operation {op.id} places parts inside and outside the unit"
                )
        unplaced = set(members) - {p for op in member_ops for p in op.parts}
        if unplaced:
            raise ValueError(f"{where}: no operation places part {sorted(unplaced)[0]!r}")
        longest: dict[str, float] = {}
        for op in member_ops:
            for agent, d in op.durations:
                longest[agent] = max(longest.get(agent, 0.0), d)
        ops.append(
            Operation(
                id=uid,
                description=f"insert subassembly {uid} ({', '.join(members)})",
                durations=tuple(longest.items()),
                after=tuple(op.id for op in member_ops),
                unit=uid,
            )
        )
        taken |= set(members)
        ids.add(uid)
    return replace(spec, operations=tuple(ops), subassemblies=(*spec.subassemblies, *units))


def check_predecessors(ops, source: str) -> None:
    """Raise ``ValueError`` for an unknown, self or cyclic predecessor (naming the cycle)."""
    ids = {op.id for op in ops}
    g = nx.DiGraph()
    g.add_nodes_from(op.id for op in ops)
    for op in ops:
        for a in op.after:
            if a not in ids:
                raise ValueError(f"{source}: operations[{op.id}].after: unknown predecessor {a!r}")
            if a == op.id:
                raise ValueError(f"{source}: operations[{op.id}].after: operation precedes itself")
            g.add_edge(a, op.id)
    try:
        cycle = nx.find_cycle(g)
    except nx.NetworkXNoCycle:
        return
    names = [u for u, _ in cycle] + [cycle[0][0]]
    raise ValueError(
        f"{source}: operations[{cycle[0][1]}].after: cyclic predecessors: " + " -> ".join(names)
    )


def tool_values(spec: AssemblySpec) -> dict[str, tuple[str, ...]]:
    """Every value each tool can take: the initial one first, then in order of appearance."""
    out = {t.name: [t.initial] for t in spec.tools}
    for op in spec.operations:
        for t, v in (*op.sets, *op.requires):
            if v not in out[t]:
                out[t].append(v)
    return {k: tuple(v) for k, v in out.items()}


__all__ = [
    "DIRECTIONS",
    "SPEC_FILE",
    "TURN_MODELS",
    "Agent",
    "AssemblySpec",
    "Constraints",
    "Operation",
    "Part",
    "Tool",
    "load_spec",
    "resolve_spec_path",
    "spec_from_dict",
    "tool_values",
    "with_subassemblies",
    "with_tolerances",
]
"""What other modules may use (asmplan and arl among them)."""
