"""Tests of the experiment sweeps (issue 6): tasks, seeds, backends, resume, outputs."""

from __future__ import annotations

import csv
import io
import json
from types import SimpleNamespace

import numpy as np
import pytest
from typer.testing import CliRunner

from arl.plots import moving_average
from asmplan.experiments import tasks as tasks_module
from asmplan.experiments.paper_values import (
    PAPER_TABLE3,
    PAPER_TABLE4,
    PAPER_TABLE4_QUOTED,
    paper_table3_row,
    paper_table4_row,
)
from asmplan.experiments.runner import FIGURE11, FIGURE12, FIGURE13, run_experiment, task_path
from asmplan.experiments.tables import PAPER_COLUMNS
from asmplan.experiments.tasks import (
    TABLE3_CONFIGS,
    GraphConfig,
    ResultRow,
    TaskResult,
    TaskSpec,
    make_specs,
    run_task,
)

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _text(path) -> str:
    return path.read_text(encoding="utf-8")


def comparable(report) -> list[dict]:
    return [row.comparable() for row in report.rows]


# ----------------------------------------------------------------------------- paper values


def test_paper_table3_values():
    got = {(r.label): (r.tct, r.wcpl, r.max_random, r.avg_random, r.rr) for r in PAPER_TABLE3}
    assert got == {
        "4/10": (1, 4, 5, 3.86, 0.879),
        "10/4": (2, 7, 8, 4.57, 0.942),
        "10/10": (2, 9, 11, 8.18, 0.934),
        "15/10": (5, 10, 12, 8.18, 0.933),
        "20/10": (4, 11, 18, 10.75, 0.71),
        "20/20": (3, 14, 19, 12.28, 0.85),
    }
    assert [(c.layers, c.max_nodes) for c in TABLE3_CONFIGS] == [
        (r.layers, r.max_nodes) for r in PAPER_TABLE3
    ]
    assert paper_table3_row(15, 10).wcpl == 10
    assert paper_table3_row(3, 3) is None


def test_paper_table4_values_and_quoted_means():
    assert [r.trial for r in PAPER_TABLE4] == list(range(1, 11))
    assert [r.nodes for r in PAPER_TABLE4] == [76, 70, 59, 56, 62, 64, 73, 69, 77, 68]
    assert [r.tct for r in PAPER_TABLE4] == [5, 6, 2, 4, 3, 6, 3, 4, 6, 5]
    assert [r.wcpl for r in PAPER_TABLE4] == [11, 17, 11, 8, 5, 10, 16, 15, 13, 11]
    assert paper_table4_row(5).rr == pytest.approx(0.283)
    assert paper_table4_row(11) is None
    # The averages the paper quotes in section 5.2 follow from its table.
    assert np.mean([r.wcpl for r in PAPER_TABLE4]) == pytest.approx(
        PAPER_TABLE4_QUOTED["mean_wcpl"]
    )
    assert np.mean([r.avg_random for r in PAPER_TABLE4]) == pytest.approx(
        PAPER_TABLE4_QUOTED["mean_avg_random"], abs=0.01
    )


# ------------------------------------------------------------------------------ task specs


def test_task_seeds_are_deterministic_and_distinct():
    specs = make_specs("table3", trials=2, base_seed=7) + make_specs("table4", trials=3)
    assert len(specs) == 6 * 2 + 3
    seeds = [s.seeds for s in specs]
    assert seeds == [s.seeds for s in specs]  # a pure function of the spec
    assert len({s.graph for s in seeds}) == len(specs)
    # Keyed by (experiment, configuration, trial) and the base seed only.
    a = TaskSpec("table4", GraphConfig(20, 10), 2, base_seed=0, solver="exact")
    b = TaskSpec("table4", GraphConfig(20, 10), 2, base_seed=0, solver="both", config="fast")
    assert a.seeds == b.seeds
    assert a.seeds != TaskSpec("table4", GraphConfig(20, 10), 2, base_seed=1).seeds
    assert a.seeds != TaskSpec("table3", GraphConfig(20, 10), 2, base_seed=0).seeds


