"""STEP files OCCT cannot read whole: each named with what is wrong, stdout kept clean."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from cad.errors import GeometryError
from cad.readers import MESH_SUFFIXES, READERS, SCENE_SUFFIXES, reader_for
from cad.scene import read_scene

pytest.importorskip("cascadio")

DATA = Path(__file__).parent / "data"
GOOD = (DATA / "two_boxes.step").read_bytes()


def _drop_entity(data: bytes, entity: bytes) -> bytes:
    return b"".join(line for line in data.splitlines(True) if not line.startswith(entity))


DAMAGED = {
    # name: (bytes of the file, what the message must say)
    "truncated": (GOOD[: len(GOOD) // 2], "is truncated: it stops at line"),
    "garbage": (bytes(range(7, 250)) * 8, "is not a STEP file: it does not begin with"),
    "text": (b"solid cube\nfacet normal 0 0 1\n", "it begins 'solid cube"),
    "header only": (GOOD[: GOOD.index(b"DATA;")], "holds a header but no DATA section"),
    "empty data": (GOOD[: GOOD.index(b"#1 =")] + b"ENDSEC;\nEND-ISO-10303-21;\n", "empty DATA"),
    "lost body (undefined entity)": (
        _drop_entity(GOOD, b"#387 = "),
        "defines 2 solids and OCCT read 1; entities refer to #387",
    ),
    "lost body (unknown type)": (
        GOOD.replace(b"#387 = CLOSED_SHELL", b"#387 = CLOSED_SHELX"),
        "defines 2 solids and OCCT read 1",
    ),
}


@pytest.mark.parametrize("case", sorted(DAMAGED))
def test_a_damaged_step_names_the_file_and_the_damage(tmp_path, case):
    data, said = DAMAGED[case]
    path = tmp_path / "damaged.step"
    path.write_bytes(data)
    with pytest.raises(GeometryError) as info:
        read_scene(path)
    message = str(info.value)
    assert said in message and str(path) in message
    assert "converted.glb" not in message and "\n" not in message


def test_the_whole_file_reads_without_a_message(recwarn):
    assert len(read_scene(DATA / "two_boxes.step").ids) == 2
    assert not [w for w in recwarn if "OCCT" in str(w.message)]


def test_occt_messages_stay_off_stdout_of_relations_json(tmp_path):
    """OCCT prints a syntax error it recovers from on fd 1; the JSON on stdout still parses
    and the message reaches stderr as one warning."""
    lines = GOOD.splitlines(True)
    k = next(i for i, line in enumerate(lines) if line.startswith(b"#388 = "))
    lines[k] = b"#388 = ADVANCED_FACE(\n"
    path = tmp_path / "recovered.step"
    path.write_bytes(b"".join(lines))
    run = subprocess.run(
        [str(Path(sys.executable).parent / "asmplan"), "relations", str(path), "--format", "json"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr
    assert len(json.loads(run.stdout)["parts"]) == 2
    assert "OCCT: ERR StepFile : Incorrect Syntax" in run.stderr


def test_every_suffix_has_one_reader():
    assert set(MESH_SUFFIXES) == set(READERS) and set(SCENE_SUFFIXES) <= set(MESH_SUFFIXES)
    assert reader_for("a.STP") is reader_for("b.step") and reader_for("x.glb").scene
    assert reader_for("p.obj").options == {"split_objects": True}
    assert not reader_for("p.stl").declares_unit and reader_for("s.3mf").default_unit == "mm"
