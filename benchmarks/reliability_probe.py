"""The reliability probe of issue 26, rerun from code: every command on bad and hostile input.

Usage: python benchmarks/reliability_probe.py [--quick] [--only FAMILY,...] [--seed N]

Builds its cases in a temporary folder from the bundled examples (``examples/vacuum_pump``,
``examples/finger_box``, ``tests/cad/data/table_frame_in.step``, synthetic DAGs), runs each
command of the command line in a child process with a timeout (the service over real HTTP
on 127.0.0.1) and puts every case in one of six classes:

- ``clean``: exit 0 with the expected output, or exit 2 with one line on stderr naming the
  file or key and nothing half-written in ``--output``;
- ``traceback``: a Python traceback anywhere in the output;
- ``silent``: a wrong result, or a bad input accepted without a word;
- ``hang``: the timeout struck;
- ``lost``: a kill or a failed write left a file, a session or an event lost, or a folder
  a rerun cannot take.

The families of cases (rows of the table): ``commands`` (every command on valid input),
``spec`` (every key of the spec with wrong types, numbers written oddly, duplicate keys,
huge texts), ``dag`` (bad game-DAG files), ``cad`` (truncated, garbage, header-only and
damaged STEP, empty meshes, NaN vertices, degenerate parts), ``output`` (foreign manifests,
other files, runs repeated into a folder), ``kill`` (SIGKILL at random delays during a
write, then a rerun), ``repeat`` (byte-identical outputs of repeated runs), ``service``
(bad requests, sessions up to the cap, two clients racing on one session, SIGKILL and
restart against the acknowledged events, a re-planned folder), ``disk`` (a full disk: a
small tmpfs when ``mount -t tmpfs`` works, else a file-size limit, RLIMIT_FSIZE; the
table says which).

Every child runs the packages as they were at the start (:func:`snapshot`: a copy, numba's
caches kept), never a checkout that changes under the run.

Prints the table of families x classes and every case outside ``clean`` with its reason.
Exit status 1 when any case is outside ``clean``. ``--quick`` takes a sample of each family
(about ten minutes on a loaded 2-core machine); the full run takes every case, more kills
and 5,000 sessions.
"""

from __future__ import annotations

import argparse
import concurrent.futures as futures
import contextlib
import hashlib
import http.client
import json
import os
import random
import re
import resource
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
PUMP = REPO / "examples" / "vacuum_pump"
STEP = REPO / "tests" / "cad" / "data" / "table_frame_in.step"
CLASSES = ("clean", "traceback", "silent", "hang", "lost")
CLI = [
    sys.executable,
    "-c",
    "import sys; from asmplan.cli import main; sys.exit(main(sys.argv[1:]))",
]
PACKAGES = ("cad", "asp", "arl", "asmplan")
ENV = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")])}
ENV.pop("COLUMNS", None)
ENV["XDG_DATA_HOME"] = tempfile.mkdtemp(prefix="probe-xdg-")  # never the user's own folder


@dataclass
class Run:
    """One child process: its exit code (None: timed out), stdout and stderr."""

    rc: int | None
    out: str
    err: str
    seconds: float


@dataclass
class Result:
    family: str
    name: str
    cls: str
    reason: str = ""


@dataclass
class Probe:
    tmp: Path
    quick: bool
    rng: random.Random
    results: list[Result] = field(default_factory=list)
    lock: threading.Lock = field(default_factory=threading.Lock)
    disk_mode: str = "?"

    def add(self, family: str, name: str, cls: str, reason: str = "") -> None:
        with self.lock:
            self.results.append(Result(family, name, cls, reason))
            mark = (
                "." if cls == "clean" else f"\n  {cls.upper()}: {family}/{name}: {reason[:300]}\n"
            )
            print(mark, end="", flush=True)

    def folder(self, name: str) -> Path:
        path = Path(
            tempfile.mkdtemp(prefix=re.sub(r"[^\w.-]+", "_", name)[:40] + "-", dir=self.tmp)
        )
        return path


def snapshot(tmp: Path) -> Path:
    """The packages copied into ``tmp/code`` with numba's caches beside them (modification
    times kept, so the caches stay valid), and every child run from the copy: a probe tests
    one code version however the checkout changes while it runs. (A commit landing under a
    running probe changed ``asp/concurrent/search.py``; numba then recompiled its kernels
    in the next ``plan``, 88 s of CPU where the pump takes 6, judged a hang; from a cold
    cache the pump's plan takes 137 s of CPU, 193 s of a profiled run's compiling in the
    concurrent search's kernels.) A cold cache is warmed by the reference plan in
    :func:`prepare`."""
    code = tmp / "code"
    for package in PACKAGES:
        shutil.copytree(REPO / package, code / package, ignore=shutil.ignore_patterns("*.pyc"))
    ENV["PYTHONPATH"] = os.pathsep.join([str(code), os.environ.get("PYTHONPATH", "")])
    return code


def run(args: list[str], timeout: float = 120, stdin: str = "", preexec=None, cwd=None) -> Run:
    """Run ``asmplan ARGS`` in a child process; kill its group at the timeout."""
    t0 = time.monotonic()
    proc = subprocess.Popen(
        CLI + [str(a) for a in args],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=ENV,
        cwd=cwd or tempfile.gettempdir(),
        start_new_session=True,
        preexec_fn=preexec,
    )
    try:
        out, err = proc.communicate(stdin, timeout=timeout)
        rc = proc.returncode
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        rc = None
    seconds = time.monotonic() - t0
    with _RUNS_LOCK:
        RUNS.append((seconds, " ".join(Path(str(a)).name or str(a) for a in args)[:160]))
    return Run(rc, out, err, seconds)


RUNS: list[tuple[float, str]] = []
"""Every child run: (wall seconds, its command line), for the slowest-runs list."""
_RUNS_LOCK = threading.Lock()


def traced(r: Run) -> bool:
    return "Traceback (most recent call last)" in r.out + r.err


def judge_refusal(r: Run, out: Path | None = None, names: tuple[str, ...] = ()) -> tuple[str, str]:
    """A bad input: exit 2, one ``asmplan: error:`` line last on stderr, naming one of
    ``names`` when given, nothing left at ``out``."""
    if r.rc is None:
        return "hang", f"no answer in {r.seconds:.0f} s"
    if traced(r):
        return "traceback", _last(r.err or r.out)
    if r.rc == 0:
        return "silent", "accepted (exit 0): " + _last(r.out or r.err)
    lines = r.err.strip().splitlines()
    errors = [line for line in lines if line.startswith("asmplan: error: ")]
    if r.rc != 2 or len(errors) != 1 or lines[-1] != errors[0]:
        return "silent", f"exit {r.rc}, stderr {_last(r.err)!r}"
    if names and not any(n.lower() in errors[0].lower() for n in names):
        return "silent", f"the error names none of {names}: {errors[0]}"
    if out is not None and out.exists():
        return "lost", f"{out} left behind after a refusal"
    return "clean", ""


def judge_ok(r: Run, check: Callable[[], str | None] = lambda: None) -> tuple[str, str]:
    """A valid input: exit 0 and ``check()`` returns None (else the reason it is wrong)."""
    if r.rc is None:
        return "hang", f"no answer in {r.seconds:.0f} s"
    if traced(r):
        return "traceback", _last(r.err or r.out)
    if r.rc != 0:
        return "silent", f"valid input refused (exit {r.rc}): {_last(r.err)}"
    try:
        wrong = check()
    except Exception as exc:  # the output is not what it should be
        wrong = f"{type(exc).__name__}: {exc}"
    return ("silent", wrong) if wrong else ("clean", "")


def _last(text: str) -> str:
    lines = [line for line in text.strip().splitlines() if line.strip()]
    return lines[-1][:300] if lines else "(nothing)"


