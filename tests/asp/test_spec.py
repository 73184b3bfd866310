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
        (("operations", 1, "parts"), ["A"], r"operations\[2\]: both part and parts: give one"),
        # issue 26 (the reliability probe): a name or text of the wrong type is refused
        (("name",), {"a": 1}, r"name: expected a name, got \{'a': 1\}"),
        (("name",), ["a"], r"name: expected a name"),
        (("operations", 0, "description"), {"a": 1}, r"description: expected a text, got a map"),
        (("agents", "H", "description"), [1, 2], r"H\.description: expected a text, got a list"),
        (("credit",), {"by": "me"}, r"credit: expected a text"),
        # a part's text given a mapping or list: the key, the part and the value's type
        (
            ("parts", 0, "type"),
            {"a": 1},
            r"parts\[0\] \(part 'A'\): type: expected a text, got a map",
        ),
        (("parts", 0, "type"), ["screw"], r"\(part 'A'\): type: expected a text, got a list"),
        (("parts", 1, "name"), {"a": 1}, r"\(part 'B'\): name: expected a text, got a mapping"),
        (("parts", 1, "shape"), [1], r"\(part 'B'\): shape: expected a text, got a list"),
        (("parts", 0, "file"), {"a": 1}, r"\(part 'A'\): file: expected a text, got a mapping"),
        (("parts", 0, "id"), {"a": 1}, r"parts\[0\]: id: expected a text, got a mapping"),
    ],
)
def test_validation_errors_name_file_key_and_culprit(path, value, message):
    with pytest.raises(ValueError, match=message) as info:
        spec_from_dict(variant(path, value), source="toy.yaml")
    text = str(info.value)
    assert text.startswith("toy.yaml: ") and "\n" not in text


@pytest.mark.parametrize(
    "text",
    [
        "name: a\nname: b\n",  # top level
        "agents:\n  H: {side: human}\n  H: {side: robot}\n",  # nested
        "operations:\n  - {id: 1, id: 2}\n",  # flow mapping
    ],
)
def test_a_repeated_yaml_key_is_refused_with_its_line(tmp_path, text):
    path = tmp_path / "assembly.yaml"
    path.write_text(text)
    with pytest.raises(
        ValueError, match=r"duplicate key '(name|H|id)' at line \d+ \(first at"
    ) as info:
        load_spec(path)
    assert str(info.value).startswith(str(path)) and "\n" not in str(info.value)


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


# ---------------------------------------------------------------- one part model (issue 10)


@pytest.mark.parametrize(
    ("path", "value", "message"),
    [
        (("gravty",), "+z", r"toy\.yaml: unknown key 'gravty' \(did you mean 'gravity'\?\)"),
        (("operatons",), [], r"unknown key 'operatons' \(did you mean 'operations'\?\)"),
        (("parts", 0, "qty"), 2, r"parts\[0\]: unknown key 'qty'"),
        (("parts", 0, "fiel"), "a.stl", r"did you mean 'file'"),
        (("agents", "H", "sde"), "human", r"agents\.H: unknown key 'sde' \(did you mean 'side'"),
        (("tools", "R1.bit", "inital"), "hex", r"did you mean 'initial'"),
        (("operations", 0, "afterr"), ["2"], r"did you mean 'after'"),
        (("units",), "furlong", r"units: unknown length unit 'furlong'"),
        (("parts", 0, "quantity"), "many", r"quantity 'many' is not a positive integer"),
        (("parts", 0, "quantity"), 0, r"quantity 0 is not a positive integer"),
    ],
)
def test_unknown_keys_are_refused_with_the_nearest_one(path, value, message):
    with pytest.raises(ValueError, match=message):
        spec_from_dict(variant(path, value), source="toy.yaml")


def test_spec_and_bom_accept_the_same_parts(tmp_path):
    # quantity "2" (as CSV gives it) and a bare part name: one model, one validation
    spec = spec_from_dict(variant(("parts",), ["A", {"id": "B", "quantity": "2"}]), "toy.yaml")
    assert [(p.id, p.quantity, p.file) for p in spec.parts] == [("A", 1, None), ("B", 2, None)]
    from cad import read_bom

    bom = tmp_path / "bom.yaml"
    bom.write_text("parts: [A, {id: B, quantity: '2'}]\n")
    assert read_bom(bom) == spec.parts
    csv = tmp_path / "bom.csv"
    csv.write_text("id,quantity\nA,\nB,2\n")
    assert read_bom(csv) == spec.parts


