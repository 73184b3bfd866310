"""``asmplan plan --output``: the outputs of one run are one unit (issue 14, item 4)."""

from __future__ import annotations

import json
import os

import pytest
from typer.testing import CliRunner

from asmplan import pipeline
from asmplan.cli import app
from asp.atomic import MANIFEST, OutputSet, remove_stale_temps, write_text
from tests.conftest import REPO

PUMP = REPO / "examples" / "vacuum_pump"


@pytest.fixture(scope="module")
def pump_plan():
    return pipeline.plan(PUMP, time_limit=20)


def dead_pid() -> int:
    """A process id that no process has now."""
    pid = 2**22 + 12345
    while True:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return pid
        except PermissionError:
            pass
        pid += 1


def test_a_complete_run_names_its_files_last(pump_plan, tmp_path):
    written = pipeline.write_plan(pump_plan, tmp_path)
    files = ["plan.json", "timings.json", "dag.png", "report.html"]
    assert [p.name for p in written] == files
    manifest = json.loads((tmp_path / MANIFEST).read_text())
    assert manifest == {"format": "asmplan-manifest/1", "files": files}
    assert json.loads((tmp_path / "plan.json").read_text()) == json.loads(
        json.dumps(pump_plan.to_dict())
    )


def test_a_concurrent_run_writes_its_own_game_s_figures_only(tmp_path):
    """Issue 23 item 4: a concurrent plan has no alternating game, so no ``dag.png`` (whose
    title gave that game's TCT and W* beside the concurrent metrics); its figures are the
    curve and the two timelines, named by the manifest, the report last."""
    result = pipeline.plan(PUMP, turn_model="concurrent", time_limit=20, keep_game=False)
    written = pipeline.write_plan(result, tmp_path)
    files = ["plan.json", "timings.json", "robustness.png", "gantt_cooperative.png"]
    files += ["gantt_worst.png", "report.html"]
    assert [p.name for p in written] == files
    assert json.loads((tmp_path / MANIFEST).read_text())["files"] == files


def test_a_failure_mid_write_leaves_no_mixed_folder(pump_plan, tmp_path, monkeypatch):
    """A new plan.json never sits beside an old dag.png: the write fails after plan.json."""
    pipeline.write_plan(pump_plan, tmp_path)
    (tmp_path / "mine.txt").write_text("the user's own file")
    old_png = (tmp_path / "dag.png").read_bytes()

    import asmplan.report.plot as plot

    def killed(*args, **kwargs):
        assert (tmp_path / "plan.json").is_file()  # the new plan.json is written by now
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(plot, "draw_dag", killed)
    with pytest.raises(OSError, match="No space"):
        pipeline.write_plan(pump_plan, tmp_path, force=True)
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["mine.txt"], "no half run, no old run, the user's file kept"
    assert old_png  # the previous picture existed before the failed run

    monkeypatch.undo()
    pipeline.write_plan(pump_plan, tmp_path, force=True)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ["mine.txt", "plan.json", "timings.json", "dag.png", "report.html", MANIFEST]
    )


def test_temp_files_of_a_killed_write_are_gone_when_the_next_run_starts(pump_plan, tmp_path):
    stale = tmp_path / f".plan.json.{dead_pid()}.abc123.tmp"
    stale.write_text('{"half": ')
    live = tmp_path / f".plan.json.{os.getpid()}.def456.tmp"  # a writer still running
    live.write_text("")
    pipeline.write_plan(pump_plan, tmp_path)
    assert not stale.exists() and live.exists()
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp") and p != live]


def test_a_kill_inside_an_atomic_write_leaves_a_temp_file_the_next_run_removes(
    tmp_path, monkeypatch
):
    """The kill is injected: ``os.replace`` never runs, as when the process dies."""
    import asp.atomic as atomic

    def die(*args):
        raise SystemExit("killed")

    monkeypatch.setattr(atomic.Path, "unlink", lambda self, missing_ok=False: None)
    monkeypatch.setattr(atomic.os, "replace", die)
    with pytest.raises(SystemExit):
        write_text(tmp_path / "plan.json", "{}")
    monkeypatch.undo()
    leftovers = [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]
    assert len(leftovers) == 1 and str(os.getpid()) in leftovers[0].name
    # The dead process's pid is in the name; pretend it has ended.
    renamed = leftovers[0].with_name(leftovers[0].name.replace(str(os.getpid()), str(dead_pid())))
    leftovers[0].rename(renamed)
    assert remove_stale_temps(tmp_path) == [renamed]
    with OutputSet(tmp_path) as out:
        out.write_text("plan.json", "{}")
    assert sorted(p.name for p in tmp_path.iterdir()) == [MANIFEST, "plan.json"]


def test_a_rerun_that_writes_fewer_files_removes_its_own_old_ones(tmp_path):
    with OutputSet(tmp_path) as out:
        out.write_text("plan.json", "{}")
        out.write_bytes("dag.png", b"old")
    with OutputSet(tmp_path) as out:
        out.write_text("plan.json", "{}")  # a run too large to draw writes no dag.png
    assert sorted(p.name for p in tmp_path.iterdir()) == [MANIFEST, "plan.json"]


