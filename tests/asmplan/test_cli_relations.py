"""``asmplan relations``: formats and error handling."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from asmplan.cli import app, main
from tests.cad import shapes
from tests.cad.test_loading import write_folder


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return write_folder(tmp_path_factory.mktemp("cli") / "asm", shapes.boxed_container())


def run(*args: str):
    result = CliRunner().invoke(app, ["relations", *args])
    assert result.exit_code == 0, result.output
    return result.output


def test_json_document(folder):
    doc = json.loads(run(str(folder), "--format", "json"))
    assert {"parts", "directions", "tc", "tt", "units"} <= set(doc)
    assert doc["parts"] == ["item", "lid", "tray"]
    assert doc["directions"] == ["+x", "-x", "+y", "-y", "+z", "-z"]
    n = len(doc["parts"])
    for key in ("tc", "tt"):
        table = doc[key]
        assert len(table) == n and all(len(r) == n and all(len(c) == 6 for c in r) for r in table)
        assert not any(any(table[i][i]) for i in range(n))
    item, tray = doc["parts"].index("item"), doc["parts"].index("tray")
    assert doc["tc"][item][tray] == [False] * 5 + [True]
    assert doc["tt"][item][tray] == [False] * 4 + [True, False]


@pytest.mark.parametrize(
    ("fmt", "needle"),
    [
        ("text", "item  tray  -z"),
        ("markdown", "| item | tray | -z | +z |"),
        ("csv", "item,tray,tt,0,0,0,0,1,0"),
    ],
)
def test_table_formats(folder, fmt, needle):
    assert needle in run(str(folder), "--format", fmt)


def test_tolerance_options(folder):
    doc = json.loads(
        run(
            str(folder),
            "--format",
            "json",
            "--penetration-tol",
            "0.2",
            "--contact-tol",
            "0.02",
            "--units",
            "mm",
        )
    )
    assert doc["penetration_tol_mm"] == 0.2 and doc["contact_tol_mm"] == 0.02


def test_bad_input_exits_2_with_one_line(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["relations", str(tmp_path / "missing")])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("asmplan: error: assembly not found") and err.count("\n") == 1
