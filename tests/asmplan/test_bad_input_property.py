"""Property: random bad input to any command is one line on stderr, exit 2, no output left.

Issue 14: "A property test feeds random bad inputs (hypothesis) to every command and asserts
exit 2 with one line and no file left in ``--output``." Two kinds of bad input:

- a garbage input file (random bytes, text, JSON or YAML values) under each suffix the
  command reads;
- a bad value of a numeric or choice option (out of range, not a number, ``nan``, ``inf``,
  unknown names) with an otherwise valid command line.
"""

from __future__ import annotations

import json
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from asmplan.cli import app
from asp.game.io import save_dag
from tests.asp.figures import figure4
from tests.conftest import REPO

PUMP = REPO / "examples" / "vacuum_pump"
RUNS = settings(
    max_examples=40,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)

# command -> (suffixes of its input file, arguments after the input; OUT is the output path)
FILE_COMMANDS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "solve": ((".json", ".graphml"), ("--games", "10")),
    "baseline": ((".json", ".graphml", ".sm", ".yaml", ".IN2"), ("--time-limit", "5")),
    "graph": ((".yaml", ".IN2"), ("--output", "OUT/g.json")),
    "plan": ((".yaml", ".IN2"), ("--output", "OUT", "--time-limit", "5")),
    "relations": ((".yaml", ".stl", ".obj", ".ply", ".glb", ".3mf"), ()),
    "init": ((".stl", ".obj", ".glb", ".step"), ("--output", "OUT/assembly.yaml")),
    "play": ((".json", ".graphml", ".yaml"), ()),
    "train": ((".json", ".graphml"), ("--output", "OUT", "--max-cycles", "1")),
    "evaluate": ((".json",), ("--model", "MODEL")),
}

json_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=6), inner),
    max_leaves=12,
)
garbage = st.one_of(
    st.binary(max_size=200),
    st.text(max_size=200).map(str.encode),
    json_values.map(lambda v: json.dumps(v).encode()),
    st.dictionaries(
        st.sampled_from(["name", "parts", "agents", "operations", "nodes", "edges", "cost"]),
        json_values,
        max_size=4,
    ).map(lambda v: json.dumps(v).encode()),  # JSON is YAML too: keys the readers look for
)


def invoke(args: list[str]):
    return CliRunner().invoke(app, args, input="")


def assert_bad_input(result, out: Path) -> None:
    assert result.exit_code == 2, (result.exit_code, result.output, result.exception)
    lines = result.stderr.strip().splitlines()
    errors = [line for line in lines if line.startswith("asmplan: error: ")]
    # Progress lines ("[1/5] ...") may come first; the error is one line, the last.
    assert len(errors) == 1 and lines[-1] == errors[0], result.stderr
    assert "Traceback" not in result.stderr
    assert not out.exists(), f"{out} was left behind"


@pytest.mark.slow
@RUNS
@given(
    command=st.sampled_from(sorted(FILE_COMMANDS)),
    content=garbage,
    pick=st.integers(min_value=0, max_value=10),
)
def test_garbage_input_files(command, content, pick):
    suffixes, rest = FILE_COMMANDS[command]
    suffix = suffixes[pick % len(suffixes)]
    if suffix == ".IN2":
        content = b"x" + content  # the first line of a .IN2 must be a count: never valid
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        source = tmp / f"input{suffix}"
        source.write_bytes(content)
        out = tmp / "out"
        (tmp / "model").mkdir()
        args = [a.replace("OUT", str(out)).replace("MODEL", str(tmp / "model")) for a in rest]
        assert_bad_input(invoke([command, str(source), *args]), out)


@pytest.fixture(scope="module")
def graph_file(tmp_path_factory) -> str:
    return str(save_dag(figure4(), tmp_path_factory.mktemp("g") / "fig4.json"))


not_a_number = st.text(min_size=1, max_size=6).filter(
    lambda s: not s.strip().lstrip("+-").replace(".", "", 1).isdigit()
)
negative = st.integers(max_value=-1).map(str)
huge = st.integers(min_value=10**12, max_value=10**40).map(str)
non_finite = st.sampled_from(["nan", "inf", "-inf", "NaN"])

