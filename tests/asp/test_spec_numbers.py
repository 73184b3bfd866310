"""Every number of a spec is written in plain decimal (issue 26 item 9, :mod:`cad.numbers`):
``010`` (8 to YAML), ``1_000``, ``1:30`` (90), ``0x10`` and ``true`` refused in one line
naming the file, the key and the value as written."""

from __future__ import annotations

import pytest

from asp.spec import load_spec

AGENTS = "agents: {H: {side: human}, R: {side: robot}}\n"
TOOLS = "tools: {R.bit: {initial: a, change_time: VALUE}}\n"
BAD = ["010", "1_000", "1:30", "0x10", "true", "01.5"]


def spec_text(where: str, value: str) -> str:
    op = "  - {id: a, agents: {H: 1}}\n"
    if where == "duration":
        op = f"  - {{id: a, agents: {{H: {value}}}}}\n"
    elif where == "range":
        op = f"  - {{id: a, agents: {{H: [1, {value}]}}}}\n"
    text = AGENTS + "operations:\n" + op
    if where == "change_time":
        text += TOOLS.replace("VALUE", value)
    elif where in ("max_states", "contact_tol"):
        text += f"{where}: {value}\n"
    elif where == "degrees":
        text += f"frame: {{axis: [0, 0, 1], degrees: {value}}}\n"
    return text


KEYS = {
    "duration": "operations[a].agents.H",
    "range": "operations[a].agents.H",
    "change_time": "tools.R.bit.change_time",
    "max_states": "max_states",
    "contact_tol": "contact_tol",
    "degrees": "degrees",
}


@pytest.mark.parametrize("value", BAD)
@pytest.mark.parametrize("where", sorted(KEYS))
def test_a_number_not_written_plainly_is_refused_with_key_and_value(tmp_path, where, value):
    path = tmp_path / "assembly.yaml"
    path.write_text(spec_text(where, value))
    with pytest.raises(ValueError) as info:
        load_spec(path)
    text = str(info.value)
    assert str(path) in text and KEYS[where] in text and "\n" not in text, text
    assert repr(value) in text or (value == "true" and "True" in text), text


@pytest.mark.parametrize(
    ("where", "value"),
    [
        ("duration", "12"),
        ("duration", "1.5"),
        ("range", "2e1"),
        ("change_time", "0"),
        ("max_states", "1000"),
        ("contact_tol", "0.1"),
        ("degrees", "30"),
    ],
)
def test_a_number_written_plainly_is_read(tmp_path, where, value):
    path = tmp_path / "assembly.yaml"
    path.write_text(spec_text(where, value))
    spec = load_spec(path)
    if where == "duration":
        assert spec.operations[0].duration("H") == float(value)
    if where == "max_states":
        assert spec.max_states == int(value)
