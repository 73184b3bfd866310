"""The assembly specification: loading, defaults and one-line validation errors."""

from __future__ import annotations

import copy
from pathlib import Path

import pytest

from asp.spec import load_spec, spec_from_dict

PUMP = Path(__file__).resolve().parents[2] / "examples" / "vacuum_pump"

BASE = {
    "name": "toy",
    "parts": [{"id": "A", "file": "a.stl"}, {"id": "B", "file": "b.stl"}],
    "agents": {"H": {"side": "human"}, "R1": {"side": "robot"}},
    "tools": {"R1.bit": {"initial": "hex", "change_time": 2}},
    "base_part": "A",
    "operations": [
        {"id": "1", "agents": {"H": 2}, "sets": {"R1.bit": "cross"}},
        {
            "id": "2",
            "agents": {"R1": 3},
            "part": "B",
            "requires": {"R1.bit": "cross"},
            "after": ["1"],
        },
    ],
}


def variant(path, value):
    data = copy.deepcopy(BASE)
    target = data
    for key in path[:-1]:
        target = target[key]
    if value is KeyError:
        del target[path[-1]]
    else:
        target[path[-1]] = value
    return data


def test_valid_spec_defaults():
    spec = spec_from_dict(copy.deepcopy(BASE), source="toy.yaml")
    assert spec.op_ids == ("1", "2")
    assert spec.cost == "steps" and spec.gravity == "-z" and spec.turn_model == "alternate"
    assert spec.constraints.stability and spec.constraints.functional
    assert spec.operation("2").duration("R1") == 3.0
    assert spec.operation("2").parts == ("B",)
    assert spec.tool("R1.bit").change_time == 2.0
    with pytest.raises(ValueError, match="may not do it"):
        spec.operation("2").duration("H")


@pytest.mark.parametrize(
    ("path", "value", "message"),
    [
        (("operations", 0, "agents"), {"R9": 1}, r"operations\[1\]\.agents: unknown agent 'R9'"),
        (("operations", 1, "after"), ["7"], r"operations\[2\]\.after: unknown predecessor '7'"),
        (("operations", 0, "after"), ["2"], r"cyclic predecessors: (1 -> 2 -> 1|2 -> 1 -> 2)"),
        (("operations", 0, "agents"), {}, r"operations\[1\]\.agents: no agent may do"),
        (("operations", 1, "requires"), {"R1.bit": "torx"}, r"R1\.bit = 'torx' is needed but"),
        (("operations", 1, "id"), "1", r"duplicate operation id '1'"),
        (("operations", 1, "part"), "Z", r"operations\[2\]\.part: unknown part 'Z'"),
        (("operations", 0, "part"), "B", r"part 'B' is already placed by operation '1'"),
        (("operations", 1, "requires"), {"R2.bit": "hex"}, r"unknown tool 'R2\.bit'"),
        (("operations", 1, "agents"), {"R1": -1}, r"agents\.R1: expected a finite number >= 0"),
        (("operations", 1, "colour"), "red", r"unknown key 'colour'"),
        (("agents", "H", "side"), "alien", r"agents\.H\.side: expected human, robot or any"),
        (("base_part",), "Q", r"base_part: unknown part 'Q'"),
        (("gravity",), "down", r"gravity: expected one of"),
        (("cost",), "money", r"cost: expected 'steps' or 'time'"),
        (("turn_model",), "free", r"turn_model: expected 'alternate'"),
        (("constraints",), {"stability": "yes"}, r"constraints\.stability: expected true or false"),
        (("constraints",), {"beauty": True}, r"unknown switch 'beauty'"),
        (("tools", "R1.bit", "initial"), KeyError, r"tools\.R1\.bit: missing 'initial'"),
        (("parts",), [{"id": "A"}, {"id": "A"}], r"parts: duplicate part id 'A'"),
        (("operations",), [], r"operations: expected a non-empty list"),
    ],
)
def test_validation_errors_name_file_key_and_culprit(path, value, message):
    with pytest.raises(ValueError, match=message) as info:
        spec_from_dict(variant(path, value), source="toy.yaml")
    text = str(info.value)
    assert text.startswith("toy.yaml: ") and "\n" not in text


def test_ids_stay_strings(tmp_path):
    text = """
agents: {H: {side: human}}
operations:
  - {id: 1.10, agents: {H: 1.5}}
  - {id: 1.1, agents: {H: 2}, after: [1.10]}
"""
    (tmp_path / "assembly.yaml").write_text(text)
    spec = load_spec(tmp_path)
    assert spec.op_ids == ("1.10", "1.1")
    assert spec.operation("1.1").after == ("1.10",)
    assert spec.operation("1.10").duration("H") == 1.5


def test_malformed_yaml_and_missing_file(tmp_path):
    (tmp_path / "assembly.yaml").write_text("operations: [\n")
    with pytest.raises(ValueError, match="malformed YAML"):
        load_spec(tmp_path / "assembly.yaml")
    with pytest.raises(FileNotFoundError, match="no assembly.yaml"):
        load_spec(tmp_path / "..")
    with pytest.raises(FileNotFoundError):
        load_spec(tmp_path / "nothing.yaml")


def test_vacuum_pump_spec():
    spec = load_spec(PUMP)
    assert len(spec.operations) == 21
    assert {a.name: a.side for a in spec.agents} == {"H": "human", "R1": "robot", "R2": "robot"}
    assert spec.tool("R1.bit").initial == "hex"
    assert spec.operation("1.6").requires == (("R1.bit", "cross"),)
    assert spec.operation("2.5").requires == (("R1.bit", "hex"),)
    assert spec.operation("1.2").sets == (("R1.bit", "cross"),)
    assert spec.operation("2.1").sets == (("R1.bit", "hex"),)
    assert spec.base_part == "BD" and "BD" not in spec.placed_parts
    assert spec.has_geometry
