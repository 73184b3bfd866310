"""``study.yaml``: a trust study run with ``asmplan serve --study study.yaml``.

The file (format ``asmplan-study/1``; paths relative to the file; every key is checked and
an unknown one is refused with its place):

.. code-block:: yaml

    format: asmplan-study/1
    title: Does a robust robot earn trust?
    consent: |                      # shown before anything else; the participant agrees
      You will assemble a box with two robots ...
    plans:                          # what each participant assembles, in this order
      - source: ../finger_box       # an assembly (folder, assembly.yaml) or a plan folder
        turn_model: concurrent      # optional: the spec's otherwise
    conditions:                     # the robots
      - {id: robust, label: Robot A, robot: robust}
      - {id: schedule, label: Robot B, robot: cp-sat}
      # robot: robust | fast-greedy | cp-sat | ignores-person | {run: runs/box}
      # ignores-person may take script: {R1: [op, ...], R2: [...]}
    assignment:
      design: within                # within | between
      order: counterbalanced        # counterbalanced | random
      plans: fixed                  # fixed | counterbalanced | random
      seed: 0                       # for random
    questionnaire:
      scales:
        agree7: {min: 1, max: 7, labels: {1: Strongly disagree, 7: Strongly agree}}
      items:
        - {id: reliable, text: The robots were reliable., scale: agree7, required: true}
        - {id: comment, text: Anything else?, scale: text}
      # or: file: items.yaml (a list of items, or {scales, items}): a published scale
    realtime:                       # optional: the clock runs
      speed: 5                      # game seconds per wall-clock second

:func:`load_study` reads it; :class:`Study` is the result. Plans are not planned here:
:func:`asmplan.study.plans.study_plans` does it, once per plan, and makes each condition's
plan document.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import yaml

from asmplan.study.assignment import DESIGNS, ORDERS, PLAN_ORDERS
from asmplan.study.conditions import ROBOTS, Condition
from asmplan.study.questionnaire import Item, items_from_data, scale_from_data
from asp.spec import TURN_MODELS
from cad.yamlfile import PlainNumbers

FORMAT = "asmplan-study/1"
MAX_TEXT = 20_000
"""Longest consent text, characters."""
_ID = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$")


@dataclass(frozen=True)
class StudyPlan:
    """One plan of the study: its source and turn model (None: the spec's)."""

    source: Path
    turn_model: str | None = None


@dataclass(frozen=True)
class Study:
    """A study file, checked (module docstring)."""

    path: Path
    title: str
    consent: str
    plans: tuple[StudyPlan, ...]
    conditions: tuple[Condition, ...]
    design: str
    order: str
    plan_order: str
    seed: int
    questionnaire: tuple[Item, ...]
    speed: float | None = None

    def summary(self) -> dict:
        """What ``GET /api/study`` says (conditions by label and id; the robots' kinds
        stay with the researcher)."""
        return {
            "title": self.title,
            "consent": self.consent,
            "design": self.design,
            "order": self.order,
            "plans_order": self.plan_order,
            "conditions": [{"id": c.id, "label": c.label} for c in self.conditions],
            "questionnaire": [item.to_dict() for item in self.questionnaire],
            "realtime": None if self.speed is None else {"speed": self.speed},
        }


class _Keys:
    """Reads one mapping of the file, naming the place of every fault."""

    def __init__(self, data, where: str, known: tuple[str, ...]):
        if not isinstance(data, dict):
            raise ValueError(f"{where}: expected a mapping")
        unknown = sorted(set(data) - set(known))
        if unknown:
            raise ValueError(f"{where}: unknown key {unknown[0]!r} (known: {', '.join(known)})")
        self.data, self.where = data, where

    def text(self, key: str, default: str | None = None, limit: int = 200) -> str:
        value = self.data.get(key, default)
        if not isinstance(value, str) or not value.strip() or len(value) > limit:
            raise ValueError(f"{self.where}: {key}: expected text (at most {limit} characters)")
        return value.strip()

    def choice(self, key: str, values: tuple[str, ...], default: str) -> str:
        value = self.data.get(key, default)
        if value not in values:
            raise ValueError(f"{self.where}: {key}: expected {' or '.join(values)}, got {value!r}")
        return value


def load_study(path: str | Path) -> Study:
    """Read and check ``study.yaml`` (``ValueError`` naming the file and the key)."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ValueError(f"{path}: cannot read ({exc.strerror or exc})") from None
    try:
        data = yaml.load(text, Loader=PlainNumbers)  # noqa: S506 - a SafeLoader
    except yaml.YAMLError as exc:
        raise ValueError(f"{path}: not YAML ({_yaml_problem(exc)})") from None
    top = _Keys(
        data,
        str(path),
        (
            "format",
            "title",
            "consent",
            "plans",
            "conditions",
            "assignment",
            "questionnaire",
            "realtime",
        ),
    )
    if data.get("format", FORMAT) != FORMAT:
        raise ValueError(f"{path}: format: expected {FORMAT!r}, got {data.get('format')!r}")
    base = path.parent
    plans = _plans(data.get("plans"), f"{path}: plans", base)
    conditions = _conditions(data.get("conditions"), f"{path}: conditions", base)
    assign = _Keys(
        data.get("assignment") or {}, f"{path}: assignment", ("design", "order", "plans", "seed")
    )
    seed = assign.data.get("seed", 0)
    if not isinstance(seed, int) or isinstance(seed, bool):
        raise ValueError(f"{path}: assignment: seed: expected a whole number, got {seed!r}")
    speed = None
    if data.get("realtime") is not None:
        rt = _Keys(data["realtime"], f"{path}: realtime", ("speed",))
        speed = rt.data.get("speed", 1)
        if not isinstance(speed, int | float) or isinstance(speed, bool) or not 0 < speed <= 1000:
            raise ValueError(
                f"{path}: realtime: speed: expected game seconds per second (0 to 1000]"
            )
        speed = float(speed)
    return Study(
        path=path,
        title=top.text("title", "asmplan study"),
        consent=top.text("consent", "", limit=MAX_TEXT) if data.get("consent") else "",
        plans=plans,
        conditions=conditions,
        design=assign.choice("design", DESIGNS, "within"),
        order=assign.choice("order", ORDERS, "counterbalanced"),
        plan_order=assign.choice("plans", PLAN_ORDERS, "fixed"),
        seed=seed,
        questionnaire=tuple(
            _questionnaire(data.get("questionnaire"), f"{path}: questionnaire", base)
        ),
        speed=speed,
    )


def _yaml_problem(exc: yaml.YAMLError) -> str:
    mark = getattr(exc, "problem_mark", None)
    problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
    if mark is None:
        return problem
    return f"{problem} at line {mark.line + 1}, column {mark.column + 1}"


def _plans(data, where: str, base: Path) -> tuple[StudyPlan, ...]:
    if not isinstance(data, list) or not data:
        raise ValueError(f"{where}: expected a list of plans ({{source: ...}})")
    out = []
    for n, raw in enumerate(data):
        if isinstance(raw, str):
            raw = {"source": raw}
        keys = _Keys(raw, f"{where}[{n}]", ("source", "turn_model"))
        source = base / keys.text("source", limit=1000)
        if not source.exists():
            raise ValueError(f"{where}[{n}]: source {source}: no such file or folder")
        turn = raw.get("turn_model")
        if turn is not None and turn not in TURN_MODELS:
            raise ValueError(f"{where}[{n}]: turn_model: expected {' or '.join(TURN_MODELS)}")
        out.append(StudyPlan(source, turn))
    return tuple(out)


def _conditions(data, where: str, base: Path) -> tuple[Condition, ...]:
    if not isinstance(data, list) or not data:
        raise ValueError(f"{where}: expected a list of conditions ({{id, label, robot}})")
    out, seen = [], set()
    for n, raw in enumerate(data):
        at = f"{where}[{n}]"
        keys = _Keys(raw, at, ("id", "label", "robot", "script"))
        cid = keys.text("id", limit=64)
        if not _ID.match(cid):
            raise ValueError(f"{at}: id {cid!r}: expected letters, digits, '_', '.', '-'")
        if cid in seen:
            raise ValueError(f"{at}: condition {cid!r} given twice")
        seen.add(cid)
        label = keys.text("label", f"Robot {chr(ord('A') + n)}", limit=64)
        robot, run = raw.get("robot", "robust"), None
        if isinstance(robot, dict):
            run_keys = _Keys(robot, f"{at}: robot", ("run",))
            run = base / run_keys.text("run", limit=1000)
            if not run.is_dir():
                raise ValueError(f"{at}: robot: run {run}: no such run folder")
            robot = "run"
        elif robot not in ROBOTS:
            raise ValueError(
                f"{at}: robot: expected {', '.join(ROBOTS)} or {{run: DIR}}, got {robot!r}"
            )
        script = raw.get("script")
        if script is not None:
            if robot != "ignores-person":
                raise ValueError(f"{at}: script: only for robot ignores-person")
            ok = isinstance(script, dict) and all(
                isinstance(a, str) and isinstance(ops, list) for a, ops in script.items()
            )
            if not ok:
                raise ValueError(f"{at}: script: expected robot -> [operation, ...]")
            script = {a: [str(op) for op in ops] for a, ops in script.items()}
        out.append(Condition(cid, label, robot, run, script))
    return tuple(out)


def _questionnaire(data, where: str, base: Path) -> list[Item]:
    if data is None:
        raise ValueError(f"{where}: expected the questionnaire's items (the researcher's)")
    keys = _Keys(data, where, ("scales", "items", "file"))
    if "file" in data:
        if "items" in data:
            raise ValueError(f"{where}: give items or file, not both")
        source = base / keys.text("file", limit=1000)
        try:
            loaded = yaml.load(source.read_text(encoding="utf-8"), Loader=PlainNumbers)  # noqa: S506
        except OSError as exc:
            raise ValueError(f"{where}: file {source}: cannot read ({exc.strerror})") from None
        except yaml.YAMLError as exc:
            raise ValueError(f"{source}: not YAML ({_yaml_problem(exc)})") from None
        if isinstance(loaded, list):
            loaded = {"items": loaded}
        inner = _Keys(loaded, str(source), ("scales", "items"))
        data = {
            "scales": {**(data.get("scales") or {}), **(inner.data.get("scales") or {})},
            "items": inner.data.get("items"),
        }
        where = str(source)
    scales_data = data.get("scales") or {}
    if not isinstance(scales_data, dict):
        raise ValueError(f"{where}: scales: expected name -> {{min, max, labels}}")
    scales = {
        str(name): scale_from_data(str(name), value, f"{where}: scales: {name}")
        for name, value in scales_data.items()
    }
    return items_from_data(data.get("items"), f"{where}: items", scales)