def train_args(graph: Path, out: Path, cycles: int = 1, *extra: str) -> list:
    """``asmplan train`` of ``graph`` into ``out`` with the fast configuration, quietly."""
    return ["train", graph, "-o", out, "--max-cycles", str(cycles), "--no-progress"] + [
        "--config",
        "fast",
        *extra,
    ]


def pump_copy(probe: Probe, name: str, text: str | None = None) -> Path:
    """A copy of the vacuum pump's folder (meshes linked), with ``text`` as its spec."""
    folder = probe.folder(name)
    (folder / "meshes").symlink_to(PUMP / "meshes")
    (folder / "assembly.yaml").write_text(
        text if text is not None else (PUMP / "assembly.yaml").read_text()
    )
    return folder


def manifest_check(folder: Path) -> str | None:
    """None if ``folder`` holds a whole run: a manifest whose files all exist, plan.json
    that parses; else what is wrong."""
    manifest = folder / "manifest.json"
    if not manifest.exists():
        return "no manifest.json"
    names = json.loads(manifest.read_text())["files"]
    missing = [n for n in names if not (folder / n).exists()]
    if missing:
        return f"manifest names files that are gone: {missing}"
    if "plan.json" in names:
        json.loads((folder / "plan.json").read_text())
    return None


# --------------------------------------------------------------------------------------
# commands: every command on valid input


def family_commands(probe: Probe, shared: dict) -> list[Callable[[], None]]:
    tmp = probe.folder("commands")
    graph = tmp / "g.json"
    cases = []

    def case(name, args, check=lambda r: None, timeout=300, stdin=""):
        def go():
            r = run(args, timeout=timeout, stdin=stdin)
            cls, why = judge_ok(r, lambda: check(r))
            probe.add("commands", name, cls, why)

        cases.append(go)

    def synth_then_more():
        r = run(["synth", "--layers", "4", "--max-nodes", "3", "--seed", "3", "-o", graph])
        cls, why = judge_ok(r, lambda: None if json.loads(graph.read_text())["nodes"] else "empty")
        probe.add("commands", "synth", cls, why)

    synth_then_more()
    case("solve", ["solve", graph, "--format", "json"])
    case("baseline dag", ["baseline", graph, "--time-limit", "5"])
    case(
        "graph",
        ["graph", PUMP, "-o", tmp / "pump_dag.json"],
        lambda r: None if (tmp / "pump_dag.json").exists() else "no DAG written",
    )
    case(
        "relations json",
        ["relations", PUMP, "--format", "json"],
        lambda r: None if isinstance(json.loads(r.out), (dict, list)) else "not a JSON document",
    )
    case("play", ["play", graph, "--moves", "1,1,1,1,1,1,1,1,1,1"], stdin="")
    case(
        "init stl folder",
        ["init", PUMP / "meshes", "-o", tmp / "init" / "assembly.yaml"],
        lambda r: None if "parts:" in (tmp / "init" / "assembly.yaml").read_text() else "no parts",
    )
    case(
        "report",
        ["report", shared["plan_dir"], "-o", tmp / "report.html"],
        lambda r: None if (tmp / "report.html").stat().st_size > 1000 else "empty page",
    )
    run_dir = tmp / "run"
    case(
        "train",
        train_args(graph, run_dir),
        lambda r: None if any(run_dir.iterdir()) else "empty run folder",
        timeout=600,
    )
    if not probe.quick:
        case(
            "experiment table3",
            [
                "experiment",
                "table3",
                "-o",
                tmp / "t3",
                "--solver",
                "exact",
                "--trials",
                "1",
                "--no-progress",
            ],
            timeout=900,
        )
    return cases


# --------------------------------------------------------------------------------------
# spec: the assembly spec with every key wrong


SPEC_TEXT_CASES: list[tuple[str, str, str, tuple[str, ...]]] = [
    # (name, replace this, with this, words the error must hold (any))
    (
        "duplicate top key",
        "name: vacuum pump\n",
        "name: vacuum pump\nname: other pump\n",
        ("name", "duplicate"),
    ),
    (
        "duplicate op key",
        '- {id: "1.1", description: Confirm start of R2 movement, agents: {H: 2}}',
        '- {id: "1.1", description: Confirm start of R2 movement, agents: {H: 2}, agents: {H: 3}}',
        ("agents", "duplicate"),
    ),
    ("octal time 010", "agents: {H: 2}}", "agents: {H: 010}}", ("010", "1.1", "H")),
    ("sexagesimal 1:30", "agents: {H: 2}}", "agents: {H: 1:30}}", ("1:30", "1.1", "H")),
    ("bool time", "agents: {H: 2}}", "agents: {H: true}}", ("true", "1.1", "H")),
    ("null time", "agents: {H: 2}}", "agents: {H: null}}", ("null", "none", "1.1", "H")),
    ("negative time", "agents: {H: 2}}", "agents: {H: -2}}", ("-2", "1.1", "H")),
    ("nan time", "agents: {H: 2}}", "agents: {H: .nan}}", ("nan", "1.1", "H")),
    ("inf time", "agents: {H: 2}}", "agents: {H: .inf}}", ("inf", "1.1", "H")),
    ("hex time", "agents: {H: 2}}", "agents: {H: 0x10}}", ("0x10", "1.1", "H")),
    ("1e400 time", "agents: {H: 2}}", "agents: {H: 1e400}}", ("1e400", "inf", "1.1", "H")),
    ("text time", "agents: {H: 2}}", "agents: {H: two}}", ("two", "1.1", "H")),
    ("list time", "agents: {H: 2}}", "agents: {H: [2]}}", ("1.1", "H")),
    ("unknown agent", "agents: {H: 2}}", "agents: {H9: 2}}", ("H9",)),
    (
        "part beside parts",
        "    part: [PC, VT1]\n",
        "    part: [PC, VT1]\n    parts: [BC]\n",
        ("part",),
    ),
    ("unknown part", "    part: [PC, VT1]\n", "    part: [PC, NOPE]\n", ("NOPE",)),
    ("duplicate op id", 'id: "1.2"', 'id: "1.1"', ("1.1",)),
    ("after unknown op", 'after: ["1.1"]', 'after: ["9.9"]', ("9.9",)),
    (
        "quantity 1.5",
        "quantity: 1, type: component}",
        "quantity: 1.5, type: component}",
        ("quantity", "1.5"),
    ),
    (
        "quantity -1",
        "quantity: 1, type: component}",
        "quantity: -1, type: component}",
        ("quantity", "-1"),
    ),
    (
        "quantity true",
        "quantity: 1, type: component}",
        "quantity: true, type: component}",
        ("quantity", "true"),
    ),
    ("missing mesh", "file: meshes/PC.stl", "file: meshes/NOPE.stl", ("NOPE",)),
    ("units furlongs", "units: mm", "units: furlongs", ("furlongs",)),
    ("gravity sideways", "gravity: -z", "gravity: sideways", ("sideways", "gravity")),
    ("base part unknown", "base_part: BD ", "base_part: NOPE ", ("NOPE",)),
    ("cost money", "cost: time ", "cost: money ", ("money", "cost")),
    ("turn model chess", "turn_model: alternate", "turn_model: chess", ("chess", "turn_model")),
    (
        "tool initial list",
        "R1.bit: {initial: hex, change_time: 0}",
        "R1.bit: {initial: [hex], change_time: 0}",
        ("R1.bit", "initial"),
    ),
    (
        "tool change time text",
        "R1.bit: {initial: hex, change_time: 0}",
        "R1.bit: {initial: hex, change_time: soon}",
        ("change_time", "soon"),
    ),
    ("requires unknown tool", "requires: {R1.bit: hex}", "requires: {R9.bit: hex}", ("R9.bit",)),
    ("tab indent", "parts:\n  - {id: BD", "parts:\n\t- {id: BD", ("assembly.yaml",)),
    ("not yaml", "name: vacuum pump\n", "name: [vacuum pump\n", ("assembly.yaml",)),
]


