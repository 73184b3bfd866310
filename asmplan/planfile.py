"""The plan file ``plan.json`` (format ``asmplan-plan/2``): the robust policy a cell runs.

A robust plan is a policy, not a line (``../shared/DESIGN.md``, "The plan a robot runs").
The file holds, for every state the robust robot can reach against any human, the robots'
next operations, the instruction to the person and the remaining guaranteed bound
(``policy``); the principal line (``robust_plan``: both sides follow the plan); the worst
line (``worst_line``: the robust robot against a delaying human); the metrics and the CP-SAT
schedule. The JSON Schema is ``asmplan/schemas/plan-2.schema.json`` (shipped in the package).
Times measured while planning (the CP-SAT wall times, its improvements over time, the
concurrent game's seconds; :data:`TIMING_KEYS`) are not in the plan document but in
``timings.json`` beside it (:func:`split_timings`), so ``plan.json`` is a pure function of
its inputs.

The policy table is columnar so that large policies stay fast to write and read: state
``i`` is entry ``i`` of every array of ``policy.states``; its moves are
``policy.moves.*[ptr[i]:ptr[i + 1]]``. A state's done operations are a hexadecimal bit mask
over ``policy.operations`` (bit ``k`` set: ``operations[k]`` done); its tools are value
indices into ``policy.tools``. A move's operation and agent are indices into
``policy.operations`` and ``policy.agents`` (``-1``: the side passes at zero cost).
:class:`asmplan.advisor.Advisor` reads it and answers in operation ids.

Turn model ``alternate``: a state is (assembly state, side on turn). At a robot state the
table keeps the robots' one planned move; at a human state every move the person may make.
The instruction to the person is the move that keeps the guaranteed bound lowest (ties: the
cooperative cost, then the move order).
"""

from __future__ import annotations

import json
import os
import time
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from asp.atomic import write_text
from asp.errors import FormatError
from asp.game.dag import ROBOT
from asp.game.metrics import adversarial_tax
from asp.game.policy import PlayedPolicy, PolicyTable, StateDescriber
from asp.game.turns import CONCURRENT, turn_of
from asp.graph.game_states import AlternateStates

if TYPE_CHECKING:  # pragma: no cover - types only
    from asp.concurrent.describe import PolicyNames

FORMAT = "asmplan-plan/2"
MAIN = "main"
"""The workspace of the main assembly (a unit's workspace is named by the unit's id)."""
SCHEMA_FILE = "plan-2.schema.json"
TURN_NAMES = ("robot", "human")


# --------------------------------------------------------------------------- policy table


def played_policy_object(played: PlayedPolicy, describe: StateDescriber | None) -> dict:
    """The ``policy`` object of the plan file from a :class:`PlayedPolicy`."""
    table = played.table
    op_index = {op: k for k, op in enumerate(played.operations)}
    agent_index = {a: k for k, a in enumerate(played.agents)}
    states = _state_columns(table, describe or _anonymous, op_index, agent_index)

    ptr, turns = table.ptr.tolist(), table.turn.tolist()
    ops, agents = played.operation.tolist(), played.agent.tolist()
    robots: list[list] = []
    instruction: list = []
    for i, j in enumerate(table.instruction.tolist()):
        lo = ptr[i]
        if turns[i] == ROBOT and ptr[i + 1] > lo and ops[lo] >= 0:
            robots.append([[ops[lo], agents[lo]]])
        else:
            robots.append([])
        instruction.append(None if j < 0 else [ops[j], agents[j]])
    states.update(robots=robots, instruction=instruction)
    tools = states.pop("_tools")
    return {
        **_policy_head(
            played.turn_model, played.cost_model, table, played.operations, played.agents, tools
        ),
        "states": {"node": played.node_ids, **states},
        "moves": {
            "ptr": ptr,
            "operation": ops,
            "agent": agents,
            "cost": _numbers(played.cost),
            "next": table.next.tolist(),
        },
    }


def _policy_head(turn_model, cost_model, table, op_names, agent_names, tools) -> dict:
    return {
        "turn_model": turn_model,
        "cost": cost_model,
        "operations": op_names,
        "agents": agent_names,
        "tools": tools,
        "start": 0,
        "n_states": int(table.node.size),
        "n_moves": int(table.edge.size),
    }


