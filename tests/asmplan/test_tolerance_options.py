"""``--contact-tol`` / ``--penetration-tol`` on plan, relations and init, and the same keys in
the spec: one range (cad.tolerances.checked_tolerance), one-line errors, the flag wins."""

from __future__ import annotations

import json

import pytest
import yaml
from typer.testing import CliRunner

from asmplan.cli import app, main
from asp.spec import spec_from_dict
from tests.cad import shapes
from tests.cad.test_loading import write_folder

SUNK = 0.15
"""The top cube is sunk this deep into the bottom one: deeper than two 10 mm cubes' default
tolerance (0.104 mm), within an explicit 0.2 mm."""


@pytest.fixture()
def sunk_cubes(tmp_path):
    return write_folder(tmp_path / "cubes", shapes.stacked_cubes(overlap=SUNK))


def invoke(*args: str):
    return CliRunner().invoke(app, [str(a) for a in args])


def test_default_tolerance_refuses_the_overlap_and_the_flag_accepts_it(sunk_cubes, tmp_path):
    refused = invoke("plan", sunk_cubes)
    assert refused.exit_code == 2
    assert "interpenetrate" in refused.output
    out = tmp_path / "out"
    ok = invoke("plan", sunk_cubes, "-o", out, "--penetration-tol", "0.2", "--contact-tol", "0.05")
    assert ok.exit_code == 0, ok.output
    doc = json.loads((out / "plan.json").read_text())
    assert [s["operation"] for s in doc["robust_plan"] if s["operation"]] == ["1", "2"]


def test_spec_keys_and_the_flag_overrides_them(sunk_cubes, tmp_path):
    spec = sunk_cubes / "assembly.yaml"
    made = invoke("init", sunk_cubes, "-o", spec, "--penetration-tol", "0.2")
    assert made.exit_code == 0, made.output
    data = yaml.safe_load(spec.read_text())
    assert data["penetration_tol"] == 0.2 and "contact_tol" not in data
    assert "# contact_tol:" in spec.read_text()
    assert invoke("plan", spec).exit_code == 0
    rel = json.loads(invoke("relations", sunk_cubes, "--format", "json").output)
    assert rel["penetration_tol_mm"] == 0.2  # the folder's assembly.yaml is read
    tight = invoke("plan", spec, "--penetration-tol", "0.1")
    assert tight.exit_code == 2 and "interpenetrate" in tight.output


@pytest.mark.parametrize("command", ["plan", "relations", "init"])
@pytest.mark.parametrize(
    ("flag", "value"),
    [
        ("--penetration-tol", "0"),
        ("--penetration-tol", "-1"),
        ("--penetration-tol", "nan"),
        ("--contact-tol", "-0.1"),
        ("--contact-tol", "1e9"),
        ("--contact-tol", "inf"),
    ],
)
def test_out_of_range_is_one_line_naming_the_option(sunk_cubes, capsys, command, flag, value):
    with pytest.raises(SystemExit) as info:
        main([command, str(sunk_cubes), flag, value])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and flag in err and "mm from" in err


@pytest.mark.parametrize(
    ("key", "value", "ok"),
    [
        ("contact_tol", 0, True),
        ("contact_tol", 0.3, True),
        ("penetration_tol", 0.5, True),
        ("penetration_tol", 0, False),
        ("penetration_tol", -0.2, False),
        ("contact_tol", "wide", False),
        ("contact_tol", True, False),
        ("penetration_tol", 1000, False),
    ],
)
def test_spec_tolerance_keys(key, value, ok):
    data = {"agents": {"R": {"side": "robot"}}, "operations": [{"id": "1", "agents": {"R": 1}}]}
    if ok:
        assert getattr(spec_from_dict({**data, key: value}, source="a.yaml"), key) == value
    else:
        with pytest.raises(ValueError, match=rf"^a\.yaml: {key}: expected a number of mm from"):
            spec_from_dict({**data, key: value}, source="a.yaml")
