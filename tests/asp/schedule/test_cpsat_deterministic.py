"""Same input, same plan (issue 26 item 7): CP-SAT stops on its deterministic time, so a
search cut short by its limit ends at the same schedule whatever the load; the wall clock
is only a safety net, recorded among the timings."""

from __future__ import annotations

import itertools
import json
import multiprocessing
import os
from contextlib import contextmanager
from types import SimpleNamespace

import numpy as np
import pytest

import asp.schedule.assembly_makespan as assembly_makespan
import asp.schedule.makespan as makespan
from asp.schedule import cpsat
from asp.schedule.makespan import ScheduleProblem, Task, min_makespan
from tests.conftest import REPO

TIMINGS = ("wall_s", "improvements", "wall_stop")


def hard_job(n: int = 40, seed: int = 1) -> ScheduleProblem:
    """A random job of ``n`` tasks on three agents that CP-SAT does not prove in seconds."""
    rng = np.random.default_rng(seed)
    tasks = []
    for i in range(n):
        modes = tuple(
            (a, float(rng.integers(3, 30))) for a in ("r1", "r2", "h") if rng.random() < 0.8
        )
        tasks.append(Task(f"t{i}", modes or (("h", 5.0),)))
    prec = tuple((i, j) for i in range(n) for j in range(i + 1, n) if rng.random() < 0.04)
    return ScheduleProblem("hard", tuple(tasks), prec)


def without_timings(result) -> str:
    doc = {k: v for k, v in result.to_dict().items() if k not in TIMINGS}
    return json.dumps(doc, sort_keys=True)


def _spin() -> None:
    while True:
        pass


@contextmanager
def half_a_core():
    """This process and a busy one share one core: CP-SAT gets about half of it."""
    if not hasattr(os, "sched_setaffinity"):
        pytest.skip("needs sched_setaffinity")
    before = os.sched_getaffinity(0)
    core = min(before)
    hog = multiprocessing.get_context("fork").Process(target=_spin, daemon=True)
    os.sched_setaffinity(0, {core})
    try:
        hog.start()
        os.sched_setaffinity(hog.pid, {core})
        yield
    finally:
        hog.kill()
        hog.join()
        os.sched_setaffinity(0, before)


def test_a_search_cut_short_ends_at_the_same_schedule_under_load():
    problem = hard_job()
    alone = min_makespan(problem, time_limit=0.5)
    assert alone.status == "FEASIBLE"  # the limit, not a proof, ended it
    with half_a_core():
        loaded = min_makespan(problem, time_limit=0.5)
    assert without_timings(loaded) == without_timings(alone)
    assert "wall_stop" not in alone.detail and "wall_stop" not in loaded.detail


def test_the_plan_document_is_the_same_bytes_on_a_slow_machine(tmp_path, monkeypatch):
    from asmplan import pipeline

    assembly = pipeline.load(REPO / "examples" / "finger_box")  # 8 solves, 11 cuts to its optimum
    options = {"time_limit": 2.0}
    pipeline.write_plan(pipeline.plan(assembly, **options), tmp_path / "a")
    with monkeypatch.context() as patch:  # the replay loop's clock: 0.5 s a reading
        ticks = itertools.count()
        clock = SimpleNamespace(perf_counter=lambda: 0.5 * next(ticks))
        patch.setattr(makespan, "time", clock)
        patch.setattr(assembly_makespan, "time", clock)
        slow = pipeline.plan(assembly, **options)
    pipeline.write_plan(slow, tmp_path / "b")
    first = (tmp_path / "a" / "plan.json").read_bytes()
    assert (tmp_path / "b" / "plan.json").read_bytes() == first
    assert json.loads(first)["schedule"]["status"] == "OPTIMAL"
    assert "wall_stop" not in json.loads((tmp_path / "b" / "timings.json").read_text())["schedule"]


def test_the_wall_clock_safety_net_stops_and_is_recorded_among_the_timings(monkeypatch):
    monkeypatch.setattr(cpsat, "WALL_SAFETY_FACTOR", 0.0)
    monkeypatch.setattr(cpsat, "WALL_SAFETY_S", 0.2)
    result = min_makespan(hard_job(), time_limit=1e4)  # the net (0.2 s) ends it
    assert result.status == "FEASIBLE" and result.detail["wall_stop"] == pytest.approx(0.2)
    assert "within" in result.detail["status_note"]
    from asmplan.planfile import TIMING_KEYS

    assert "wall_stop" in TIMING_KEYS["schedule"]


def test_limits_are_search_seconds_of_deterministic_time():
    solver = cpsat.new_solver(2.0, 1, 0)
    assert solver.parameters.max_deterministic_time == pytest.approx(
        2.0 * cpsat.DETERMINISTIC_PER_SECOND
    )
    assert solver.parameters.max_time_in_seconds == cpsat.wall_safety(2.0)
    assert solver.parameters.num_workers == 1 and solver.parameters.random_seed == 0
    assert cpsat.search_seconds(cpsat.DETERMINISTIC_PER_SECOND) == pytest.approx(1.0)