def test_spec_and_result_round_trip():
    spec = TaskSpec("table4", GraphConfig(20, 10), 3, base_seed=5, solver="exact", n_games=50)
    assert TaskSpec.from_dict(json.loads(json.dumps(spec.to_dict()))) == spec
    result = run_task(spec)
    again = TaskResult.from_dict(json.loads(json.dumps(result.to_dict())))
    assert again.spec == spec and again.rows == result.rows
    assert spec.task_id == "table4-L20-M10-A4-t03"


@pytest.mark.parametrize(
    "kwargs",
    [
        {"experiment": "table5"},
        {"trial": 0},
        {"base_seed": -1},
        {"solver": "greedy"},
        {"n_games": 0},
    ],
)
def test_bad_specs_raise_value_error(kwargs):
    base = {"experiment": "table4", "graph": GraphConfig(20, 10), "trial": 1}
    with pytest.raises(ValueError):
        TaskSpec(**{**base, **kwargs})


def test_exact_task_is_certified():
    result = run_task(TaskSpec("table4", GraphConfig(20, 10), 1, solver="exact", n_games=200))
    (row,) = result.rows
    assert row.solver == "exact"
    assert row.wcpl == row.minimax == row.certified_wcpl == row.max_random
    assert row.robust_optimal and row.rr == 1.0 and row.rr_certified == 1.0
    assert row.tct <= row.avg_random <= row.max_random
    assert row.adversarial_tax == pytest.approx(row.minimax / row.tct)
    assert result.episode_rewards is None


# ----------------------------------------------------------------- sweeps, resume, outputs


@pytest.fixture(scope="module")
def serial_sweep(tmp_path_factory):
    out = tmp_path_factory.mktemp("t4")
    report = run_experiment(
        "table4", out, trials=3, solver="exact", workers=1, n_games=200, progress=False
    )
    return out, report


def test_sweep_writes_tables(serial_sweep):
    out, report = serial_sweep
    assert report.ran == 3 and report.resumed == 0 and len(report.rows) == 3
    with open(out / "results.csv", newline="") as handle:
        reader = csv.DictReader(handle)
        assert reader.fieldnames == ResultRow.field_names()
        rows = list(reader)
    assert [int(r["trial"]) for r in rows] == [1, 2, 3]
    header = (out / "results.md").read_text().splitlines()[0]
    cells = [c.strip() for c in header.strip("|").split("|")]
    paper = [name for name, _ in PAPER_COLUMNS["table4"]]
    assert cells[: len(paper)] == ["Trial", "Total Nodes", "TCT", "WCPL", "Avg Random Length", "RR"]
    for extra in ("W*", "Certified WCPL", "RR certified", "Adversarial tax W*/TCT", "Time (s)"):
        assert extra in cells
    assert len((out / "results.md").read_text().splitlines()) == 2 + 3


def test_sweep_writes_figures_and_summary(serial_sweep):
    out, _ = serial_sweep
    for name in (FIGURE12, FIGURE13):
        data = (out / name).read_bytes()
        assert data.startswith(PNG_MAGIC) and len(data) > 10_000
    assert not (out / FIGURE11).exists()  # no ARL run, no training curves
    summary = (out / "summary.md").read_text()
    assert "published numbers" in summary and "62.6%" in summary  # paper's trial 1 RR
    assert "100% by construction" in summary


def test_resume_skips_finished_tasks(serial_sweep, tmp_path):
    out, first = serial_sweep
    stamps = {p.name: p.stat().st_mtime_ns for p in (out / "tasks").iterdir()}
    again = run_experiment(
        "table4", out, trials=3, solver="exact", workers=1, n_games=200, progress=False
    )
    assert again.ran == 0 and again.resumed == 3
    assert comparable(again) == comparable(first)
    assert {p.name: p.stat().st_mtime_ns for p in (out / "tasks").iterdir()} == stamps
    # One more trial runs one task; a missing task file is run again.
    spec = make_specs("table4", trials=1, solver="exact", n_games=200)[0]
    task_path(out, spec).unlink()
    more = run_experiment(
        "table4", out, trials=4, solver="exact", workers=1, n_games=200, progress=False
    )
    assert more.ran == 2 and more.resumed == 2
    # A different seed is a different task: nothing is reused (another sweep: --force).
    other = run_experiment(
        "table4",
        out,
        trials=1,
        seed=3,
        solver="exact",
        workers=1,
        n_games=200,
        progress=False,
        force=True,
    )
    assert other.ran == 1


