"""The bundled study example, ``examples/finger_box``: real geometry where the person's
choices matter, and a fixed-plan robot that loses time to a deviating person while the
robust one does not."""

from __future__ import annotations

from pathlib import Path

import pytest
import trimesh

from asmplan.advisor import Advisor
from asmplan.study.config import load_study
from asmplan.study.plans import study_plans

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "finger_box"
PID = "finger-box-concurrent"

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def variants():
    return study_plans(load_study(EXAMPLE / "study.yaml"), say=lambda _: None)


def test_meshes_are_closed_and_the_fingers_interlock():
    from asmplan import pipeline
    from asp.game.plan import relations_summary

    for path in sorted((EXAMPLE / "meshes").glob("*.stl")):
        assert trimesh.load(path).is_watertight, path.name
    summary = relations_summary(pipeline.load(EXAMPLE).relations)
    free = {row["part"]: row["free"] for row in summary}
    assert free["front"] == ["-y"] and free["left"] == ["-x"]  # slide in from outside only
    assert free["gusset_fl"] == []  # boxed in by two walls, the base and the lid


def test_choices_matter(variants):
    """States of the robust plan where the person's options lead to different worst cases
    (counted over the options the advisor shows, at every state the plan reaches)."""
    plan = variants[(PID, "robust")]
    states = _states_with_choices(plan)
    assert states >= 5, states


def test_the_fixed_plan_loses_time_the_robust_plan_does_not(variants):
    robust, fixed = variants[(PID, "robust")], variants[(PID, "schedule")]
    r = {x["k"]: x["bound"] for x in robust["condition"]["worst_case"]}
    f = {x["k"]: x["bound"] for x in fixed["condition"]["worst_case"]}
    assert r[0] == f[0]  # the same makespan when the person follows
    assert r[None] - r[0] <= 3  # robust: 49 -> 52 s against any person
    assert f[None] - f[0] >= 15  # the CP-SAT schedule: 49 -> 69 s
    assert Advisor(fixed).advice().total_bound == f[max(k for k in f if k is not None)]


def _states_with_choices(plan: dict) -> int:
    """Walk every state the policy reaches (each option, each completion) and count those
    where the options shown have more than one worst case."""
    seen, count = set(), 0
    stack: list[list[dict]] = [[]]
    while stack and len(seen) < 5000:
        events = stack.pop()
        advice = Advisor.replay(plan, events).advice()
        running = tuple(sorted((r["agent"], r["operation"]) for r in advice.running))
        key = (advice.state, tuple(sorted(advice.done)), advice.elapsed, running)
        if key in seen or advice.finished:
            continue
        seen.add(key)
        count += len({round(o["worst"], 6) for o in advice.options}) > 1
        for o in advice.options:
            ev = {"kind": "started", "operation": o["operation"], "agent": o["agent"]}
            stack.append([*events, ev])
        for f in advice.finishes:
            ev = {"kind": "finished", "operation": f["operation"], "agent": f["agent"]}
            stack.append([*events, {**ev, "time": f["time"]}])
    return count