def _state_columns(table: PolicyTable, describe, op_index: dict, agent_index: dict) -> dict:
    """``turn``, ``done``, ``tools``, ``running``, ``bound`` (and ``_tools``: tool -> values)."""
    if isinstance(describe, AlternateStates) and not describe.has_tools:
        n = table.node.size
        return {
            "turn": np.array(TURN_NAMES, dtype=object)[table.turn].tolist(),
            "done": _done_masks(describe, table.node, op_index),
            "tools": [[] for _ in range(n)],
            "running": [[] for _ in range(n)],
            "bound": _numbers(table.bound),
            "_tools": {},
        }
    tools: dict[str, list[str]] = {}
    done_col, tools_col, running_col = [], [], []
    cache: dict[int, tuple] = {}
    for v in table.node.tolist():
        if v not in cache:
            state = describe(v)
            values = [_value_index(tools, name, value) for name, value in state["tools"].items()]
            running = [[r["agent"], r["operation"], r["remaining"]] for r in state["running"]]
            cache[v] = (_done_mask(state["done"], op_index), values, running)
        mask_hex, values, running = cache[v]
        done_col.append(mask_hex)
        tools_col.append(values)
        running_col.append(running)
    return {
        "turn": np.array(TURN_NAMES, dtype=object)[table.turn].tolist(),
        "done": done_col,
        "tools": tools_col,
        "running": running_col,
        "bound": _numbers(table.bound),
        "_tools": tools,
    }


def _done_mask(done, op_index: dict) -> str:
    """The hexadecimal done mask of the operations ``done`` (bit ``op_index[op]``: ``op``
    done), as ``policy.states.done`` writes it (module docstring)."""
    mask = 0
    for op in done:
        mask |= 1 << op_index[op]
    return format(mask, "x")


def _done_masks(describe: AlternateStates, nodes: np.ndarray, op_index: dict) -> list[str]:
    """The hexadecimal done mask of each node of ``nodes`` (bit ``op_index[op]``: ``op``
    done), as :func:`_done_mask` writes it, computed for many nodes at once."""
    uniq, inverse = np.unique(nodes, return_inverse=True)
    done = describe.done_matrix(uniq)
    bit_of = np.array([op_index[op] for op in describe.op_ids], dtype=np.int64)
    bits = np.zeros((uniq.size, max(op_index.values(), default=-1) + 1), dtype=bool)
    bits[:, bit_of] = done  # an operation done at some node is always one of op_index
    packed = np.packbits(bits, axis=1, bitorder="little")
    texts = [format(int.from_bytes(row, "little"), "x") for row in map(bytes, packed)]
    return [texts[k] for k in inverse.ravel().tolist()]


def concurrent_policy_object(names: PolicyNames, table: PolicyTable) -> dict:
    """The ``policy`` object of the concurrent game (turn model ``concurrent``, module
    docstring) from its table and the names :func:`asp.concurrent.describe.policy_names`
    gave it.

    A robot state's one move is the robot side's commitment (``robots``: the operations the
    robots start; ``instruction``: what each free person is told); a human state's moves are
    every reply of the human side (``moves.starts``: the operations the people start, with
    the durations they take; ``moves.deviations``), each followed by the wait for the next
    completion (``moves.cost``, the time until it).
    """
    op_names = list(names.operations)
    op_index = {op: k for k, op in enumerate(op_names)}
    agent_names = list(names.agents)
    agent_index = {a: k for k, a in enumerate(agent_names)}

    def told(instruct: dict) -> list | None:
        if not instruct:
            return None
        return [[-1 if o == "wait" else op_index[o], agent_index[h]] for h, o in instruct.items()]

    # Each distinct value converted once, then written for every state or move that has it.
    tools: dict[str, list[str]] = {}
    done_tools = []
    for done, values in names.done_tools:
        done_tools.append(
            (_done_mask(done, op_index), [_value_index(tools, n, x) for n, x in values.items()])
        )
    running = [[[r["agent"], r["operation"], r["remaining"]] for r in rs] for rs in names.running]
    budgets = [budget for budget, _ in names.budget_told]
    instructions = [told(instruct) for _, instruct in names.budget_told]
    starts = [[[op_index[o], agent_index[a], _number(d)] for o, a, d in s] for s, _ in names.starts]
    commits = {k: told(instruct) for k, instruct in names.commits.items()}
    robot_starts = [[s[:2] for s in x] for x in starts]  # a robot move: no durations

    state_of, running_of, told_of = (
        x.tolist() for x in (names.state_of, names.running_of, names.told_of)
    )
    move_of, edges, ptr = names.move_of.tolist(), table.edge.tolist(), table.ptr.tolist()
    robots, instruction = [], []
    for i, t in enumerate(table.turn.tolist()):
        lo = ptr[i]
        if t == ROBOT and ptr[i + 1] > lo and edges[lo] >= 0:
            robots.append(robot_starts[move_of[lo]])
            instruction.append(commits[move_of[lo]])
        else:
            robots.append([])
            instruction.append(instructions[told_of[i]])
    states = {
        "turn": np.array(TURN_NAMES, dtype=object)[table.turn].tolist(),
        "done": [done_tools[k][0] for k in state_of],
        "tools": [done_tools[k][1] for k in state_of],
        "running": [running[k] for k in running_of],
        "bound": _numbers(table.bound),
        "robots": robots,
        "instruction": instruction,
        "budget": [budgets[k] for k in told_of],
    }
    return {
        **_policy_head(CONCURRENT.name, names.cost_model, table, op_names, agent_names, tools),
        "states": {"node": table.node.tolist(), **states},
        "moves": {
            "ptr": ptr,
            "starts": [starts[k] for k in move_of],
            "deviations": [names.starts[k][1] for k in move_of],
            "cost": _numbers(names.cost),
            "next": table.next.tolist(),
        },
    }