def test_a_part_without_a_mesh_is_named_when_geometry_is_needed(tmp_path):
    from asp.fromcad.generate import spec_geometry

    spec = spec_from_dict(variant(("parts",), ["A", {"id": "B", "file": "b.stl"}]), "x.yaml")
    with pytest.raises(ValueError, match="part 'A' has no mesh file"):
        spec_geometry(spec)


ALIAS_BOMB = """\
a: &a ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]
b: &b [*a, *a, *a, *a, *a, *a, *a, *a, *a]
c: &c [*b, *b, *b, *b, *b, *b, *b, *b, *b]
d: &d [*c, *c, *c, *c, *c, *c, *c, *c, *c]
e: &e [*d, *d, *d, *d, *d, *d, *d, *d, *d]
f: &f [*e, *e, *e, *e, *e, *e, *e, *e, *e]
g: &g [*f, *f, *f, *f, *f, *f, *f, *f, *f]
name: *g
"""


def test_a_yaml_alias_bomb_is_refused(tmp_path):
    path = tmp_path / "assembly.yaml"
    path.write_text(ALIAS_BOMB)
    with pytest.raises(ValueError, match="expands to more than 1,000,000 values"):
        load_spec(path)
    path.write_text("a: &x [1, 2]\nb: [*x, *x]\n")  # a few aliases are fine (then: unknown key)
    with pytest.raises(ValueError, match="unknown key 'a'"):
        load_spec(path)


def test_a_self_referencing_yaml_is_refused(tmp_path):
    path = tmp_path / "assembly.yaml"
    path.write_text("name: &x [*x]\n")
    with pytest.raises(ValueError, match="expands to more than"):
        load_spec(path)


LONG_NAME, LONG_TEXT = "n" * 201, "t" * 2001


@pytest.mark.parametrize(
    ("path", "value", "where"),
    [
        (("name",), LONG_NAME, "toy.yaml: name: 201 characters"),
        (("credit",), LONG_TEXT, "toy.yaml: credit: 2,001 characters"),
        (("operations", 0, "id"), LONG_NAME, "operations[0].id: 201 characters"),
        (("operations", 0, "description"), LONG_TEXT, "operations[1].description: 2,001"),
        (("operations", 1, "after"), [LONG_NAME], "operations[2].after: 201"),
        (("agents", "H", "description"), LONG_TEXT, "agents.H.description: 2,001"),
        (("tools", "R1.bit", "initial"), LONG_NAME, "tools.R1.bit.initial: 201"),
        (("parts", 1, "name"), LONG_NAME, "(part 'B'): name: 201 characters"),
        (("parts", 1, "id"), LONG_NAME, "id: 201 characters"),
        (("parts", 1, "file"), LONG_TEXT, "(part 'B'): file: 2,001 characters"),
    ],
)
def test_every_free_text_is_bounded(path, value, where):
    """Issue 26 item 13: a 5 MB name kept `plan` drawing its figures for minutes; every
    name is at most 200 characters and every description 2,000 (cad.texts), refused in one
    line naming the file, the key and the length."""
    with pytest.raises(ValueError, match="over the limit of") as info:
        spec_from_dict(variant(path, value), source="toy.yaml")
    message = str(info.value)
    assert where in message and "\n" not in message and len(message) < 300, message
    at_limit = (
        value[:200] if len(value) == 201 else value[:2000] if isinstance(value, str) else None
    )
    if at_limit is not None and path[-1] not in ("id", "initial"):  # ids must stay consistent
        spec_from_dict(variant(path, at_limit), source="toy.yaml")  # the bound itself is fine


@pytest.mark.parametrize("word", ["widget", "O-ring (Viton)", "12", "a{b}"])
def test_a_part_type_is_free_text(word):
    """A part's ``type`` is the BOM's own word (``screw``, ``component``): kept as written,
    never a category the planner reads, so no word is unknown (the reliability probe's slow
    ``plan`` of a spec with an unknown type was numba recompiling its kernels, not the type)."""
    spec = spec_from_dict(variant(("parts", 0, "type"), word), source="toy.yaml")
    assert spec.parts[0].type == word and spec.parts[1].type == ""
