"""Studies: ``study.yaml``, robot conditions, assignment, the questionnaire's checks, the
study API over real HTTP, and ``asmplan study export``."""

from __future__ import annotations

import csv
import io
import itertools
import json

import httpx
import pytest
import yaml
from hypothesis import given
from hypothesis import strategies as st
from typer.testing import CliRunner

from asmplan.cli import app as cli
from asmplan.study.assignment import blocks, latin_square
from asmplan.study.config import load_study
from asmplan.study.plans import study_plans
from asmplan.study.questionnaire import AnswerError, check_answers
from tests.asmplan.plans import CHOICES
from tests.asmplan.server import running

QUESTIONS = {
    "scales": {"agree5": {"min": 1, "max": 5, "labels": {1: "Disagree", 5: "Agree"}}},
    "items": [
        {"id": "trust", "text": "I trusted the robots.", "scale": "agree5", "required": True},
        {"id": "predictable", "text": "They were predictable.", "scale": "agree5"},
        {"id": "comment", "text": "Anything else?", "scale": "text"},
    ],
}


def write_study(tmp_path, **changes) -> object:
    (tmp_path / "job").mkdir(exist_ok=True)
    (tmp_path / "job" / "assembly.yaml").write_text(
        yaml.safe_dump({**CHOICES, "turn_model": "concurrent"})
    )
    data = {
        "format": "asmplan-study/1",
        "title": "Two robots",
        "consent": "You agree to play two rounds.",
        "plans": [{"source": "job"}],
        "conditions": [
            {"id": "robust", "label": "Robot A", "robot": "robust"},
            {"id": "schedule", "label": "Robot B", "robot": "cp-sat"},
        ],
        "assignment": {"design": "within", "order": "counterbalanced"},
        "questionnaire": QUESTIONS,
        **changes,
    }
    path = tmp_path / "study.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


# --------------------------------------------------------------------------- the file

BAD_FILES = [
    ({"colour": 1}, "unknown key 'colour'"),
    ({"conditions": [{"id": "x", "robot": "kind"}]}, "robot: expected robust, fast-greedy"),
    ({"conditions": [{"id": "x"}, {"id": "x"}]}, "condition 'x' given twice"),
    ({"plans": [{"source": "nowhere"}]}, "no such file or folder"),
    ({"assignment": {"design": "mixed"}}, "design: expected within or between"),
    ({"questionnaire": None}, "expected the questionnaire's items"),
    ({"questionnaire": {"items": [{"id": "a", "text": "A?", "scale": "agree9"}]}}, "unknown scale"),
    ({"questionnaire": {"items": [{"id": "a", "text": "A?", "scale": [5, 1]}]}}, "min < max"),
    ({"realtime": {"speed": 0}}, "speed"),
]


@pytest.mark.parametrize(("change", "message"), BAD_FILES)
def test_bad_study_files_name_the_key(tmp_path, change, message):
    with pytest.raises(ValueError, match=message) as info:
        load_study(write_study(tmp_path, **change))
    assert "study.yaml" in str(info.value)


def test_a_published_scale_loads_from_its_own_file(tmp_path):
    (tmp_path / "scale.yaml").write_text(yaml.safe_dump(QUESTIONS))
    study = load_study(write_study(tmp_path, questionnaire={"file": "scale.yaml"}))
    assert [i.id for i in study.questionnaire] == ["trust", "predictable", "comment"]
    assert study.questionnaire[0].scale.labels == {1: "Disagree", 5: "Agree"}


# --------------------------------------------------------------------------- assignment


@given(st.integers(1, 9))
def test_latin_square_is_balanced(n):
    rows = latin_square(n)
    assert all(sorted(r) == list(range(n)) for r in rows)
    for pos in range(n):  # each item in each position equally often
        counts = [sum(r[pos] == x for r in rows) for x in range(n)]
        assert len(set(counts)) == 1
    pairs = [(r[i], r[i + 1]) for r in rows for i in range(n - 1)]
    for a, b in itertools.permutations(range(n), 2):  # each item follows each other alike
        assert pairs.count((a, b)) == (1 if n % 2 == 0 else 2)


def test_assignment_counterbalanced_and_seeded():
    def of(number, pid="p", **kw):
        args = {"design": "within", "order": "counterbalanced", "plan_order": "fixed"}
        args.update(kw)
        out = blocks(["p1", "p2"], ["a", "b"], seed=3, number=number, participant=pid, **args)
        return [(b["plan"], b["condition"]) for b in out]

    assert of(0) == [("p1", "a"), ("p1", "b"), ("p2", "a"), ("p2", "b")]
    assert of(1) == [("p1", "b"), ("p1", "a"), ("p2", "b"), ("p2", "a")]
    assert of(2) == of(0)
    assert of(0, design="between") == [("p1", "a"), ("p2", "a")]
    assert of(1, design="between") == [("p1", "b"), ("p2", "b")]
    random_one = of(5, "P07", design="between", order="random")
    assert random_one == of(9, "P07", design="between", order="random")  # the id decides
    drawn = {of(0, f"P{k}", order="random")[0][1] for k in range(20)}
    assert drawn == {"a", "b"}