def test_bad_input_creates_no_output_folder(tmp_path):
    target = tmp_path / "out"
    result = CliRunner().invoke(app, ["plan", str(tmp_path / "missing"), "--output", str(target)])
    assert result.exit_code == 2
    assert not target.exists()


def test_make_demo_path(tmp_path):
    """``make demo`` runs exactly this."""
    result = CliRunner().invoke(app, ["plan", str(PUMP), "--output", str(tmp_path / "pump")])
    assert result.exit_code == 0, result.output
    assert f"wrote {tmp_path / 'pump' / 'plan.json'} and" in result.output
    assert (tmp_path / "pump" / MANIFEST).is_file()


def test_a_plan_that_lets_its_game_go_writes_the_same_files(pump_plan, tmp_path):
    """``asmplan plan`` lets the game and its solution go once solved (``keep_game=False``,
    less memory for CP-SAT and the files): the same plan.json and dag.png as with them kept."""
    lean = pipeline.plan(PUMP, time_limit=20, keep_game=False)
    assert lean.game is None and lean.solution is None and pump_plan.game is not None
    kept, let_go = pump_plan.to_dict(), lean.to_dict()
    assert {k: v for k, v in kept.items() if k != "schedule"} == {
        k: v for k, v in let_go.items() if k != "schedule"
    }
    assert kept["schedule"]["objective"] == let_go["schedule"]["objective"]
    pipeline.write_plan(pump_plan, tmp_path / "kept")
    pipeline.write_plan(lean, tmp_path / "lean")
    png = [(tmp_path / name / "dag.png").read_bytes() for name in ("kept", "lean")]
    assert png[0] == png[1]


def test_plan_refuses_a_foreign_manifest_and_keeps_the_thesis(tmp_path):
    """Issue 26 item 4: ``echo keep > D/thesis.tex`` and a ``manifest.json`` of another
    format naming it; ``plan -o D`` (with or without --force) refuses and deletes nothing."""
    (tmp_path / "thesis.tex").write_text("keep\n")
    foreign = '{"format": "other/1", "files": ["thesis.tex"]}'
    (tmp_path / MANIFEST).write_text(foreign)
    for extra in ([], ["--force"]):
        result = CliRunner().invoke(app, ["plan", str(PUMP), "-o", str(tmp_path), *extra])
        assert result.exit_code == 2
        assert f"{tmp_path}: holds a 'manifest.json' that is not asmplan's" in result.output
    assert (tmp_path / "thesis.tex").read_text() == "keep\n"
    assert (tmp_path / MANIFEST).read_text() == foreign


def test_plan_refuses_a_folder_of_other_files_unless_forced(tmp_path):
    (tmp_path / "robustness.png").write_bytes(b"mine")  # not written by asmplan
    refused = CliRunner().invoke(app, ["plan", str(PUMP), "-o", str(tmp_path)])
    assert refused.exit_code == 2
    line = refused.output.strip()
    assert "\n" not in line and f"{tmp_path}: holds 'robustness.png'" in line
    forced = CliRunner().invoke(
        app, ["plan", str(PUMP), "-o", str(tmp_path), "--force", "--time-limit", "1"]
    )
    assert forced.exit_code == 0, forced.output
    assert (tmp_path / "robustness.png").read_bytes() == b"mine"
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        [MANIFEST, "plan.json", "timings.json", "dag.png", "report.html", "robustness.png"]
    )


def test_a_sigkill_right_after_step_5_leaves_a_folder_the_next_run_takes(tmp_path):
    """Issue 26 item 5: ``asmplan plan`` killed (SIGKILL) as it prints ``[5/5]``: the
    manifest never names a deleted file, and the next run needs no --force."""
    import signal
    import subprocess
    import sys

    command = [sys.executable, "-c", "from asmplan.cli import main; main()", "plan", str(PUMP)]
    command += ["-o", str(tmp_path), "--time-limit", "1"]
    (tmp_path / "old.png").write_bytes(b"old")  # a file of the previous run, not of this one
    (tmp_path / MANIFEST).write_text(
        json.dumps({"format": "asmplan-manifest/1", "files": ["old.png"]})
    )
    proc = subprocess.Popen(command, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True)
    for line in proc.stderr:
        if line.startswith("[5/5]"):
            proc.send_signal(signal.SIGKILL)
            break
    proc.wait(timeout=120)
    assert proc.returncode == -signal.SIGKILL
    doc = json.loads((tmp_path / MANIFEST).read_text())
    assert all((tmp_path / name).is_file() for name in doc["files"]), doc
    again = CliRunner().invoke(app, ["plan", str(PUMP), "-o", str(tmp_path), "--time-limit", "1"])
    assert again.exit_code == 0, again.output
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        [MANIFEST, "plan.json", "timings.json", "dag.png", "report.html"]
    )
