"""``python -m asmplan.warmup``: plans the bundled examples once so numba's cache is warm."""

from pathlib import Path

import pytest

from asmplan import warmup

ROOT = Path(__file__).resolve().parents[2]


def test_default_sources_exist():
    for source in warmup.DEFAULT_SOURCES:
        assert (ROOT / source).exists(), source


def test_warm_plans_both_turn_models_quietly(capsys):
    warmup.warm([str(ROOT / "examples" / "vacuum_pump")])
    out, err = capsys.readouterr()
    lines = out.splitlines()
    assert len(lines) == 2
    assert "(alternate)" in lines[0] and "(concurrent)" in lines[1]
    assert err == ""  # the steps' progress is shown only on failure


def test_missing_source_is_named():
    with pytest.raises(FileNotFoundError, match="no_such_folder"):
        warmup.warm(["no_such_folder"])


def test_a_bad_source_raises_its_error(tmp_path):
    bad = tmp_path / "assembly.yaml"
    bad.write_text("parts: [a, b]\nagents: 3\n")
    with pytest.raises(ValueError, match="assembly.yaml"):
        warmup.warm([str(bad)])