def _value_index(tools: dict[str, list[str]], name: str, value: str) -> int:
    """The index of tool ``name``'s ``value`` in ``tools[name]``, appended when new (the
    values of a tool in the order the policy first reaches them)."""
    known = tools.setdefault(name, [])
    if value not in known:
        known.append(value)
    return known.index(value)


def _number(x: float):
    x = float(x)
    return int(x) if x == round(x) else round(x, 6)


def _anonymous(v: int) -> dict:
    return {"done": [], "tools": {}, "running": []}


def _numbers(arr: np.ndarray) -> list:
    """Floats that are whole as ints (shorter JSON), others as floats."""
    arr = np.asarray(arr, dtype=np.float64)
    if np.all(np.isfinite(arr)) and np.all(arr == np.round(arr)):
        return arr.astype(np.int64).tolist()
    return arr.tolist()


# --------------------------------------------------------------------------- lines


def move_starts(policy: dict, j: int) -> list[list]:
    """The operations move ``j`` starts: ``[operation index, agent index, duration]`` each.

    Turn model ``alternate``: the move's one operation (none for a pass); ``concurrent``:
    ``policy.moves.starts[j]``.
    """
    moves = policy["moves"]
    if "starts" in moves:
        return moves["starts"][j]
    if moves["operation"][j] < 0:
        return []
    return [[moves["operation"][j], moves["agent"][j], moves["cost"][j]]]


def worst_move(policy: dict, candidates) -> int:
    """Of the moves ``candidates``, one that keeps the guaranteed bound highest (its cost plus
    the bound after it; ties: the lower index)."""
    states, moves = policy["states"], policy["moves"]
    return max(candidates, key=lambda m: (moves["cost"][m] + states["bound"][moves["next"][m]], -m))


def line_moves(
    policy: dict, follow: str, *, start: int | None = None, first: int | None = None
) -> list[tuple[int, int]]:
    """A line through the policy as ``(state, move)`` pairs, to the end.

    From state ``start`` (default the policy's start), taking move ``first`` there when
    given. The robots take their planned move; the person, with ``follow="plan"``, the
    instruction (in the concurrent game, of the moves without a deviation, the worst: the
    longest durations a range allows), with ``follow="worst"`` a move that keeps the bound
    highest (:func:`worst_move`).
    """
    states, moves = policy["states"], policy["moves"]
    out: list[tuple[int, int]] = []
    i = policy["start"] if start is None else start
    while True:
        lo, hi = moves["ptr"][i], moves["ptr"][i + 1]
        if lo == hi:
            return out
        if first is not None:
            j, first = first, None
        elif states["turn"][i] == "robot" or hi - lo == 1:
            j = lo
        elif follow != "plan":
            j = worst_move(policy, range(lo, hi))
        elif "deviations" in moves:
            calm = [m for m in range(lo, hi) if moves["deviations"][m] == 0]
            j = worst_move(policy, calm or range(lo, hi))
        else:
            j = _instruction_move(policy, i)
        out.append((i, j))
        i = moves["next"][j]