def _spec_key_cases(spec: dict) -> list[tuple[str, dict, tuple[str, ...]]]:
    """Every key of the spec given a value of a wrong type (top level, a part, an
    operation, an agent)."""
    import copy

    out = []

    def wrong_values(value):
        if isinstance(value, (dict, list)):
            return [12345, "some text"]
        if isinstance(value, str):
            return [[1, 2], {"a": 1}]
        if isinstance(value, bool):
            return ["maybe", [True]]
        if isinstance(value, (int, float)):
            return ["many", {"n": 1}]
        return [{"x": 1}]

    for key, value in spec.items():
        for bad in wrong_values(value):
            s = copy.deepcopy(spec)
            s[key] = bad
            out.append((f"top {key}={type(bad).__name__}", s, (key,)))
    for where, holder in (("part", spec["parts"][1]), ("operation", spec["operations"][2])):
        index = spec["parts"].index(holder) if where == "part" else spec["operations"].index(holder)
        for key, value in holder.items():
            for bad in wrong_values(value):
                s = copy.deepcopy(spec)
                (s["parts"] if where == "part" else s["operations"])[index][key] = bad
                out.append((f"{where} {key}={type(bad).__name__}", s, (key,)))
    for key, value in spec["agents"]["R1"].items():
        for bad in wrong_values(value):
            s = copy.deepcopy(spec)
            s["agents"]["R1"][key] = bad
            out.append((f"agent {key}={type(bad).__name__}", s, (key, "R1")))
    return out


def family_spec(probe: Probe, shared: dict) -> list[Callable[[], None]]:
    import yaml

    text = (PUMP / "assembly.yaml").read_text()
    spec = yaml.safe_load(text)
    cases: list[tuple[str, str, tuple[str, ...]]] = []
    for name, old, new, words in SPEC_TEXT_CASES:
        assert old in text, name
        cases.append((name, text.replace(old, new, 1), words))
    for name, bad, words in _spec_key_cases(spec):
        cases.append((name, yaml.safe_dump(bad, sort_keys=False), words))
    cases.append(
        (
            "huge name 1 MB",
            text.replace("name: vacuum pump", "name: " + "x" * 1_000_000, 1),
            ("name",),
        )
    )
    cases.append(
        (
            "huge description",
            text.replace("description: operator", "description: " + "y" * 200_000, 1),
            ("description",),
        )
    )
    cases.append(
        ("deep nesting", text + "extra: " + "[" * 5000 + "]" * 5000 + "\n", ("assembly.yaml",))
    )
    if probe.quick:
        n = len(SPEC_TEXT_CASES)
        cases = [
            c for i, c in enumerate(cases) if (i < n and i % 2 == 0) or (i >= n and i % 5 == 0)
        ]
    commands = ("plan", "graph", "baseline", "play")
    jobs = []
    for i, (name, bad_text, words) in enumerate(cases):
        command = "plan" if probe.quick else commands[i % len(commands)]

        def go(name=name, bad_text=bad_text, words=words, command=command, i=i):
            folder = pump_copy(probe, f"spec{i}", bad_text)
            out = folder / "out"
            args = {
                "plan": ["plan", folder, "-o", out, "--time-limit", "5"],
                "graph": ["graph", folder, "-o", out / "g.json"],
                "baseline": ["baseline", folder, "--time-limit", "5"],
                "play": ["play", folder, "--moves", "1"],
            }[command]
            cls, why = judge_refusal(run(args, timeout=180), out, words)
            probe.add("spec", f"{command}: {name}", cls, why)

        jobs.append(go)
    return jobs


# --------------------------------------------------------------------------------------
# dag: bad game-DAG files