def test_process_pool_matches_serial(serial_sweep, tmp_path):
    _, serial = serial_sweep
    pool = run_experiment(
        "table4", tmp_path, trials=3, solver="exact", workers=2, n_games=200, progress=False
    )
    assert pool.ran == 3
    assert comparable(pool) == comparable(serial)


# ------------------------------------------------------------------------------------ Ray


@pytest.fixture(scope="module")
def ray_instance():
    ray = pytest.importorskip("ray")
    started = not ray.is_initialized()
    if started:
        ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    yield ray
    if started:
        ray.shutdown()


def test_ray_backend_matches_local(ray_instance, serial_sweep, tmp_path):
    _, serial = serial_sweep
    report = run_experiment(
        "table4", tmp_path, trials=3, solver="exact", backend="ray", n_games=200, progress=False
    )
    assert report.ran == 3
    assert comparable(report) == comparable(serial)
    resumed = run_experiment(
        "table4", tmp_path, trials=3, solver="exact", backend="ray", n_games=200, progress=False
    )
    assert resumed.ran == 0


# ----------------------------------------------------------------------- the ARL code path


def fake_train(dag, config="paper", seed=0, **_):
    """A stand-in for arl.train: first-edge policies, deterministic reward curves."""
    from asp.game.solve import certified_worst_case, play

    first = np.where(np.diff(dag.indptr) > 0, dag.indptr[:-1], -1).astype(np.int64)
    _, wcpl = play(dag, first, first)
    rng = np.random.default_rng(seed)
    return SimpleNamespace(
        robot_policy=first,
        human_policy=first,
        cycles=[{"cycle": 1, "timesteps": 4096}],
        episode_rewards={
            "robot": rng.normal(5, 1, 300).tolist(),
            "human": rng.normal(6, 1, 300).tolist(),
        },
        wall_s=0.01,
        converged=True,
        wcpl=wcpl,
        certified_wcpl=certified_worst_case(dag, first),
    )


def test_arl_path_with_a_stand_in_trainer(monkeypatch, tmp_path):
    monkeypatch.setattr(tasks_module, "require_trainer", lambda: fake_train)
    monkeypatch.setattr("asmplan.experiments.runner.require_trainer", lambda: fake_train)
    report = run_experiment(
        "table3",
        tmp_path,
        trials=1,
        solver="both",
        config="fast",
        workers=1,
        n_games=200,
        progress=False,
    )
    assert len(report.rows) == 2 * 6
    for result in report.results:
        arl_row, exact_row = result.rows
        assert (arl_row.solver, exact_row.solver) == ("arl", "exact")
        assert arl_row.certified_wcpl >= exact_row.minimax
        assert arl_row.wcpl <= arl_row.certified_wcpl
        assert arl_row.rr_certified == 1.0 and arl_row.timesteps == 4096
        assert len(result.episode_rewards["robot"]) == 300
    data = (tmp_path / FIGURE11).read_bytes()
    assert data.startswith(PNG_MAGIC) and len(data) > 10_000
    assert "ARL's learned-vs-learned WCPL" in (tmp_path / "summary.md").read_text()