def line_steps(policy: dict, follow: str, operations: dict[str, dict]) -> list[dict]:
    """A line through the policy from the start (:func:`line_moves`), as readable steps.

    ``follow="plan"``: the person follows the instruction (the principal line; in the
    concurrent game, of the durations its range allows, the worst); ``follow="worst"``: the
    person takes a move that keeps the bound highest (the worst line). A step of the
    concurrent game starts several operations at once: ``operation`` and ``agent`` join
    them with commas and ``starts`` lists them.
    """
    states, moves = policy["states"], policy["moves"]
    op_names, agent_names = policy["operations"], policy["agents"]
    steps: list[dict] = []
    total = 0.0
    for i, j in line_moves(policy, follow):
        lo, hi = moves["ptr"][i], moves["ptr"][i + 1]
        turn = states["turn"][i]
        started = [(op_names[o], agent_names[a], d) for o, a, d in move_starts(policy, j)]
        options = []
        if turn == "human":
            options = list(
                dict.fromkeys(
                    " ".join((op_names[o], agent_names[a]))
                    for m in range(lo, hi)
                    for o, a, _ in move_starts(policy, m)
                )
            )
        cost = moves["cost"][j]
        total += cost
        infos = [operations.get(op, {}) for op, _, _ in started]
        idle = "pass" if "starts" not in moves else "wait"
        spaces = list(dict.fromkeys(x.get("workspace", MAIN) for x in infos))
        units = [x["unit"] for x in infos if x.get("unit")]
        steps.append(
            {
                "step": len(steps) + 1,
                "player": turn,
                "operation": ",".join(op for op, _, _ in started),
                "agent": ",".join(a for _, a, _ in started),
                "description": "; ".join(x.get("description", "") for x in infos) or idle,
                "parts": [p for x in infos for p in x.get("parts", [])],
                "starts": [
                    {"operation": op, "agent": a, "duration": d, **_where(x)}
                    for (op, a, d), x in zip(started, infos, strict=True)
                ],
                "workspace": spaces[0] if len(spaces) == 1 else None,
                "unit": units[0] if len(units) == 1 else None,
                "held": any(x.get("held", False) for x in infos),
                "cost": cost,
                "elapsed": total,
                "bound": states["bound"][moves["next"][j]],
                "human_options": options,
                "node": states["node"][i],
            }
        )
    return steps


def _where(info: dict) -> dict:
    """What a line step or an insertion says of one operation it starts: parts, workspace,
    unit, held."""
    return {
        "parts": list(info.get("parts", [])),
        "workspace": info.get("workspace", MAIN),
        "unit": info.get("unit"),
        "held": info.get("held", False),
    }


def _instruction_move(policy: dict, i: int) -> int:
    """The move index of the instruction at state ``i`` (its first move if none)."""
    states, moves = policy["states"], policy["moves"]
    lo, hi = moves["ptr"][i], moves["ptr"][i + 1]
    want = states["instruction"][i]
    if want is not None:
        for m in range(lo, hi):
            if [moves["operation"][m], moves["agent"][m]] == want:
                return m
    return lo


# --------------------------------------------------------------------------- the document


def policy_lines(policy: dict, operations: dict[str, dict]) -> dict[str, list[dict]]:
    """The plan file's two lines of a ``policy`` object: ``robust_plan`` (both sides follow
    the plan) and ``worst_line`` (the robust robot against a delaying human), as
    :func:`line_steps` gives them (without their ``insertions`` yet)."""
    return {
        "robust_plan": line_steps(policy, "plan", operations),
        "worst_line": line_steps(policy, "worst", operations),
    }


def line_operations(steps: list[dict]) -> list[str]:
    """The operations a line starts, in order."""
    return [s["operation"] for step in steps for s in step["starts"]]


