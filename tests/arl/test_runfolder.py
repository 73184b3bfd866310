"""A run folder's checkpoint is one unit: a kill at any write resumes to the same run."""

from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from arl import get_config, runfolder, train
from arl.trainer import read_log
from asmplan.cli.app import main
from asp.game.io import save_dag
from tests.arl.graphs import figure4

pytestmark = pytest.mark.usefixtures("deterministic_torch")

CFG = get_config("fast").replace(
    name="kill", n_envs=8, n_steps=8, phase_steps=64, batch_size=64, max_cycles=2
)
WRITES = ("write_bytes", "write_text", "_replace", "_link", "_remove_tree")


class Killed(BaseException):
    """The process died here (not an Exception: nothing may catch it)."""


def _inject(monkeypatch, kill_at: int | None = None) -> list[tuple[str, str]]:
    """Record the run folder's writes as (function, file name); raise :class:`Killed`
    instead of the ``kill_at``-th."""
    calls: list[tuple[str, str]] = []
    for name in WRITES:

        def write(path, *args, _real=getattr(runfolder, name), _name=name, **kwargs):
            calls.append((_name, Path(path).name))
            if len(calls) == kill_at:
                raise Killed(f"killed at write {kill_at} ({_name})")
            return _real(path, *args, **kwargs)

        monkeypatch.setattr(runfolder, name, write)
    return calls


def _restore(monkeypatch) -> None:
    for name in WRITES:
        monkeypatch.setattr(runfolder, name, getattr(runfolder, name).__kwdefaults__["_real"])


def _without_time(cycles):
    return [{k: v for k, v in c.items() if k not in ("wall_s", "elapsed_s")} for c in cycles]


def _tb_steps(run) -> Counter:
    """(run, tag, step) of every scalar TensorBoard holds for the run folder."""
    from tensorboard.backend.event_processing.event_file_loader import EventFileLoader

    steps = Counter()
    for path in sorted((run / "tb").rglob("*tfevents*")):
        for event in EventFileLoader(str(path)).Load():
            for value in event.summary.value:
                steps[path.parent.name, value.tag, event.step] += 1
    return steps


def test_a_kill_at_every_write_resumes_to_the_uninterrupted_run(tmp_path, monkeypatch):
    import arl.plots

    dag = figure4()
    monkeypatch.setattr(arl.plots, "rewards_png", lambda rewards: b"PNG")  # not under test
    reference = tmp_path / "reference"
    writes = _inject(monkeypatch)
    full = train(dag, CFG, seed=2, output=reference)
    _restore(monkeypatch)
    expected_tb = _tb_steps(reference)
    assert expected_tb and max(expected_tb.values()) == 1
    assert {name for name, _ in writes} == set(WRITES)
    # Every write point: the first write of the run, and every write of the last cycle's
    # commit (the same points as the first's, plus the removal of the older checkpoint).
    last_commit = [i for i, call in enumerate(writes) if call == ("write_bytes", "robot.zip")][-1]
    for k in [1, *range(last_commit + 1, len(writes) + 1)]:
        run = tmp_path / f"killed-{k}"
        _inject(monkeypatch, kill_at=k)
        with pytest.raises(Killed):
            train(dag, CFG, seed=2, output=run)
        _restore(monkeypatch)
        if (run / runfolder.POINTER).exists():
            log = read_log(run)  # never models newer than the log: the log names them
            assert len(log["cycles"]) in (1, 2)
            resumed = train(dag, CFG, seed=2, output=run, resume=True)
        else:  # killed before the first commit: nothing to resume, start again
            with pytest.raises(ValueError, match="no log.json"):
                train(dag, CFG, seed=2, output=run, resume=True)
            resumed = train(dag, CFG, seed=2, output=run)
        where = f"kill at write {k} {writes[k - 1]}"
        assert _without_time(resumed.cycles) == _without_time(full.cycles), where
        assert resumed.cycles[-1]["timesteps"] == full.cycles[-1]["timesteps"], where
        assert np.array_equal(resumed.robot_policy, full.robot_policy), where
        assert _without_time(read_log(run)["cycles"]) == _without_time(full.cycles), where
        assert _tb_steps(run) == expected_tb, where  # each step once
        assert [p.name for p in run.glob("checkpoint-*")] == ["checkpoint-000002"], where
        assert not list(run.rglob("*.tmp")), where


def test_a_write_error_leaves_no_half_cycle(tmp_path, monkeypatch):
    run = tmp_path / "run"

    def full_disk(path, data):
        raise OSError(28, "No space left on device", str(path))

    monkeypatch.setattr(runfolder, "write_bytes", full_disk)
    with pytest.raises(OSError, match="No space left"):
        train(figure4(), CFG, seed=0, output=run)
    assert sorted(p.name for p in run.iterdir()) == []  # no tb/, no checkpoint folder


@pytest.mark.parametrize(
    "text, problem",
    [
        ("{", "not valid JSON"),
        ('{"format": "asmplan-arl-run"}', "malformed run log ('seed'"),
        ("[1, 2]", "expected an asmplan-arl-run log"),
    ],
)
def test_a_malformed_log_is_one_line_naming_the_file(tmp_path, capsys, text, problem):
    graph = save_dag(figure4(), tmp_path / "g.json")
    run = tmp_path / "run"
    run.mkdir()
    (run / "log.json").write_text(text)
    for argv in (
        ["train", str(graph), "--output", str(run), "--resume", "--no-progress"],
        ["evaluate", str(graph), "--model", str(run)],
    ):
        with pytest.raises(SystemExit) as exit_info:
            main(argv)
        assert exit_info.value.code == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and str(run / "log.json") in err and problem in err


def test_a_fresh_run_never_deletes_an_existing_one_without_force(tmp_path, capsys):
    """Issue 26 item 6: training without --resume into a run folder is refused, naming the
    folder and both ways on; --force replaces the run."""
    dag = figure4()
    run = tmp_path / "run"
    train(dag, CFG, seed=2, output=run)
    before = (run / runfolder.LOG).read_bytes()
    with pytest.raises(ValueError, match=r"holds a training run .*--resume continues it"):
        train(dag, CFG, seed=3, output=run)
    assert (run / runfolder.LOG).read_bytes() == before  # untouched
    graph = tmp_path / "g.json"
    save_dag(dag, graph)
    with pytest.raises(SystemExit) as info:
        main(["train", str(graph), "--config", "fast", "-o", str(run), "--no-progress"])
    assert info.value.code == 2
    err = capsys.readouterr().err.strip()
    assert "--force replaces it" in err and "\n" not in err
    assert (run / runfolder.LOG).read_bytes() == before
    replaced = train(dag, CFG, seed=3, output=run, force=True)
    assert read_log(run)["seed"] == 3 and len(replaced.cycles) >= 1