@pytest.mark.parametrize(
    "change, flag",
    [
        ({"solver": "exact"}, "--solver both -> exact"),
        ({"config": "paper"}, "--config fast -> paper"),
        ({"seed": 5}, "--seed 0 -> 5"),
        ({"n_games": 100}, "--games 200 -> 100"),
    ],
)
def test_another_sweep_is_refused_and_force_replaces_it(monkeypatch, tmp_path, change, flag):
    """Issue 26 item 6: a re-run with another --solver/--config/--seed/--games never
    overwrites finished results silently, and never leaves a figure of the earlier sweep."""
    monkeypatch.setattr(tasks_module, "require_trainer", lambda: fake_train)
    monkeypatch.setattr("asmplan.experiments.runner.require_trainer", lambda: fake_train)
    first = {"solver": "both", "config": "fast", "seed": 0, "n_games": 200}
    options = {"trials": 2, "workers": 1, "progress": False}
    run_experiment("table4", tmp_path, **first, **options)
    before = {p: p.read_bytes() for p in sorted(tmp_path.rglob("*")) if p.is_file()}
    assert tmp_path / FIGURE11 in before

    with pytest.raises(ValueError, match="another sweep") as refused:
        run_experiment("table4", tmp_path, **{**first, **change}, **options)
    message = str(refused.value)
    assert "\n" not in message and str(tmp_path) in message and "--force" in message
    assert flag in message
    assert {p: p.read_bytes() for p in sorted(tmp_path.rglob("*")) if p.is_file()} == before

    again = run_experiment("table4", tmp_path, **{**first, **change}, **options, force=True)
    assert again.ran == 2 and again.resumed == 0
    held = [json.loads(p.read_text())["spec"] for p in sorted((tmp_path / "tasks").iterdir())]
    assert len(held) == 2
    assert all(TaskSpec.from_dict(h) == r.spec for h, r in zip(held, again.results, strict=True))
    solvers = {r["solver"] for r in csv.DictReader(io.StringIO(_text(tmp_path / "results.csv")))}
    assert solvers == ({"exact"} if change.get("solver") == "exact" else {"arl", "exact"})
    # Figure 11 is there exactly when the results beside it hold an ARL run.
    assert (tmp_path / FIGURE11).exists() == ("arl" in solvers)
    # More trials of the same sweep are no other sweep.
    more = run_experiment("table4", tmp_path, **{**first, **change}, **{**options, "trials": 3})
    assert more.ran == 1 and more.resumed == 2


def test_arl_task_with_the_real_trainer():
    pytest.importorskip("arl.trainer")
    spec = TaskSpec("table3", GraphConfig(4, 10), 1, solver="both", config="fast", n_games=200)
    result = run_task(spec)
    arl_row, exact_row = result.rows
    assert arl_row.solver == "arl" and arl_row.cycles >= 1 and arl_row.timesteps > 0
    assert exact_row.minimax <= arl_row.certified_wcpl == arl_row.max_random
    assert arl_row.rr_certified == 1.0
    assert len(result.episode_rewards["robot"]) > 0 and len(result.episode_rewards["human"]) > 0


def test_moving_average():
    x = np.arange(1.0, 7.0)
    assert moving_average(x, 3).tolist() == [1.0, 1.5, 2.0, 3.0, 4.0, 5.0]
    assert moving_average([], 50).size == 0


# ------------------------------------------------------------------------------------ CLI


def test_cli_runs_and_reports_bad_input(tmp_path):
    import asmplan.cli.experiment  # noqa: F401  registers the commands
    from asmplan.cli.app import app

    runner = CliRunner()
    args = [
        "experiment",
        "table4",
        "--solver",
        "exact",
        "--trials",
        "2",
        "--workers",
        "1",
        "--games",
        "100",
        "--no-progress",
        "--output",
        str(tmp_path),
    ]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    assert "2 tasks (2 run, 0 resumed)" in result.output
    assert (tmp_path / "results.csv").is_file()

    bad = runner.invoke(app, [*args[:4], "--trials", "0", "--output", str(tmp_path)])
    assert bad.exit_code == 2
    assert "asmplan: error: trials" in bad.output
    other = runner.invoke(app, [*args[:-2], "--seed", "1", "--output", str(tmp_path)])
    assert other.exit_code == 2, other.output
    assert "another sweep (--seed 0 -> 1)" in other.output and "--force" in other.output
    forced = runner.invoke(app, [*args[:-2], "--seed", "1", "--force", "--output", str(tmp_path)])
    assert forced.exit_code == 0, forced.output
    assert "2 tasks (2 run, 0 resumed)" in forced.output
