"""``asmplan serve``'s inputs: plan folders, plan files, questionnaires; its local default."""

from __future__ import annotations

import inspect
import json

import pytest

from asmplan.cli.serve import load_source, read_questionnaire, serve_command
from asmplan.planfile import write_plan
from tests.asmplan.plans import cell_plan


def test_load_source_reads_plan_folders_and_files(tmp_path):
    doc = cell_plan()
    write_plan(tmp_path / "plan.json", doc)
    assert load_source(tmp_path) == json.loads((tmp_path / "plan.json").read_text())
    assert load_source(tmp_path / "plan.json")["assembly"] == "cell"
    with pytest.raises(FileNotFoundError, match="no such file"):
        load_source(tmp_path / "missing")


def test_questionnaire_file(tmp_path):
    good = tmp_path / "q.json"
    good.write_text(json.dumps([{"id": "trust", "text": "Trust?", "scale": [1, 7]}]))
    assert read_questionnaire(good)[0]["scale"] == [1, 7]
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"id": "x"}))
    with pytest.raises(ValueError, match="expected a list"):
        read_questionnaire(bad)
    assert read_questionnaire(None) is None


def test_binds_local_by_default():
    host = inspect.signature(serve_command).parameters["host"].default
    assert host.default == "127.0.0.1"


def test_load_source_plans_an_assembly_in_its_turn_model(tmp_path):
    """An assembly given to ``serve`` is planned in the spec's turn model or ``--turn-model``."""
    import yaml

    from tests.asmplan.plans import CHOICES

    (tmp_path / "assembly.yaml").write_text(yaml.safe_dump({**CHOICES, "turn_model": "concurrent"}))
    doc = load_source(tmp_path)
    assert doc["turn_model"] == doc["policy"]["turn_model"] == "concurrent"
    assert [r["bound"] for r in doc["robustness"]] == [12, 14, 15, 15]
    assert load_source(tmp_path, "alternate")["turn_model"] == "alternate"