def document(
    spec,
    policy: dict,
    sizes: tuple,
    values: tuple,
    operations: dict[str, dict],
    lines: dict[str, list[dict]],
    checks: dict[str, tuple[dict, str | None]],
    *,
    extra: dict | None = None,
    geometry: dict | None = None,
    part_sources: dict | None = None,
    interchangeable=(),
) -> dict:
    """The whole plan file around its ``policy``: lines, metrics, operations, parts, ``extra``.

    ``sizes``: the game's cost model, node and edge counts; ``values``: TCT, W* and the
    expected cost against a random person, from the start. ``operations``: the
    :func:`operation_records` of ``spec``; ``lines``: the :func:`policy_lines` of ``policy``;
    ``checks``: each line's :func:`asp.graph.checker.line_directions` (its steps then get
    their ``insertions``, :func:`add_insertions`; its error is the line's ``line_check``).
    ``extra`` holds the keys computed elsewhere (relations, state graph sizes,
    ``schedule``); they are kept as given. ``geometry``: the unit, scale, frame and
    tolerances of the part meshes (:func:`asmplan.pipeline.geometry_record`, None without
    geometry); ``part_sources``: each part file's ``source`` record
    (:func:`asmplan.pipeline.part_source`), by the file as the spec names it.
    ``interchangeable``: the classes of interchangeable blocks of operations the
    state graph's reduction used (``graph.model.interchangeable``,
    :mod:`asp.graph.symmetry`), written as the plan's ``interchangeable`` for the runtime
    advisor.
    """
    cost_model, n_nodes, n_edges = sizes
    tct, minimax, avg_random = values
    principal, worst = lines["robust_plan"], lines["worst_line"]
    line_check = {}
    for name, steps in lines.items():
        checked, line_check[name] = checks[name]
        add_insertions(steps, spec, checked, operations)
    w0 = principal[-1]["elapsed"] if principal else 0.0
    doc = {
        "format": FORMAT,
        "assembly": spec.name,
        "source": spec.source,
        "turn_model": policy["turn_model"],
        "cost": cost_model,
        "game_nodes": n_nodes,
        "game_edges": n_edges,
        "tct": tct,
        "minimax": minimax,
        "metrics": {
            "tct": tct,
            "minimax": minimax,
            "w0": w0,
            "worst_line": worst[-1]["elapsed"] if worst else 0.0,
            "adversarial_tax": adversarial_tax(tct, minimax),
            "avg_random": avg_random,
            "policy_states": policy["n_states"],
            "policy_moves": policy["n_moves"],
        },
        "agents": {a.name: a.side for a in spec.agents},
        "gravity": spec.gravity,
        "base_part": spec.base_part,
        "geometry": geometry,
        "sources": list(dict.fromkeys(split_file(p.file)[0] for p in spec.parts if p.file)),
        "parts": [
            {
                "id": p.id,
                "name": p.name,
                "file": p.file,
                "quantity": p.quantity,
                "source": (part_sources or {}).get(p.file) if p.file else None,
            }
            for p in spec.parts
        ],
        "operations": operations,
        "subassemblies": {u: list(ms) for u, ms in spec.subassemblies},
        "interchangeable": [[list(block) for block in cls] for cls in interchangeable],
        "workspaces": workspace_records(spec, operations, principal),
        "line_check": line_check,
        "robust_plan": principal,
        "worst_line": worst,
        "policy": policy,
    }
    if extra:
        for key, value in extra.items():
            doc.setdefault(key, value)
    if spec.credit:
        doc["credit"] = spec.credit
    return doc


# --------------------------------------------------------------------------- replay facts
#
# What a checker that replays a line from plan.json and the meshes alone needs: the
# workspace of every operation, the real parts a unit's insertion places, held parts,
# gravity, the length unit and frame, where each part's mesh is, and for each insertion
# the direction it goes in along (README, "The plan file").


def operation_records(spec) -> dict[str, dict]:
    """Operation id -> ``description, agents, parts, workspace, unit, held``.

    ``parts`` are real part ids: a unit's insertion lists the unit's members (``unit`` names
    it). ``workspace`` is where the operation's parts go: ``MAIN``, or the id of the unit
    whose member it places (a unit is built in its own workspace, then inserted into main).
    """
    members = dict(spec.subassemblies)
    owner = {p: u for u, ms in members.items() for p in ms}
    out = {}
    for op in spec.operations:
        parts = list(members.get(op.unit, op.parts)) if op.unit else list(op.parts)
        space = MAIN if op.unit or not op.parts else owner.get(op.parts[0], MAIN)
        out[op.id] = {
            "description": op.description,
            "agents": dict(op.durations),
            "parts": parts,
            "workspace": space,
            "unit": op.unit or None,
            "held": bool(op.held),
        }
    return out


