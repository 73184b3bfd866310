"""``asmplan init`` writes a spec it reads back: every id quoted where YAML would retype it.

Mesh files named ``00.obj``, ``01.obj`` once gave ``part: 01``, read back as the integer 1,
so ``init`` failed its own check. The round trip runs ``init`` on part names of every shape
(digits, leading zeros, YAML's booleans and nulls, exponents, decimals, free text) and reads
the file with the spec parser; ``--units`` and ``--gravity`` on ``plan`` and ``init``; a
note when the model is implausibly small for its unit. Geometry built here.
"""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from asmplan.cli import app
from asp.fromcad.generate import _scalar, generated_spec
from asp.spec import load_spec
from cad.yamlfile import DecimalsAsText
from tests.cad.real_shapes import box

TRICKY = ("00", "01", "007", "1", "yes", "no", "on", "off", "y", "n", "true", "null", "~")
TRICKY += ("1e3", "1E3", "1.10", "0x1f", "0o17", ".5", "-3", "+4", "1_000", "inf", ".nan")
TRICKY += ("nan", "2026-12-02", "12:30", "a b", "a#b", "x-1", "v1.0", "body001", "Null")
NAME = st.one_of(
    st.sampled_from(TRICKY),
    st.text(alphabet="abcxyz0123456789_-.eE", min_size=1, max_size=8),
).filter(lambda s: s.strip(" .") == s and not s.startswith("-") and s not in (".", ".."))


def stacked(folder: Path, names: list[str]) -> Path:
    """One box per name, stacked along z (the first the widest), as ``<name>.obj``."""
    folder.mkdir(parents=True)
    for k, name in enumerate(names):
        half = 20 - 2 * k
        mesh = box((-half, -half, 5 * k), (half, half, 5 * k + 5))
        mesh.export(folder / f"{name}.obj")
    return folder


def init(source: Path, out: Path, *more: str):
    result = CliRunner().invoke(app, ["init", str(source), "-o", str(out), "--force", *more])
    assert result.exit_code == 0, result.output
    return result


@pytest.mark.parametrize("text", TRICKY + ("plain", "bolt_m6", "Ø8 pin", "tab\tname"))
def test_a_written_scalar_reads_back_as_the_same_text(text):
    for loader in (yaml.SafeLoader, DecimalsAsText):
        assert yaml.load(f"k: {_scalar(text)}", Loader=loader) == {"k": text}  # noqa: S506


def test_plain_names_stay_plain():
    assert [_scalar(t) for t in ("bolt", "nut_m6", "Plate 2")] == ["bolt", "nut_m6", "Plate 2"]


@settings(
    max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(names=st.lists(NAME, min_size=2, max_size=3, unique_by=str.lower))
def test_init_round_trip_on_names_of_every_shape(tmp_path_factory, names):
    folder = stacked(tmp_path_factory.mktemp("names") / "meshes", names)
    out = folder.parent / "assembly.yaml"
    init(folder, out)
    written = load_spec(out)
    generated = generated_spec(folder)
    assert [p.id for p in written.parts] == [p.id for p in generated.parts]
    assert {p.id for p in written.parts} == set(names)
    assert written.base_part == generated.base_part
    assert sorted(op.parts for op in written.operations) == sorted(
        op.parts for op in generated.operations
    )


def test_leading_zero_files_plan_from_the_written_spec(tmp_path):
    folder = stacked(tmp_path / "meshes", ["00", "01", "02"])
    out = tmp_path / "assembly.yaml"
    init(folder, out)
    assert 'base_part: "00"' in out.read_text()
    result = CliRunner().invoke(app, ["plan", str(out), "-o", str(tmp_path / "plan")])
    assert result.exit_code == 0, result.output


def tiny(folder: Path) -> Path:
    """A plate and a block 1.5 mm across: a model in metres read as millimetres."""
    folder.mkdir()
    box((-0.5, -0.5, 0), (0.5, 0.5, 0.2)).export(folder / "plate.stl")
    box((-0.15, -0.15, 0.2), (0.15, 0.15, 0.5)).export(folder / "block.stl")
    return folder


def test_a_model_a_few_mm_across_gets_a_unit_note(tmp_path):
    folder = tiny(tmp_path / "tiny")
    result = init(folder, tmp_path / "a.yaml")
    assert "units: the whole assembly is only 1.5 mm across" in result.stderr
    assert "--units m" in result.stderr
    assert "#   the whole assembly is only" in (tmp_path / "a.yaml").read_text()
    planned = CliRunner().invoke(app, ["plan", str(folder)])
    assert planned.exit_code == 0, planned.output
    assert "units: the whole assembly is only 1.5 mm across" in planned.stderr


def test_units_option_on_init_and_plan(tmp_path):
    folder = tiny(tmp_path / "tiny")
    result = init(folder, tmp_path / "a.yaml", "--units", "m")
    assert "units: m " in (tmp_path / "a.yaml").read_text()
    assert "mm across" not in result.stderr
    planned = CliRunner().invoke(
        app, ["plan", str(folder), "--units", "m", "-o", str(tmp_path / "p")]
    )
    assert planned.exit_code == 0, planned.output
    assert "mm across" not in planned.stderr
    bad = CliRunner().invoke(app, ["plan", str(folder), "--units", "parsec"])
    assert bad.exit_code == 2 and "unknown length unit 'parsec'" in bad.output


def test_gravity_option_overrules_the_choice(tmp_path):
    folder = stacked(tmp_path / "meshes", ["plate", "block"])
    result = init(folder, tmp_path / "a.yaml", "--gravity", "+x")
    assert "gravity: +x" in (tmp_path / "a.yaml").read_text()
    assert "given (--gravity); from the geometry alone: -z" in result.stderr
    planned = CliRunner().invoke(app, ["plan", str(folder), "--gravity", "+x"])
    assert "generated spec: gravity +x: given (--gravity)" in planned.stderr
    bad = CliRunner().invoke(app, ["init", str(folder), "--gravity", "down"])
    assert bad.exit_code == 2 and "--gravity: expected one of" in bad.output