# --------------------------------------------------------------------------- questionnaire


def _items():
    from asmplan.study.config import _questionnaire

    return _questionnaire(QUESTIONS, "q", None)


ANSWERS = [
    ({"trust": 4}, {"trust": 4}, None),
    ({"trust": 4, "predictable": None, "comment": ""}, {"trust": 4}, None),  # missing, not 1
    ({"trust": 4.0}, {"trust": 4}, None),
    ({"trust": 6}, None, "from 1 to 5"),
    ({"trust": 0}, None, "from 1 to 5"),
    ({"trust": 3.5}, None, "whole number"),
    ({"trust": True}, None, "whole number"),
    ({"trust": "4"}, None, "whole number"),
    ({"trust": 4, "comment": 3}, None, "expected text"),
    ({"trust": 4, "comment": "x" * 3000}, None, "over 2000"),
    ({"predictable": 2}, None, "'trust' must be answered"),
    ({"trust": 4, "mood": 1}, None, "unknown questionnaire item 'mood'"),
]


@pytest.mark.parametrize(("answers", "stored", "error"), ANSWERS)
def test_answers_are_checked_and_never_defaulted(answers, stored, error):
    items = _items()
    if error is None:
        assert check_answers(items, answers) == stored
    else:
        with pytest.raises(AnswerError, match=error):
            check_answers(items, answers)


# --------------------------------------------------------------------------- conditions