def add_insertions(steps: list[dict], spec, checked: dict, operations: dict) -> None:
    """Give each step ``insertions``: the bodies it puts in, in order, each with its way in.

    An insertion is ``{operation, parts, workspace, unit, held, free_along, insert_along,
    insert_vector_file}``: one per part an operation places in turn, one for a unit (all its
    members together). ``free_along`` is a direction ``d`` of the build frame with ``TT_d``
    from everything already in the workspace (the body can leave along ``d``),
    ``insert_along`` is ``-d``: the body moves along it to go in; ``insert_vector_file`` is
    that direction as a unit vector in the file's coordinates. They are null for the first
    body of a workspace and without geometry. ``checked``: the bodies and directions of the
    line replayed by :func:`asp.graph.checker.line_directions` (empty when the checker
    refused the line: the insertions then carry no directions).
    """
    for step in steps:
        step["insertions"] = []
        for start in step["starts"]:
            op = start["operation"]
            info = operations.get(op, {})
            parts = info.get("parts", [])
            bodies = checked.get(op) or [
                (body, None) for body in ([parts] if info.get("unit") else [[p] for p in parts])
            ]
            for body, free in bodies:
                step["insertions"].append(
                    {
                        "operation": op,
                        **_where(info),
                        "parts": body,  # in _where's place: the keys keep their order
                        "free_along": free,
                        "insert_along": _opposite(free) if free else None,
                        "insert_vector_file": file_vector(spec, _opposite(free)) if free else None,
                    }
                )


def _opposite(direction: str) -> str:
    return ("-" if direction[0] == "+" else "+") + direction[1:]


def build_rotation(spec) -> tuple[tuple[float, ...], ...]:
    """The spec's build frame as a 3x3 rotation ``R`` (``x_build = R @ x_file``; the
    identity for the file's own frame)."""
    identity = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    return identity if getattr(spec, "frame", None) is None else spec.frame


def file_vector(spec, direction: str) -> list[float]:
    """A build-frame axis direction (``"-z"``) as a unit vector in the file's coordinates
    (``R^T`` times the axis vector), rounded to 1e-9."""
    k = "xyz".index(direction[1])
    sign = 1.0 if direction[0] == "+" else -1.0
    return [round(sign * x, 9) + 0.0 for x in build_rotation(spec)[k]]


def split_file(file: str) -> tuple[str, str | None]:
    """``"model.step#nut_2"`` -> ``("model.step", "nut_2")``; a plain file has no node."""
    name, sep, node = file.partition("#")
    return name, (node if sep else None)


def source_folder(source: str) -> Path:
    """The folder part files are relative to: ``source`` itself when it is a folder of
    meshes, else the folder holding it."""
    path = Path(source) if source else Path()
    return path if path.is_dir() else path.parent


def workspace_records(spec, operations: dict, principal: list[dict]) -> list[dict]:
    """The main workspace, then each unit's in the order the principal line inserts them.

    Each: ``id``, ``parts`` (its parts, in the order the principal line places them; main:
    its ``initial`` parts first, then every part placed into it, a unit's members at its
    insertion), ``operations`` (in principal-line order), ``inserted_by`` and ``into``
    (a unit: the operation inserting it, into ``MAIN``; main: null), and ``gravity``: the
    direction a part falls along in that workspace, in the product's frame (main: the
    spec's; a unit built upside down: the opposite, :mod:`asp.fromcad.orientation`), the direction
    its support is tested along.
    """
    placed = {p for info in operations.values() for p in info["parts"]}
    initial = [p.id for p in spec.parts if p.id not in placed]
    order = [s["operation"] for step in principal for s in step["starts"]]
    order += [op for op in operations if op not in order]
    spaces = {MAIN: {"id": MAIN, "initial": initial, "parts": list(initial), "operations": []}}
    inserted_by = {info["unit"]: op for op, info in operations.items() if info["unit"]}
    for op in order:
        info = operations.get(op)
        if info is None:
            continue
        space = info["workspace"]
        if space not in spaces:
            spaces[space] = {"id": space, "parts": [], "operations": []}
        spaces[space]["operations"].append(op)
        spaces[space]["parts"].extend(info["parts"])
    out = []
    for sid, rec in spaces.items():
        unit = sid != MAIN
        out.append(
            {
                **rec,
                "initial": rec.get("initial", []),
                "inserted_by": inserted_by.get(sid) if unit else None,
                "into": MAIN if unit else None,
                "gravity": spec.build_gravity(sid if unit else ""),
            }
        )
    return out