def family_dag(probe: Probe, shared: dict) -> list[Callable[[], None]]:
    base = json.loads(shared["graph"].read_text())

    def edit(fn):
        d = json.loads(json.dumps(base))
        fn(d)
        return json.dumps(d)

    def setitem(path, value):
        def fn(d):
            obj = d
            for k in path[:-1]:
                obj = obj[k]
            obj[path[-1]] = value

        return fn

    cases = [
        ("float node id", edit(setitem(["nodes", 1, "id"], 1.5)), ("1.5", "id")),
        ("bool node id", edit(setitem(["nodes", 1, "id"], True)), ("true", "id")),
        ("null node id", edit(setitem(["nodes", 1, "id"], None)), ("null", "none", "id")),
        (
            "duplicate node",
            edit(lambda d: d["nodes"].append(dict(d["nodes"][1]))),
            ("1", "duplicate"),
        ),
        ("edge to unknown node", edit(setitem(["edges", 0, "target"], 999)), ("999",)),
        ("cost text", edit(setitem(["edges", 0, "cost"], "x")), ("cost",)),
        ("cost negative", edit(setitem(["edges", 0, "cost"], -1)), ("cost", "-1")),
        ("cost nan", edit(setitem(["edges", 0, "cost"], float("nan"))), ("cost", "nan")),
        ("cost 1e400", edit(setitem(["edges", 0, "cost"], 1e400)), ("cost", "inf")),
        ("side unknown", edit(setitem(["edges", 0, "side"], "alien")), ("alien", "side")),
        (
            "cycle",
            edit(
                lambda d: d["edges"].append(
                    {"source": d["end"], "target": d["start"], "cost": 1, "side": "any"}
                )
            ),
            ("cycle",),
        ),
        ("other format", edit(setitem(["format"], "other/9")), ("format", "other")),
        ("unknown start", edit(setitem(["start"], 999)), ("999", "start")),
        (
            "duplicate key",
            json.dumps(base).replace('"start": ', '"start": 1, "start": ', 1),
            ("start", "duplicate"),
        ),
        ("truncated", json.dumps(base)[: len(json.dumps(base)) // 2], ("json",)),
        ("huge label", edit(setitem(["nodes", 1, "label"], "z" * 2_000_000)), ("label",)),
    ]
    commands = ("solve", "baseline", "play", "evaluate", "train")
    jobs = []
    for i, (name, content, words) in enumerate(cases):
        for j, command in enumerate(commands):
            # quick: one command a case in turn (training, the slowest, on the first only)
            if (
                probe.quick
                and j != (i % (len(commands) - 1))
                and not (i == 0 and command == "train")
            ):
                continue

            def go(name=name, content=content, words=words, command=command, i=i, j=j):
                folder = probe.folder(f"dag{i}{j}")
                path = folder / "g.json"
                path.write_text(content)
                out = folder / "out"
                args = {
                    "solve": ["solve", path],
                    "baseline": ["baseline", path, "--time-limit", "5"],
                    "play": ["play", path, "--moves", "1"],
                    "evaluate": ["evaluate", path, "--model", shared["train_run"]],
                    "train": ["train", path, "-o", out, "--max-cycles", "1", "--no-progress"],
                }[command]
                cls, why = judge_refusal(run(args, timeout=180), out, words)
                probe.add("dag", f"{command}: {name}", cls, why)

            jobs.append(go)
    return jobs


# --------------------------------------------------------------------------------------
# cad: bad CAD files


def _stl_ascii(triangles) -> str:
    lines = ["solid p"]
    for tri in triangles:
        lines += ["facet normal 0 0 0", "outer loop"]
        lines += [f"vertex {x} {y} {z}" for x, y, z in tri]
        lines += ["endloop", "endfacet"]
    return "\n".join(lines + ["endsolid p", ""])


def family_cad(probe: Probe, shared: dict) -> list[Callable[[], None]]:
    step = STEP.read_bytes()
    data_at = step.index(b"DATA;")
    mid = re.search(rb"\n#\d+\s*=\s*CLOSED_SHELL", step).start()  # the first solid's shell
    mid_end = step.index(b"\n", mid + 1)
    bc = (PUMP / "meshes" / "BC.stl").read_bytes()
    tet = [
        ((0, 0, 0), (1, 0, 0), (0, 1, 0)),
        ((0, 0, 0), (0, 1, 0), (0, 0, 1)),
        ((0, 0, 0), (0, 0, 1), (1, 0, 0)),
        ((1, 0, 0), (0, 0, 1), (0, 1, 0)),
    ]
    files = [
        ("step truncated", ".step", step[: len(step) // 2], ("table", "truncated")),
        ("step garbage", ".step", bytes(random.Random(1).randbytes(4000)), ("not a step",)),
        ("step header only", ".step", step[:data_at], ("DATA", "header")),
        (
            "step empty data",
            ".step",
            step[: data_at + 5] + b"\nENDSEC;\nEND-ISO-10303-21;\n",
            ("empty", "entities"),
        ),
        ("step damaged entity", ".step", step[:mid] + step[mid_end:], ("damaged", "#")),
        ("step nul bytes", ".step", b"\x00" * 5000, ("not a step",)),
        ("stl empty", ".stl", b"", ("empty", "no triangles", "faces", "mesh")),
        (
            "stl nan vertex",
            ".stl",
            _stl_ascii([((0, 0, 0), (1, 0, 0), (float("nan"), 1, 0))] + tet).encode(),
            ("nan", "finite"),
        ),
        (
            "stl inf vertex",
            ".stl",
            _stl_ascii(tet[:3] + [((1e400, 0, 0), (0, 0, 1), (0, 1, 0))]).encode(),
            ("inf", "finite"),
        ),
        (
            "stl degenerate",
            ".stl",
            _stl_ascii([((0, 0, 0), (0, 0, 0), (0, 0, 0))] * 4).encode(),
            ("degenerate", "zero", "area", "volume", "empty", "faces"),
        ),
        ("stl truncated binary", ".stl", bc[: len(bc) // 2 + 7], ("stl",)),
        ("obj empty", ".obj", b"# nothing\n", ("empty", "no", "faces", "mesh")),
        ("ply garbage", ".ply", b"ply\nformat nonsense\n" + bytes(range(256)), ("ply",)),
        ("glb garbage", ".glb", b"glTF" + bytes(200), ("glb", "gltf")),
    ]
    jobs = []
    for i, (name, suffix, content, words) in enumerate(files):
        for command in ("relations", "init", "plan"):
            # quick: STEP by init and plan, meshes by relations, a mesh by plan
            quick_skip = (command == "relations") == name.startswith("step")
            if probe.quick and quick_skip and (command, name) != ("plan", "stl nan vertex"):
                continue

            def go(name=name, suffix=suffix, content=content, words=words, command=command, i=i):
                folder = probe.folder(f"cad{i}{command}")
                path = folder / f"part{suffix}"
                path.write_bytes(content)
                out = folder / "out"
                args = {
                    "relations": ["relations", path, "--format", "json"],
                    "init": ["init", path, "-o", out / "assembly.yaml"],
                    "plan": ["plan", path, "-o", out, "--time-limit", "5"],
                }[command]
                r = run(args, timeout=240)
                cls, why = judge_refusal(r, out, words + (path.name,))
                if cls == "silent" and r.rc == 0 and name == "step damaged entity":
                    cls, why = _whole_step(r, command)
                if command == "relations" and r.rc == 0 and cls == "silent":
                    with contextlib.suppress(ValueError):
                        json.loads(r.out)
                        why += " (stdout is JSON)"
                probe.add("cad", f"{command}: {name}", cls, why)

            jobs.append(go)
    # a spec whose part is degenerate, empty or NaN: plan must name the part's file
    for name, content in (
        ("PC empty", b""),
        ("PC nan", _stl_ascii([((0, 0, 0), (1, 0, 0), (float("nan"), 1, 0))] + tet).encode()),
        ("PC one point", _stl_ascii([((5, 5, 5),) * 3] * 3).encode()),
    ):

        def go(name=name, content=content):
            folder = probe.folder("specmesh")
            shutil.copytree(PUMP / "meshes", folder / "meshes")
            (folder / "meshes" / "PC.stl").write_bytes(content)
            shutil.copy(PUMP / "assembly.yaml", folder / "assembly.yaml")
            out = folder / "out"
            r = run(["plan", folder, "-o", out, "--time-limit", "5"], timeout=240)
            probe.add("cad", f"plan spec: {name}", *judge_refusal(r, out, ("PC",)))

        jobs.append(go)
    return jobs


def _whole_step(r: Run, command: str) -> tuple[str, str]:
    """A damaged STEP read with exit 0: clean only if every solid came through."""
    if command == "relations":
        try:
            doc = json.loads(r.out)
        except ValueError:
            return "silent", "relations --format json: stdout is not JSON"
        parts = doc.get("parts", doc) if isinstance(doc, dict) else doc
        return ("clean", "") if len(parts) >= 2 else ("silent", f"{len(parts)} part(s) read")
    solids = len(re.findall(rb"MANIFOLD_SOLID_BREP\(", STEP.read_bytes()))
    if f"{solids} parts" in r.out:
        return "clean", ""
    return "silent", "a damaged STEP accepted: " + _last(r.out)


# --------------------------------------------------------------------------------------
# output: folder safety


def family_output(probe: Probe, shared: dict) -> list[Callable[[], None]]:
    jobs = []

    def foreign(force: bool):
        def go():
            d = probe.folder("foreign")
            (d / "thesis.tex").write_text("keep\n")
            (d / "manifest.json").write_text('{"format": "other/1", "files": ["thesis.tex"]}')
            r = run(
                ["plan", PUMP, "-o", d, "--time-limit", "5"] + (["--force"] if force else []),
                timeout=300,
            )
            kept = (d / "thesis.tex").exists() and (d / "thesis.tex").read_text() == "keep\n"
            if not kept:
                probe.add("output", f"foreign manifest force={force}", "lost", "thesis.tex deleted")
                return
            # refused even with --force: writing asmplan's manifest would overwrite theirs
            cls, why = judge_refusal(r, None, ("manifest.json",))
            if cls == "clean" and (d / "plan.json").exists():
                cls, why = "lost", "refused but plan.json written"
            probe.add("output", f"foreign manifest{' --force' if force else ''}", cls, why)

        return go

    jobs += [foreign(False), foreign(True)]

    def stray_pngs():
        d = probe.folder("stray")
        shutil.copytree(shared["plan_dir"], d, dirs_exist_ok=True)
        for name in ("robustness.png", "gantt_mine.png", "notes.txt"):
            (d / name).write_text("mine\n")
        r = run(["plan", PUMP, "-o", d, "--time-limit", "5"], timeout=300)
        gone = [
            n for n in ("robustness.png", "gantt_mine.png", "notes.txt") if not (d / n).exists()
        ]
        if gone:
            probe.add("output", "files of others beside a run", "lost", f"deleted {gone}")
        elif r.rc == 0:
            probe.add(
                "output", "files of others beside a run", *judge_ok(r, lambda: manifest_check(d))
            )
        else:
            probe.add("output", "files of others beside a run", *judge_refusal(r))

    jobs.append(stray_pngs)

    def train_again(resume: bool):
        def go():
            d = probe.folder("trainagain")
            shutil.copytree(shared["train_run"], d / "run")
            before = _tree_hash(d / "run")
            r = run(
                train_args(shared["graph"], d / "run", 1, *(["--resume"] if resume else [])),
                timeout=600,
            )
            if resume:
                probe.add("output", "train --resume", *judge_ok(r))
                return
            if r.rc == 0 or _tree_hash(d / "run") != before:
                probe.add(
                    "output", "train again without --resume", "lost", "the run folder was replaced"
                )
            else:
                probe.add("output", "train again without --resume", *judge_refusal(r))

        return go

    jobs += [train_again(False)] + ([] if probe.quick else [train_again(True)])

    def graph_over_file():
        d = probe.folder("graphover")
        (d / "g.json").write_text("precious\n")
        r = run(["graph", PUMP, "-o", d / "g.json"], timeout=300)
        if (d / "g.json").read_text() == "precious\n":
            probe.add("output", "graph -o over a foreign file", *judge_refusal(r))
        elif r.rc == 0:
            probe.add(
                "output", "graph -o over a foreign file", "clean", ""
            )  # a single named file: replaced
        else:
            probe.add(
                "output", "graph -o over a foreign file", "lost", "file changed though refused"
            )

    jobs.append(graph_over_file)

    def init_over_spec():
        d = probe.folder("initover")
        (d / "assembly.yaml").write_text("mine: 1\n")
        r = run(["init", PUMP / "meshes", "-o", d / "assembly.yaml"], timeout=300)
        if (d / "assembly.yaml").read_text() != "mine: 1\n":
            probe.add(
                "output", "init over a spec without --force", "lost", "the spec was overwritten"
            )
        else:
            probe.add("output", "init over a spec without --force", *judge_refusal(r))

    jobs.append(init_over_spec)

    def output_is_file():
        d = probe.folder("outfile")
        (d / "out").write_text("a file\n")
        r = run(["plan", PUMP, "-o", d / "out", "--time-limit", "5"], timeout=300)
        if (d / "out").read_text() != "a file\n":
            probe.add("output", "plan -o an existing file", "lost", "the file was replaced")
        else:
            probe.add("output", "plan -o an existing file", *judge_refusal(r))

    jobs.append(output_is_file)
    return jobs


def _tree_hash(folder: Path) -> str:
    h = hashlib.sha256()
    for p in sorted(folder.rglob("*")):
        if p.is_file():
            h.update(str(p.relative_to(folder)).encode() + p.read_bytes())
    return h.hexdigest()


# --------------------------------------------------------------------------------------
# kill: SIGKILL at random delays during writes, then a rerun


def _kill_at(args: list[str], delay: float) -> bool:
    """Run ``asmplan ARGS`` and SIGKILL it after ``delay`` seconds; True if it was killed."""
    proc = subprocess.Popen(
        CLI + [str(a) for a in args],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        stdin=subprocess.DEVNULL,
        env=ENV,
        start_new_session=True,
    )
    try:
        proc.wait(timeout=delay)
        return False
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        return True


def family_kill(probe: Probe, shared: dict) -> list[Callable[[], None]]:
    ref = (shared["plan_dir"] / "plan.json").read_bytes()
    span = shared["plan_seconds"]
    n = 3 if probe.quick else 16
    jobs = []
    for k in range(n):
        # the last fifth of the run holds the writes: half the kills land there
        delay = (
            probe.rng.uniform(0.8 * span, 1.05 * span) if k % 2 else probe.rng.uniform(0.3, span)
        )

        def go(k=k, delay=delay):
            d = probe.folder(f"kill{k}")
            shutil.copytree(shared["plan_dir"], d, dirs_exist_ok=True)  # a previous run in place
            killed = _kill_at(["plan", PUMP, "-o", d, "--time-limit", "5"], delay)
            name = f"plan killed at {delay:.1f} s" + ("" if killed else " (finished first)")
            if d.exists() and any(d.iterdir()):
                wrong = manifest_check(d)
                if wrong:
                    probe.add("kill", name, "lost", f"after the kill: {wrong}")
                    return
            r = run(["plan", PUMP, "-o", d, "--time-limit", "5"], timeout=300)
            cls, why = judge_ok(r, lambda: manifest_check(d))
            if cls == "clean" and (d / "plan.json").read_bytes() != ref:
                cls, why = "silent", "rerun's plan.json differs from the reference"
            if cls == "clean":
                leftovers = [p.name for p in d.iterdir() if p.name.endswith(".tmp")]
                if leftovers:
                    cls, why = "lost", f"temporary files left after the rerun: {leftovers}"
            probe.add("kill", name, "lost" if cls == "silent" and "refused" in why else cls, why)

        jobs.append(go)
    for k in range(1 if probe.quick else 6):
        delay = probe.rng.uniform(1.0, 8.0)

        def train_kill(k=k, delay=delay):
            d = probe.folder(f"killtrain{k}")
            killed = _kill_at(
                train_args(shared["graph"], d / "run", 3),
                delay,
            )
            there = (d / "run").exists() and any((d / "run").iterdir())
            r = run(
                train_args(shared["graph"], d / "run", 3, *(["--resume"] if there else [])),
                timeout=600,
            )
            if r.rc == 2 and there:
                # a folder killed before its first checkpoint: the rerun may ask for --force
                r = run(
                    train_args(shared["graph"], d / "run", 3, "--force"),
                    timeout=600,
                )
                cls, why = judge_ok(r)
                if cls != "clean":
                    cls = "lost"
                    why = f"a run folder neither --resume nor --force takes: {why}"
            else:
                cls, why = judge_ok(r)
            probe.add(
                "kill",
                f"train killed at {delay:.1f} s{'' if killed else ' (finished first)'}",
                cls,
                why,
            )

        jobs.append(train_kill)
    return jobs


# --------------------------------------------------------------------------------------
# repeat: same input, same bytes


def family_repeat(probe: Probe, shared: dict) -> list[Callable[[], None]]:
    jobs = []

    def twice(name, make_args, files):
        def go():
            digests = []
            for k in range(2):
                d = probe.folder(f"rep{k}")
                r = run(make_args(d), timeout=300)
                cls, why = judge_ok(r)
                if cls != "clean":
                    probe.add("repeat", name, cls, why)
                    return
                digests.append(
                    [
                        hashlib.sha256(
                            r.out.encode() if f == "-" else (d / f).read_bytes()
                        ).hexdigest()
                        for f in files
                    ]
                )
            same = digests[0] == digests[1]
            probe.add(
                "repeat",
                name,
                "clean" if same else "silent",
                "" if same else "outputs differ between runs",
            )

        return go

    jobs.append(
        twice(
            "plan: plan.json", lambda d: ["plan", PUMP, "-o", d, "--time-limit", "5"], ["plan.json"]
        )
    )
    jobs.append(twice("graph -o", lambda d: ["graph", PUMP, "-o", d / "g.json"], ["g.json"]))
    jobs.append(
        twice("relations --format json", lambda d: ["relations", PUMP, "--format", "json"], ["-"])
    )
    jobs.append(
        twice(
            "synth",
            lambda d: ["synth", "--layers", "5", "--max-nodes", "4", "-o", d / "g.json"],
            ["g.json"],
        )
    )
    jobs.append(
        twice(
            "solve --format json", lambda d: ["solve", shared["graph"], "--format", "json"], ["-"]
        )
    )
    # the reference plan of the shared folder against a fresh one
    return jobs


# --------------------------------------------------------------------------------------
# service: over real HTTP on 127.0.0.1


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Service:
    """``asmplan serve`` in a child process on a free port."""

    def __init__(self, source: Path, sessions: Path, *extra: str) -> None:
        self.port = _free_port()
        self.args = ["serve", source, "--port", str(self.port), "--sessions", sessions, *extra]
        self.proc = subprocess.Popen(
            CLI + [str(a) for a in self.args],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            stdin=subprocess.DEVNULL,
            text=True,
            env=ENV,
            start_new_session=True,
        )
        self.lines: list[str] = []
        threading.Thread(target=self._read, daemon=True).start()
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                time.sleep(0.2)
                raise RuntimeError(
                    f"serve exited {self.proc.returncode}: {' | '.join(self.lines[-3:])}"
                )
            try:
                if self.request("GET", "/api/plans")[0] == 200:
                    return
            except OSError:
                time.sleep(0.3)
        raise TimeoutError("serve did not answer in 120 s")

    def _read(self) -> None:
        for line in self.proc.stderr:
            self.lines.append(line.rstrip())

    def request(self, method: str, path: str, body=None, raw: bytes | None = None, timeout=30):
        conn = http.client.HTTPConnection("127.0.0.1", self.port, timeout=timeout)
        try:
            data = raw if raw is not None else (None if body is None else json.dumps(body).encode())
            conn.request(method, path, body=data, headers={"Content-Type": "application/json"})
            resp = conn.getresponse()
            text = resp.read()
            try:
                return resp.status, json.loads(text)
            except ValueError:
                return resp.status, text
        finally:
            conn.close()

    def kill(self) -> None:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(self.proc.pid, signal.SIGKILL)
        self.proc.wait()

    def stop(self) -> None:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(self.proc.pid, signal.SIGTERM)
        try:
            self.proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            self.kill()

    def traced(self) -> bool:
        return any("Traceback" in line for line in self.lines)


def _game(plan: dict, seed: int) -> list[dict]:
    from asmplan.advisor import Advisor

    rng = random.Random(seed)
    advisor, events = Advisor(plan), []
    advice = advisor.advice()
    while not advice.finished:
        m = advice.robots[0] if advice.turn == "robot" else rng.choice(advice.options)
        ev = {"kind": "finished", "operation": m["operation"], "agent": m["agent"]}
        advice = advisor.observe(ev)
        events.append(ev)
    return events


def _raw(port: int, data: bytes, timeout: float = 30) -> int:
    """Send raw bytes, return the answer's status (0: the connection closed first)."""
    with socket.create_connection(("127.0.0.1", port), timeout=timeout) as s:
        with contextlib.suppress(BrokenPipeError, ConnectionResetError):
            s.sendall(data)
        try:
            head = s.recv(64)
        except (ConnectionResetError, TimeoutError):
            return 0
        return int(head.split()[1]) if head.startswith(b"HTTP/") else 0


def family_service(probe: Probe, shared: dict) -> list[Callable[[], None]]:
    return [lambda: _service(probe, shared)]


def _service(probe: Probe, shared: dict) -> None:
    F = "service"
    plan_dir = shared["plan_dir"]
    plan = json.loads((plan_dir / "plan.json").read_text())
    from asmplan.serve.app import plan_id

    pid = plan_id(plan)
    sessions = probe.folder("sessions")
    cap = 200 if probe.quick else 5000
    try:
        svc = Service(plan_dir, sessions, "--max-sessions", str(cap))
    except (RuntimeError, TimeoutError) as exc:
        probe.add(F, "start", "traceback" if "Traceback" in str(exc) else "silent", str(exc))
        return
    acked: dict[str, list[dict]] = {}
    try:
        game = _game(plan, 0)
        # bad requests: each refused with 4xx and a reason, nothing changed
        st, body = svc.request("POST", "/api/sessions", {"plan": pid, "event": game[0]})
        sid = body["id"] if st == 201 else None
        probe.add(F, "create a session", "clean" if st == 201 else "silent", f"{st} {body}")
        if sid:
            acked[sid] = [game[0]]
        bad = [
            ("POST", "/api/sessions", b"{not json"),
            ("POST", "/api/sessions", json.dumps({"plan": pid, "colour": "red"}).encode()),
            ("POST", "/api/sessions", json.dumps({"plan": 5}).encode()),
            ("POST", "/api/sessions", json.dumps({"plan": "x" * 100}).encode()),
            ("POST", "/api/sessions", json.dumps({"plan": "no-such-plan"}).encode()),
            ("POST", "/api/sessions", json.dumps([1, 2]).encode()),
            ("POST", f"/api/sessions/{sid}/events", json.dumps({"kind": "finished"}).encode()),
            (
                "POST",
                f"/api/sessions/{sid}/events",
                json.dumps({"kind": "exploded", "operation": "1.1", "agent": "H"}).encode(),
            ),
            (
                "POST",
                f"/api/sessions/{sid}/events",
                json.dumps({**game[0], "time": float("nan")}).encode(),
            ),
            ("POST", f"/api/sessions/{sid}/events", json.dumps({**game[0], "time": -1}).encode()),
            (
                "POST",
                f"/api/sessions/{sid}/events",
                json.dumps({"kind": "finished", "operation": "9.9", "agent": "H"}).encode(),
            ),
            ("POST", f"/api/sessions/{sid}/events", json.dumps(game[0]).encode()),  # already done
            ("POST", "/api/sessions/ffff/events", json.dumps(game[1]).encode()),
            (
                "POST",
                f"/api/sessions/{sid}/answers",
                json.dumps({"answers": {"q": {"deep": 1}}}).encode(),
            ),
            ("GET", "/api/sessions/../../etc/passwd", None),
            ("GET", "/api/plans/no-such-plan", None),
            ("DELETE", f"/api/sessions/{sid}", None),
        ]
        for method, path, raw in bad:
            before = svc.request("GET", f"/api/sessions/{sid}")[1]
            st, body = svc.request(method, path, raw=raw)
            after = svc.request("GET", f"/api/sessions/{sid}")[1]
            name = f"bad request {method} {path[-30:]} {(raw or b'')[:40]!r}"
            if st >= 500:
                probe.add(F, name, "traceback" if svc.traced() else "silent", f"{st} {body}")
            elif st < 400:
                probe.add(F, name, "silent", f"accepted: {st} {str(body)[:120]}")
            elif before != after:
                probe.add(F, name, "lost", "refused but the session changed")
            else:
                probe.add(F, name, "clean")
        for name, data, want in (
            (
                "10 MB body",
                (
                    f"POST /api/sessions HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                    f"Content-Length: {10 << 20}\r\n\r\n"
                ).encode()
                + b" " * (1 << 20),
                413,
            ),
            (
                "chunked 10 MB body",
                b"POST /api/sessions HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                b"Transfer-Encoding: chunked\r\n\r\n"
                + (b"100000\r\n" + b" " * (1 << 20) + b"\r\n") * 10
                + b"0\r\n\r\n",
                413,
            ),
            ("garbage request line", b"\x00\x01\x02 nonsense\r\n\r\n", 400),
        ):
            st = _raw(svc.port, data)
            probe.add(
                F, name, "clean" if st == want else "silent", f"answered {st}, expected {want}"
            )
        # the rest of the game, each event acknowledged
        for ev in game[1:]:
            st, body = svc.request("POST", f"/api/sessions/{sid}/events", ev)
            if st != 200:
                probe.add(F, "play a whole game", "silent", f"{st} {body}")
                break
            acked[sid].append(ev)
        else:
            probe.add(F, "play a whole game", "clean")
        # sessions up to the cap, then 429
        made, refused = 0, None  # the first session finished its game: no longer open
        started = time.monotonic()
        while made < cap:
            st, body = svc.request("POST", "/api/sessions", {"plan": pid, "event": game[0]})
            if st != 201:
                refused = (st, body)
                break
            acked[body["id"]] = [game[0]]
            made += 1
        st, body = svc.request("POST", "/api/sessions", {"plan": pid, "event": game[0]})
        ok = refused is None and st == 429
        probe.add(
            F,
            f"{cap} sessions, then one more",
            "clean" if ok else "silent",
            f"made {made} in {time.monotonic() - started:.0f} s; the next: {st} "
            f"{str(body)[:100]}; {refused}",
        )
        # races: two clients post the same next event on one session at once
        ids = list(acked)[1 : (21 if probe.quick else 201)]
        race_ok, race_bad = 0, []
        for s in ids:
            ev = game[len(acked[s])]
            answers = []
            barrier = threading.Barrier(2)

            def client(s=s, ev=ev, barrier=barrier, answers=answers):
                barrier.wait()
                answers.append(svc.request("POST", f"/api/sessions/{s}/events", ev)[0])

            ts = [threading.Thread(target=client) for _ in range(2)]
            [t.start() for t in ts]
            [t.join() for t in ts]
            n_events = svc.request("GET", f"/api/sessions/{s}")[1]["events"]
            n_events = len(n_events) if isinstance(n_events, list) else n_events
            if sorted(answers) == [200, 409] and n_events == len(acked[s]) + 1:
                race_ok += 1
                acked[s].append(ev)
            else:
                race_bad.append((s, answers, n_events))
        probe.add(
            F,
            f"{len(ids)} races of two clients",
            "clean" if not race_bad else "silent",
            str(race_bad[:3]),
        )
        # SIGKILL while events stream, restart, compare with the acknowledged
        stream = list(acked)[1 : (60 if probe.quick else 600)]
        stop_at = time.monotonic() + probe.rng.uniform(1.0, 3.0)
        killer = threading.Timer(stop_at - time.monotonic(), svc.kill)
        killer.start()
        sent = 0
        for s in stream * 30:
            if len(acked[s]) >= len(game):
                continue
            ev = game[len(acked[s])]
            try:
                st, _ = svc.request("POST", f"/api/sessions/{s}/events", ev, timeout=5)
            except OSError:
                break
            if st == 200:
                acked[s].append(ev)
                sent += 1
        killer.join()
        svc.kill()
        svc2 = Service(plan_dir, sessions, "--max-sessions", str(cap))
        svc = svc2
        lost = []
        for s, evs in acked.items():
            st, body = svc.request("GET", f"/api/sessions/{s}")
            have = body.get("events") if st == 200 else None
            have = have if isinstance(have, list) else []
            got = [{k: e[k] for k in ("kind", "operation", "agent")} for e in have]
            want = [{k: e[k] for k in ("kind", "operation", "agent")} for e in evs]
            if got[: len(want)] != want:
                lost.append((s, len(want), len(got)))
        probe.add(
            F,
            f"SIGKILL after {sent} streamed events, restart",
            "clean" if not lost else "lost",
            f"{len(lost)} sessions lost events: {lost[:3]}",
        )
        svc.stop()
        # a re-planned folder: the old sessions no longer fit; serve starts, names them
        replanned = probe.folder("replanned")
        shutil.copytree(plan_dir, replanned, dirs_exist_ok=True)
        folder = pump_copy(
            probe, "replan", (PUMP / "assembly.yaml").read_text().replace('"1.1"', '"1.0"')
        )
        r = run(["plan", folder, "-o", replanned, "--time-limit", "5"], timeout=300)
        if r.rc != 0:
            probe.add(F, "restart after a re-plan", "silent", f"the re-plan failed: {_last(r.err)}")
        else:
            try:
                svc = Service(replanned, sessions, "--max-sessions", str(cap))
                st, body = svc.request("GET", "/api/set-aside")
                named = st == 200 and len(body) > 0
                probe.add(
                    F,
                    "restart after a re-plan",
                    "clean" if named else "silent",
                    "" if named else f"set-aside: {st} {str(body)[:200]}",
                )
                svc.stop()
            except (RuntimeError, TimeoutError) as exc:
                probe.add(F, "restart after a re-plan", "silent", f"serve refused to start: {exc}")
        if svc.traced():
            probe.add(
                F, "service stderr", "traceback", next(x for x in svc.lines if "Traceback" in x)
            )
    finally:
        svc.kill()


# --------------------------------------------------------------------------------------
# disk: a full disk


@contextlib.contextmanager
def small_disk(probe: Probe, kb: int):
    """A folder on a tmpfs of ``kb`` KiB, or (no mount) a plain folder with RLIMIT_FSIZE."""
    d = probe.folder(f"disk{kb}")
    if probe.disk_mode != "fsize":
        r = subprocess.run(
            ["mount", "-t", "tmpfs", "-o", f"size={kb}k", "tmpfs", str(d)], capture_output=True
        )
        if r.returncode == 0:
            probe.disk_mode = "tmpfs"
            try:
                yield d, None
            finally:
                subprocess.run(["umount", "-l", str(d)], capture_output=True)
            return
        probe.disk_mode = "fsize"

    def limit(kb=kb):
        resource.setrlimit(resource.RLIMIT_FSIZE, (kb * 1024, kb * 1024))
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)

    yield d, limit


def family_disk(probe: Probe, shared: dict) -> list[Callable[[], None]]:
    jobs = []
    sizes = (64, 600) if probe.quick else (16, 64, 200, 400, 600, 800, 1000)

    for kb in sizes:

        def plan_full(kb=kb):
            with small_disk(probe, kb) as (d, limit):
                out = d / "out"
                r = run(["plan", PUMP, "-o", out, "--time-limit", "5"], timeout=300, preexec=limit)
                if r.rc == 0:
                    probe.add(
                        "disk", f"plan on {kb} KiB", *judge_ok(r, lambda: manifest_check(out))
                    )
                    return
                cls, why = judge_refusal(r, None, ("space", "disk", "too large", "write", "file"))
                if (
                    cls == "clean"
                    and out.exists()
                    and any(p.name != "manifest.json" for p in out.iterdir())
                ):
                    cls, why = "lost", f"half-written: {sorted(p.name for p in out.iterdir())}"
                probe.add("disk", f"plan on {kb} KiB ({probe.disk_mode})", cls, why)

        jobs.append(plan_full)

    def replace_full():  # a previous run in place, the new one does not fit: the old stays
        kb = 1200
        with small_disk(probe, kb) as (d, limit):
            out = d / "out"
            shutil.copytree(shared["plan_dir"], out)
            before = _tree_hash(out)
            filler = d / "filler"
            free = shutil.disk_usage(d).free if limit is None else 0
            if limit is None and free > 50_000:
                filler.write_bytes(b"\0" * (free - 50_000))
            r = run(["plan", PUMP, "-o", out, "--time-limit", "5"], timeout=300, preexec=limit)
            if r.rc == 0:
                probe.add(
                    "disk", "plan over a run, disk full", *judge_ok(r, lambda: manifest_check(out))
                )
                return
            # the documented contract (asp.atomic.OutputSet): a failed run leaves the old
            # run whole or no run at all (the old files go first), never a part of one
            cls, why = judge_refusal(r, None, (str(out),))
            left = sorted(p.name for p in out.iterdir()) if out.exists() else []
            if left and (manifest_check(out) or _tree_hash(out) != before):
                cls, why = "lost", f"a part of a run left: {left}"
            elif cls == "clean":
                filler.unlink(missing_ok=True)  # room again: the rerun must take the folder
                rerun = run(["plan", PUMP, "-o", out, "--time-limit", "5"], timeout=300)
                wrong = judge_ok(rerun, lambda: manifest_check(out))
                if wrong[0] != "clean":
                    cls, why = "lost", f"after room was made the rerun failed: {wrong[1]}"
            probe.add("disk", f"plan over a run, disk full ({probe.disk_mode})", cls, why)

    jobs.append(replace_full)

    for name, make in (
        ("graph -o", lambda d: ["graph", PUMP, "-o", d / "g.json"]),
        (
            "synth -o",
            lambda d: ["synth", "--layers", "12", "--max-nodes", "12", "-o", d / "g.json"],
        ),
        ("init -o", lambda d: ["init", PUMP / "meshes", "-o", d / "s" / "assembly.yaml"]),
        (
            "train -o",
            lambda d: train_args(shared["graph"], d / "run"),
        ),
    ):

        def small_full(name=name, make=make):
            with small_disk(probe, 4) as (d, limit):
                (d / "fill").write_bytes(b"\0" * 2048) if limit is None else None
                r = run(make(d), timeout=600, preexec=limit)
                if r.rc == 0:
                    probe.add("disk", f"{name} on 4 KiB", "clean")
                    return
                cls, why = judge_refusal(r)
                left = [p.name for p in d.rglob("*") if p.is_file() and p.name != "fill"]
                if cls == "clean" and left:
                    cls, why = "lost", f"half-written: {left}"
                probe.add("disk", f"{name} on a full disk ({probe.disk_mode})", cls, why)

        jobs.append(small_full)

    def service_full():
        if probe.disk_mode == "fsize":
            probe.add("disk", "service on a full disk", "clean", "skipped: no tmpfs")
            return
        plan = json.loads((shared["plan_dir"] / "plan.json").read_text())
        from asmplan.serve.app import plan_id

        pid = plan_id(plan)
        game = _game(plan, 1)
        with small_disk(probe, 600) as (d, _):
            svc = Service(shared["plan_dir"], d / "sessions")
            acked: dict[str, int] = {}
            refusals: list[tuple[int, str]] = []
            try:
                free = shutil.disk_usage(d).free
                (d / "filler").write_bytes(b"\0" * max(0, free - 300_000))
                for _ in range(3000):
                    st, body = svc.request("POST", "/api/sessions", {"plan": pid, "event": game[0]})
                    if st == 201:
                        acked[body["id"]] = 1
                        s = body["id"]
                        for ev in game[1:]:
                            st, body = svc.request("POST", f"/api/sessions/{s}/events", ev)
                            if st != 200:
                                break
                            acked[s] += 1
                    if st != 200 and st != 201:
                        refusals.append((st, str(body)[:120]))
                        if len(refusals) >= 5:
                            break
                # a retry of a refused event must not say "already done"
                retry_bad = []
                for s, n in list(acked.items())[-3:]:
                    if n < len(game):
                        st, body = svc.request("POST", f"/api/sessions/{s}/events", game[n])
                        if st == 409 and "already" in str(body):
                            retry_bad.append((s, st, body))
                svc.kill()
                (d / "filler").unlink()
                svc = Service(shared["plan_dir"], d / "sessions")
                lost = []
                for s, n in acked.items():
                    st, body = svc.request("GET", f"/api/sessions/{s}")
                    have = len(body.get("events", [])) if st == 200 else -1
                    if have < n:
                        lost.append((s, n, have))
                bad_status = [x for x in refusals if x[0] != 503]
                if lost or retry_bad:
                    probe.add(
                        "disk",
                        "service on a full disk",
                        "lost",
                        f"lost {lost[:3]} retry {retry_bad[:2]}",
                    )
                elif not refusals:
                    probe.add("disk", "service on a full disk", "silent", "the disk never filled")
                elif bad_status:
                    probe.add(
                        "disk", "service on a full disk", "silent", f"refused with {bad_status[:2]}"
                    )
                else:
                    probe.add(
                        "disk", f"service on a full disk ({len(acked)} sessions, 503s)", "clean"
                    )
                if svc.traced():
                    probe.add("disk", "service stderr on a full disk", "traceback", svc.lines[-1])
            finally:
                svc.kill()

    jobs.append(service_full)
    return jobs


# --------------------------------------------------------------------------------------


FAMILIES: dict[str, Callable[[Probe, dict], list[Callable[[], None]]]] = {
    "commands": family_commands,
    "spec": family_spec,
    "dag": family_dag,
    "cad": family_cad,
    "output": family_output,
    "repeat": family_repeat,
    "kill": family_kill,
    "service": family_service,
    "disk": family_disk,
}
SERIAL = ("kill", "service", "disk")
"""Families run one case at a time (kill delays and service timing depend on the load)."""


def prepare(probe: Probe) -> dict:
    """The shared inputs: a plan folder of the pump (and its time), a DAG, a training run."""
    shared: dict = {}
    plan_dir = probe.tmp / "pump_plan"
    t0 = time.monotonic()
    r = run(["plan", PUMP, "-o", plan_dir, "--time-limit", "5"], timeout=600)
    if r.rc != 0:
        raise SystemExit(f"the reference plan failed: {_last(r.err)}")
    shared["plan_dir"], shared["plan_seconds"] = plan_dir, time.monotonic() - t0
    graph = probe.tmp / "g.json"
    r = run(["synth", "--layers", "4", "--max-nodes", "3", "--seed", "3", "-o", graph])
    shared["graph"] = graph
    train_run = probe.tmp / "train_run"
    r = run(
        train_args(graph, train_run),
        timeout=600,
    )
    if r.rc != 0:
        raise SystemExit(f"the reference training failed: {_last(r.err)}")
    shared["train_run"] = train_run
    return shared


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="a sample of each family (~10 minutes)")
    ap.add_argument("--only", default="", help="comma-separated families (default: all)")
    ap.add_argument("--seed", type=int, default=26)
    ap.add_argument("--workers", type=int, default=2)
    ns = ap.parse_args(argv)
    names = [n for n in FAMILIES if not ns.only or n in ns.only.split(",")]
    started, cpu0 = time.monotonic(), _children_cpu()
    with tempfile.TemporaryDirectory(prefix="reliability-probe-") as tmp:
        probe = Probe(Path(tmp), ns.quick, random.Random(ns.seed))
        snapshot(probe.tmp)
        shared = prepare(probe)
        print(
            f"prepared in {time.monotonic() - started:.0f} s "
            f"(plan of the pump: {shared['plan_seconds']:.1f} s)"
        )
        for name in names:
            jobs = FAMILIES[name](probe, shared)
            print(f"{name}: {len(jobs)} jobs ", end="", flush=True)
            t0 = time.monotonic()
            workers = 1 if name in SERIAL else ns.workers
            with futures.ThreadPoolExecutor(workers) as pool:
                for f in [pool.submit(job) for job in jobs]:
                    try:
                        f.result()
                    except Exception as exc:  # the probe's own failure: count it, go on
                        probe.add(name, f"probe error {type(exc).__name__}", "silent", str(exc))
            print(f" {time.monotonic() - t0:.0f} s")
        _table(probe, time.monotonic() - started, _children_cpu() - cpu0)
        return 0 if all(r.cls == "clean" for r in probe.results) else 1


def _children_cpu() -> float:
    u = resource.getrusage(resource.RUSAGE_CHILDREN)
    s = resource.getrusage(resource.RUSAGE_SELF)
    return u.ru_utime + u.ru_stime + s.ru_utime + s.ru_stime


def _table(probe: Probe, wall: float, cpu: float) -> None:
    rows = {}
    for r in probe.results:
        row = rows.setdefault(r.family, dict.fromkeys(CLASSES, 0))
        row[r.cls] += 1
    print(
        f"\nreliability probe ({'quick' if probe.quick else 'full'}): {wall:.0f} s wall, "
        f"{cpu:.0f} s CPU; "
        f"full disk by {probe.disk_mode}"
    )
    print(f"| family | tried | {' | '.join(CLASSES)} |")
    print("|---|---:|" + "---:|" * len(CLASSES))
    total = dict.fromkeys(CLASSES, 0)
    for family, row in rows.items():
        print(f"| {family} | {sum(row.values())} | {' | '.join(str(row[c]) for c in CLASSES)} |")
        for c in CLASSES:
            total[c] += row[c]
    print(f"| all | {sum(total.values())} | {' | '.join(str(total[c]) for c in CLASSES)} |")
    print("\nslowest child runs (wall s):")
    for seconds, line in sorted(RUNS, reverse=True)[:10]:
        print(f"  {seconds:6.1f}  asmplan {line}")
    failing = [r for r in probe.results if r.cls != "clean"]
    if failing:
        print("\nfailing cases:")
        for r in failing:
            print(f"  {r.cls:9s} {r.family}/{r.name}: {r.reason}")


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
