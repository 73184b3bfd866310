"""asp.atomic.OutputSet: asmplan deletes only what its own manifest names (issue 26, items 4
and 5), and a kill at any write point leaves a folder the next run cleans up."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from asp import atomic
from asp.atomic import MANIFEST, ForeignFilesError, OutputSet, check_output_folder


def names(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def one_run(folder: Path, files: dict[str, bytes], *, force: bool = False) -> None:
    with OutputSet(folder, force=force) as out:
        for name, data in files.items():
            out.write_bytes(name, data)


def test_a_foreign_manifest_never_causes_a_deletion(tmp_path):
    (tmp_path / "thesis.tex").write_text("keep")
    foreign = json.dumps({"format": "other/1", "files": ["thesis.tex"]})
    (tmp_path / MANIFEST).write_text(foreign)
    for force in (False, True):  # --force would overwrite the user's manifest.json: refused
        with pytest.raises(ForeignFilesError, match=f"{tmp_path}: holds a 'manifest.json'"):
            one_run(tmp_path, {"plan.json": b"{}"}, force=force)
    assert (tmp_path / "thesis.tex").read_text() == "keep"
    assert (tmp_path / MANIFEST).read_text() == foreign
    assert names(tmp_path) == [MANIFEST, "thesis.tex"]


@pytest.mark.parametrize(
    "doc",
    [
        {"format": "asmplan-manifest/2", "files": ["thesis.tex"]},  # another version
        {"files": ["thesis.tex"]},
        ["thesis.tex"],
        "thesis.tex",
    ],
)
def test_only_asmplans_own_format_and_version_counts(tmp_path, doc):
    (tmp_path / "thesis.tex").write_text("keep")
    (tmp_path / MANIFEST).write_text(json.dumps(doc))
    with pytest.raises(ForeignFilesError):
        check_output_folder(tmp_path, force=True)
    assert atomic.owned_files(tmp_path) == []
    assert (tmp_path / "thesis.tex").read_text() == "keep"


def test_a_folder_with_other_files_is_refused_naming_the_folder_and_a_file(tmp_path):
    (tmp_path / "notes.txt").write_text("mine")
    (tmp_path / "b.txt").write_text("mine too")
    with pytest.raises(ForeignFilesError) as caught:
        one_run(tmp_path, {"plan.json": b"{}"})
    message = str(caught.value)
    assert "\n" not in message
    assert message.startswith(f"{tmp_path}: holds 'b.txt' and 1 more, not written by asmplan")
    assert "--force" in message
    assert names(tmp_path) == ["b.txt", "notes.txt"]


def test_force_writes_beside_other_files_and_never_deletes_them(tmp_path):
    """robustness.png / gantt_*.png this run did not write and no manifest of ours names
    (e.g. the user's own, or from a folder written before manifests) stay."""
    for name in ("robustness.png", "gantt_worst.png", "notes.txt"):
        (tmp_path / name).write_bytes(b"theirs")
    one_run(tmp_path, {"plan.json": b"{}", "dag.png": b"png"}, force=True)
    one_run(tmp_path, {"plan.json": b"{}"}, force=True)
    assert names(tmp_path) == sorted(
        [MANIFEST, "plan.json", "robustness.png", "gantt_worst.png", "notes.txt"]
    )
    assert (tmp_path / "robustness.png").read_bytes() == b"theirs"
    assert json.loads((tmp_path / MANIFEST).read_text())["files"] == ["plan.json"]


def test_a_rerun_into_its_own_folder_needs_no_force(tmp_path):
    one_run(tmp_path, {"plan.json": b"1", "robustness.png": b"1", "gantt_worst.png": b"1"})
    one_run(tmp_path, {"plan.json": b"2", "dag.png": b"2"})
    assert names(tmp_path) == sorted([MANIFEST, "dag.png", "plan.json"])
    doc = json.loads((tmp_path / MANIFEST).read_text())
    assert doc == {"format": "asmplan-manifest/1", "files": ["plan.json", "dag.png"]}


class Killed(Exception):
    pass


def kill_points(folder: Path, previous: dict[str, bytes], new: dict[str, bytes]) -> int:
    """The number of file operations (renames, deletions) a run of ``new`` over
    ``previous`` makes in ``folder``."""
    one_run(folder, previous)
    count = 0
    replace, unlink = os.replace, Path.unlink

    def counting_replace(src, dst):
        nonlocal count
        count += 1
        replace(src, dst)

    def counting_unlink(self, missing_ok=False):
        nonlocal count
        count += 1
        unlink(self, missing_ok=missing_ok)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(atomic.os, "replace", counting_replace)
        patch.setattr(atomic.Path, "unlink", counting_unlink)
        one_run(folder, new)
    return count


def run_killed_at(folder: Path, new: dict[str, bytes], point: int) -> None:
    """Run ``new`` into ``folder`` in a child process killed (``os._exit``: no clean-up, as
    SIGKILL) just before its ``point``-th file operation."""
    pid = os.fork()
    if pid == 0:  # the child: count the operations, die at the chosen one
        count = 0
        replace, unlink = os.replace, Path.unlink

        def maybe_die():
            nonlocal count
            count += 1
            if count == point:
                os._exit(9)

        def dying_replace(src, dst):
            maybe_die()
            replace(src, dst)

        def dying_unlink(self, missing_ok=False):
            maybe_die()
            unlink(self, missing_ok=missing_ok)

        atomic.os.replace = dying_replace
        atomic.Path.unlink = dying_unlink
        try:
            one_run(folder, new)
        finally:
            os._exit(0)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 9, f"the child was not killed at {point}"


def test_a_kill_at_any_write_point_never_leaves_a_manifest_naming_deleted_files(tmp_path):
    previous = {"plan.json": b"old", "dag.png": b"old", "robustness.png": b"old"}
    new = {"plan.json": b"new", "dag.png": b"new", "report.html": b"new"}
    points = kill_points(tmp_path / "count", previous, new)
    assert points >= 5
    for point in range(1, points + 1):
        folder = tmp_path / f"kill{point}"
        one_run(folder, previous)
        run_killed_at(folder, new, point)
        doc = json.loads((folder / MANIFEST).read_text())
        missing = [n for n in doc["files"] if not (folder / n).is_file()]
        assert not missing, f"killed at {point}: the manifest names deleted {missing}"
        unnamed = set(names(folder)) - {MANIFEST, *atomic.owned_files(folder)}
        assert not [n for n in unnamed if not n.endswith(".tmp")], f"killed at {point}"
        if doc["files"]:  # a complete run: one run's bytes, never a mix
            assert {(folder / n).read_bytes() for n in doc["files"]} in ({b"old"}, {b"new"})
        one_run(folder, new)  # the next run needs no --force and cleans up
        assert names(folder) == sorted([MANIFEST, *new]), f"killed at {point}"


def test_a_full_disk_names_the_file_and_leaves_no_temporary(tmp_path, monkeypatch):
    """The reliability probe (issue 26): a write refused by a full disk said only "no space
    left on device" (a write's error carries no file name); it names the target now."""

    def full(fd):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(atomic.os, "fsync", full)
    with pytest.raises(OSError) as info:
        atomic.write_bytes(tmp_path / "plan.json", b"{}")
    assert info.value.errno == 28 and info.value.filename == str(tmp_path / "plan.json")
    assert list(tmp_path.iterdir()) == []