# --------------------------------------------------------------------------- read / write


def write_plan(path: str | os.PathLike[str], doc: dict) -> Path:
    """Write a plan file atomically (compact JSON: large policies stay small)."""
    return write_text(path, json.dumps(doc, separators=(",", ":")) + "\n")


def read_plan(path: str | os.PathLike[str]) -> dict:
    """Read a plan file (or the ``plan.json`` in a folder); check its format and shape.

    Raises
    ------
    ValueError
        Not JSON, another format, or arrays of inconsistent lengths (naming the key).
    """
    path = Path(path)
    if path.is_dir():
        path = path / "plan.json"
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such plan file")
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise FormatError(f"{path}: not JSON ({exc.msg} at line {exc.lineno})") from None
    check_plan(doc, str(path))
    return doc


def check_plan(doc: dict, where: str = "plan") -> None:
    """Check the format and that the policy's columns agree in length."""
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        got = doc.get("format") if isinstance(doc, dict) else type(doc).__name__
        raise FormatError(f"{where}: expected format {FORMAT!r}, got {got!r}")
    policy = doc.get("policy")
    if not isinstance(policy, dict):
        raise FormatError(f"{where}: no policy (write it again with 'asmplan plan')")
    n, m = policy["n_states"], policy["n_moves"]
    for key, column in policy["states"].items():
        if len(column) != n:
            raise FormatError(f"{where}: policy.states.{key}: expected {n} entries")
    if len(policy["moves"]["ptr"]) != n + 1:
        raise FormatError(f"{where}: policy.moves.ptr: expected {n + 1} entries")
    keys = turn_of(policy.get("turn_model")).move_columns
    for key in (*keys, "cost", "next"):
        if len(policy["moves"].get(key, ())) != m:
            raise FormatError(f"{where}: policy.moves.{key}: expected {m} entries")


TIMINGS_FORMAT = "asmplan-timings/1"
TIMING_KEYS = {
    "schedule": ("wall_s", "stage_s", "improvements", "wall_stop"),
    "concurrent": ("seconds", "wall_stop"),
}
"""The keys of a plan document's objects that measure time (``improvements``: ``[seconds,
makespan]`` of each better CP-SAT schedule; ``wall_stop``: the wall-clock seconds at which
the CP-SAT stage's safety net, or the concurrent search's, stopped it, only when it did,
:mod:`asp.schedule.cpsat`); they go to ``timings.json``, not ``plan.json``."""


def split_timings(doc: dict) -> tuple[dict, dict]:
    """``doc`` without its timings, and the timings (``timings.json``'s object).

    ``plan.json`` is then a function of its inputs: two runs on the same input give the same
    bytes. The timings keep the shape they had in the document (``{"schedule": {"wall_s":
    ...}, "concurrent": {"seconds": ...}}``); ``doc`` is not changed.
    """
    plan = dict(doc)
    timings: dict = {"format": TIMINGS_FORMAT}
    for part, keys in TIMING_KEYS.items():
        inner = plan.get(part)
        if not isinstance(inner, dict) or not any(k in inner for k in keys):
            continue
        timings[part] = {k: inner[k] for k in keys if k in inner}
        plan[part] = {k: v for k, v in inner.items() if k not in keys}
    return plan, timings


def plan_schema() -> dict:
    """The JSON Schema of ``asmplan-plan/2`` (shipped in the package)."""
    text = resources.files("asmplan.schemas").joinpath(SCHEMA_FILE).read_text(encoding="utf-8")
    return json.loads(text)


def validate_plan(doc: dict) -> None:
    """Validate ``doc`` against the JSON Schema; raise ``ValueError`` naming the first fault."""
    import jsonschema

    validator = jsonschema.Draft202012Validator(plan_schema())
    error = next(iter(sorted(validator.iter_errors(doc), key=lambda e: list(e.path))), None)
    if error is not None:
        where = "/".join(str(p) for p in error.absolute_path) or "(root)"
        raise FormatError(f"plan.json at {where}: {error.message[:200]}")


def timed_write(path: str | os.PathLike[str], doc: dict) -> tuple[Path, float, int]:
    """Write ``doc``; return the path, the seconds taken and the file size in bytes."""
    t0 = time.perf_counter()
    out = write_plan(path, doc)
    return out, time.perf_counter() - t0, out.stat().st_size