@pytest.fixture(scope="module")
def two_robots(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("study")
    study = load_study(write_study(tmp))
    return study, study_plans(study, say=lambda _: None)


def test_each_condition_is_its_own_robot(two_robots):
    from asmplan.advisor import Advisor

    _, variants = two_robots
    robust = variants[("choices-concurrent", "robust")]
    fixed = variants[("choices-concurrent", "schedule")]
    assert robust["condition"]["robot"] == "robust" and fixed["condition"]["robot"] == "cp-sat"
    assert robust["minimax"] == robust["robustness"][-2]["bound"]
    # the fixed plan's bound is its certified worst case, worse than the robust one's
    assert fixed["minimax"] > robust["minimax"]
    assert fixed["minimax"] == fixed["condition"]["worst_case"][-2]["bound"]
    assert Advisor(fixed).advice().total_bound == fixed["minimax"]
    assert fixed["robustness"] == robust["robustness"]  # the reference curve stays


# --------------------------------------------------------------------------- over HTTP


def _next(advice: dict, deviate: bool) -> dict:
    """The person's next event: a start (a deviation when ``deviate`` and she may), else the
    cell's next completion."""
    pool = [o for o in advice["options"] if o["deviation"] == deviate]
    if not advice["finishes"]:  # she must start something
        pool = pool or advice["options"]
    if pool:
        o = pool[0]
        ev = {"kind": "started", "operation": o["operation"], "agent": o["agent"]}
        return {**ev, "duration": o["durations"][-1]}
    f = advice["finishes"][0]
    return {"kind": "finished", "operation": f["operation"], "agent": f["agent"], "time": f["time"]}


def _finish(client, sid: str, advice: dict, deviate: bool) -> dict:
    while not advice["finished"]:
        r = client.post(f"/api/sessions/{sid}/events", json=_next(advice, deviate))
        assert r.status_code == 200, r.text
        advice = r.json()
    return advice


def test_two_participants_two_conditions_end_to_end(tmp_path, two_robots):
    study, variants = two_robots
    state = tmp_path / "state"
    with running([], state, study=study, variants=variants) as url, httpx.Client(base_url=url) as c:
        info = c.get("/api/study").json()
        assert info["consent"].startswith("You agree") and info["plans"] == ["choices-concurrent"]
        assert [x["label"] for x in info["conditions"]] == ["Robot A", "Robot B"]
        assert c.get("/api/questionnaire").json()[0]["labels"] == {"1": "Disagree", "5": "Agree"}
        seen = {}
        for pid, deviate in (("P01", False), ("P02", True)):
            r = c.post("/api/participants", json={"participant": pid})
            assert r.status_code == 201
            assert c.post("/api/participants", json={"participant": pid}).status_code == 200
            part = r.json()
            seen[pid] = [b["condition"] for b in part["blocks"]]
            for b in part["blocks"]:
                cond = b["condition"]
                start = c.get("/api/plans/choices-concurrent/advice", params={"condition": cond})
                start = start.json()
                body = {"participant": pid, "block": b["block"], "event": _next(start, deviate)}
                s = c.post("/api/sessions", json=body)
                assert s.status_code == 201, s.text
                s = s.json()
                assert s["condition"] == cond and s["block"] == b["block"]
                again = c.post("/api/sessions", json=body)
                assert again.status_code == 409 and "resume it" in again.json()["detail"]
                r = c.post(f"/api/sessions/{s['id']}/answers", json={"answers": {"trust": 3}})
                assert r.status_code == 409  # not finished
                _finish(c, s["id"], s["advice"], deviate)
                r = c.post(f"/api/sessions/{s['id']}/answers", json={"answers": {"trust": 9}})
                assert r.status_code == 422 and "from 1 to 5" in r.json()["detail"]
                answers = {"trust": 4 if cond == "robust" else 2, "comment": "ok"}
                r = c.post(f"/api/sessions/{s['id']}/answers", json={"answers": answers})
                assert r.status_code == 200, r.text
            done = c.get(f"/api/participants/{pid}").json()
            assert done["next"] is None and all(b["answered"] for b in done["blocks"])
        assert seen == {"P01": ["robust", "schedule"], "P02": ["schedule", "robust"]}
    runner = CliRunner()
    out = runner.invoke(cli, ["study", "export", str(state)])
    assert out.exit_code == 0, out.output
    rows = list(csv.DictReader(io.StringIO(out.stdout)))
    assert {r["participant"] for r in rows} == {"P01", "P02"}
    assert {r["condition"] for r in rows} == {"robust", "schedule"}
    for r in rows:
        assert r["wall_time"].endswith("Z") and r["bound_before"] and r["bound_after"]
    assert any(r["deviation"] == "1" for r in rows if r["participant"] == "P02")
    followed = [r for r in rows if r["participant"] == "P01" and r["deviation"] == "1"]
    assert not followed
    sessions = runner.invoke(cli, ["study", "export", str(state), "--table", "sessions"])
    table = list(csv.DictReader(io.StringIO(sessions.stdout)))
    assert len(table) == 4 and {r["answer.predictable"] for r in table} == {""}  # missing
    doc = json.loads(runner.invoke(cli, ["study", "export", str(state), "--format", "json"]).stdout)
    assert len(doc["events"]) == len(rows) and len(doc["sessions"]) == 4
    deviating = [s for s in doc["sessions"] if s["participant"] == "P02"]
    cost = {s["condition"]: s["cost"] for s in deviating}
    assert cost["schedule"] > cost["robust"]  # the fixed plan lost time to the deviations


def test_serve_study_from_the_command_line(tmp_path):
    """``asmplan serve --study`` plans the study's conditions, says so, and serves them."""
    from tests.asmplan.serve_proc import serve_args, serving

    path = write_study(tmp_path, realtime={"speed": 4})
    args = serve_args("--study", path, "--sessions", tmp_path / "state")
    with serving(args, timeout=300) as (url, _, lines), httpx.Client(base_url=url) as c:
        info = c.get("/api/study").json()
        part = c.post("/api/participants", json={}).json()
    assert info["title"] == "Two robots" and info["realtime"] == {"speed": 4.0}
    assert part["id"].startswith("P") and len(part["blocks"]) == 2
    text = "\n".join(lines)
    assert "choices-concurrent / schedule (cp-sat): worst case" in text
    assert "serving study 'Two robots'" in text


# --------------------------------------------------------------------------- scripted and learned


def _robot_starts(doc: dict, order: list[str]) -> tuple[list[str], float]:
    """Play a concurrent plan with a person who starts what she can in ``order`` (else
    lets the cell run): the operations the robots start, in order, and the makespan."""
    from asmplan.advisor import Advisor

    advisor = Advisor(doc)
    advice, robots = advisor.advice(), []
    while not advice.finished:
        robots += [r["operation"] for r in advice.robots if r["operation"] not in robots]
        mine = [o for o in advice.options if o["operation"] in order]
        if mine:
            o = min(mine, key=lambda o: order.index(o["operation"]))
            ev = {"kind": "started", "operation": o["operation"], "agent": o["agent"]}
            advice = advisor.observe({**ev, "duration": o["durations"][-1]})
        else:
            f = advice.finishes[0]
            ev = {"kind": "finished", "operation": f["operation"], "agent": f["agent"]}
            advice = advisor.observe({**ev, "time": f["time"]})
    return robots, advice.elapsed


def _worst(doc: dict) -> dict:
    return {x["k"]: x["bound"] for x in doc["condition"]["worst_case"]}


def test_the_robot_that_ignores_the_person_keeps_its_list(tmp_path):
    """``ignores-person``: the robot keeps its script (given, or the robust plan's line)
    whatever the person does, where the robust robot adapts; each is certified honestly."""
    conditions = [
        {"id": "robust", "robot": "robust"},
        {"id": "line", "robot": "ignores-person"},
        {"id": "script", "robot": "ignores-person", "script": {"R1": ["r", "s", "t"]}},
    ]
    study = load_study(write_study(tmp_path, conditions=conditions))
    variants = study_plans(study, say=lambda _: None)
    docs = {c: variants[("choices-concurrent", c)] for c in ("robust", "line", "script")}
    assert docs["line"]["condition"]["robot"] == "ignores-person"
    # the person follows the plan (p first): the line robot is the robust one
    assert _robot_starts(docs["line"], ["p", "q", "r"]) == _robot_starts(
        docs["robust"], ["p", "q", "r"]
    )
    # she does q first: the robust robot screws the cover first, the line robot waits for p
    robust, robust_cost = _robot_starts(docs["robust"], ["q", "p", "r"])
    line, line_cost = _robot_starts(docs["line"], ["q", "p", "r"])
    assert robust == ["t", "s"] and line == ["s", "t"] and line_cost > robust_cost
    for order in (["p", "q", "r"], ["q", "p", "r"], ["r", "q", "p"]):
        assert _robot_starts(docs["script"], order)[0] == ["r", "s", "t"]
    r = _worst(docs["robust"])
    for c in ("line", "script"):
        w = _worst(docs[c])
        assert all(w[k] >= r[k] for k in r) and w[None] > r[None]
        assert all(w[a] <= w[b] for a, b in itertools.pairwise([0, 1, 2, None]))


@pytest.fixture(scope="module")
def learned(tmp_path_factory):
    """A study folder with one learned run per turn model (one training cycle each)."""
    from asmplan.cli.app import main

    tmp = tmp_path_factory.mktemp("learned")
    write_study(tmp)
    for turn in ("concurrent", "alternate"):
        argv = ["train", str(tmp / "job"), "--turn-model", turn, "--config", "fast"]
        argv += ["--output", str(tmp / f"run-{turn}"), "--no-progress", "--max-cycles", "1"]
        with pytest.raises(SystemExit) as exit_info:
            main(argv)
        assert exit_info.value.code == 0
    return tmp


def test_a_learned_robot_is_served_with_its_certified_worst_case(learned, capsys):
    """``{run: DIR}``: the policy ``asmplan train`` learned, served with the worst case
    ``asmplan evaluate`` certifies for it, in either turn model; a game over HTTP ends
    within it."""
    from asmplan.cli.app import main

    conditions = [{"id": "learned", "robot": {"run": "run-concurrent"}}]
    plans = [{"source": "job", "turn_model": "concurrent"}]
    study = load_study(write_study(learned, conditions=conditions, plans=plans))
    concurrent = study_plans(study, say=lambda _: None)
    conditions = [{"id": "learned", "robot": {"run": "run-alternate"}}]
    plans = [{"source": "job", "turn_model": "alternate"}]
    alternate = study_plans(
        load_study(write_study(learned, conditions=conditions, plans=plans)), say=lambda _: None
    )
    for doc in [*concurrent.values(), *alternate.values()]:
        turn = doc["turn_model"]
        assert doc["condition"]["robot"].startswith("learned (")
        argv = ["evaluate", str(learned / "job"), "--turn-model", turn, "--format", "json"]
        with pytest.raises(SystemExit):
            main([*argv, "--model", str(learned / f"run-{turn}")])
        certified = json.loads(capsys.readouterr().out)["certified_wcpl"]
        worst = _worst(doc)
        assert worst[None] == certified, (turn, worst, certified)
        assert doc["minimax"] == max(worst.values())
    service = running([], learned / "state", study=study, variants=concurrent)
    with service as url, httpx.Client(base_url=url) as c:
        part = c.post("/api/participants", json={"participant": "P01"}).json()
        start = c.get("/api/plans/choices-concurrent/advice", params={"condition": "learned"})
        body = {"participant": "P01", "block": 0, "event": _next(start.json(), True)}
        s = c.post("/api/sessions", json=body).json()
        end = _finish(c, s["id"], s["advice"], True)
    assert part["blocks"][0]["condition"] == "learned"
    assert end["elapsed"] <= _worst(concurrent[("choices-concurrent", "learned")])[None]