# (command line with VALUE for the bad value; OUT the output), strategy of bad values
OPTION_CASES: list[tuple[tuple[str, ...], st.SearchStrategy[str]]] = [
    (("synth", "--layers", "VALUE", "--max-nodes", "3", "--output", "OUT/g.json"),
     negative | huge | not_a_number | st.just("0")),
    (("synth", "--layers", "3", "--max-nodes", "3", "--max-actions", "VALUE", "-o", "OUT/g.json"),
     negative | huge | not_a_number | st.just("0")),
    (("synth", "--layers", "3", "--max-nodes", "3", "--seed", "VALUE", "-o", "OUT/g.json"),
     negative | huge | not_a_number),
    (("solve", "GRAPH", "--games", "VALUE"), negative | huge | not_a_number | st.just("0")),
    (("solve", "GRAPH", "--seed", "VALUE"), negative | huge | not_a_number),
    (("solve", "GRAPH", "--wcpl", "VALUE"), non_finite | negative | not_a_number),
    (("solve", "GRAPH", "--format", "VALUE"),
     not_a_number.filter(lambda s: s not in ("text", "json"))),
    (("baseline", "GRAPH", "--seed", "VALUE"), negative | huge | not_a_number),
    (("baseline", "GRAPH", "--workers", "VALUE"), negative | huge | st.just("0")),
    (("baseline", "GRAPH", "--time-limit", "VALUE"), non_finite | negative | st.just("0")),
    (("plan", "PUMP", "--output", "OUT", "--seed", "VALUE"), negative | huge | not_a_number),
    (("plan", "PUMP", "--output", "OUT", "--time-limit", "VALUE"), non_finite | negative),
    (("plan", "PUMP", "--output", "OUT", "--cost", "VALUE"),
     not_a_number.filter(lambda s: s not in ("steps", "time"))),
    (("graph", "PUMP", "--output", "OUT/g.json", "--list", "VALUE"), negative | huge),
    (("play", "GRAPH", "--seed", "VALUE"), negative | huge | not_a_number),
    (("play", "GRAPH", "--moves", "VALUE"), st.sampled_from(["x", "1,,2", "-1", "0", "99"])),
    (("train", "GRAPH", "--output", "OUT", "--seed", "VALUE"), negative | huge | not_a_number),
    (("train", "GRAPH", "--output", "OUT", "--max-cycles", "VALUE"), negative | st.just("0")),
    (("train", "GRAPH", "--output", "OUT", "--config", "VALUE"),
     not_a_number.filter(lambda s: s not in ("paper", "fast"))),
    (("evaluate", "GRAPH", "--model", "OUT", "--games", "VALUE"), negative | huge),
    (("experiment", "table3", "--output", "OUT", "--seed", "VALUE"), negative | huge),
    (("experiment", "table3", "--output", "OUT", "--workers", "VALUE"), negative | huge),
    (("experiment", "table3", "--output", "OUT", "--games", "VALUE"), negative | huge),
    (("experiment", "table3", "--output", "OUT", "--trials", "VALUE"), negative | huge),
    (("relations", "PUMP", "--contact-tol", "VALUE"), non_finite | negative | huge),
    (("serve", "PUMP", "--port", "VALUE"), negative | huge),
]  # fmt: skip


@pytest.mark.slow
@RUNS
@given(case=st.integers(min_value=0, max_value=len(OPTION_CASES) - 1), data=st.data())
def test_bad_option_values(graph_file, case, data):
    template, values = OPTION_CASES[case]
    value = data.draw(values, label="value")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        fill = {"GRAPH": graph_file, "PUMP": str(PUMP), "OUT": str(out), "VALUE": value}
        args = []
        for a in template:
            for key, text in fill.items():
                a = a.replace(key, text) if key in ("OUT",) else (text if a == key else a)
            args.append(a)
        assert_bad_input(invoke(args), out)
