"""The plan documents a study serves: each plan of ``study.yaml`` under each condition.

Each plan is planned once (:func:`asmplan.pipeline.plan`, the game kept) and every
condition's robot is made from it (:func:`asmplan.study.conditions.condition_plan`). A
plan folder (``plan.json``) is served as it is when every condition is ``robust``; other
robots need the game, so its assembly (the plan's ``source``) is planned again.
"""

from __future__ import annotations

import sys
from pathlib import Path

from asmplan.study.conditions import condition_plan
from asmplan.study.config import Study


def study_plans(study: Study, *, say=None) -> dict[tuple[str, str], dict]:
    """``(plan id, condition id) -> plan document`` for every plan and condition."""
    from asmplan import pipeline
    from asmplan.planfile import read_plan
    from asmplan.serve.app import plan_id

    say = say or (lambda line: print(line, file=sys.stderr, flush=True))
    out: dict[tuple[str, str], dict] = {}
    robust_only = all(c.robot == "robust" for c in study.conditions)
    for plan in study.plans:
        source = plan.source
        if (source / "plan.json").is_file() or source.suffix == ".json":
            doc = read_plan(source)
            if robust_only:
                pid = plan_id(doc)
                for c in study.conditions:
                    out[(pid, c.id)] = {**doc, "condition": _robust_tag(c, doc)}
                continue
            source = Path(doc["source"])
            if not source.exists():
                raise ValueError(
                    f"{study.path}: plan {plan.source}: its assembly {source} is needed for "
                    "robots other than robust, and is not there"
                )
        say(f"study: planning {source} for {len(study.conditions)} condition(s) ...")
        result = pipeline.plan(source, turn_model=plan.turn_model, keep_game=True)
        for c in study.conditions:
            doc = condition_plan(result, c)
            pid = plan_id(doc)
            if (pid, c.id) in out:
                raise ValueError(f"{study.path}: two plans named {pid!r}")
            out[(pid, c.id)] = doc
            worst = doc["condition"]["worst_case"]
            say(f"study: {pid} / {c.id} ({c.describe()}): worst case {_bounds(worst)}")
    return out


def _robust_tag(condition, doc: dict) -> dict:
    worst = doc.get("robustness") or [{"k": None, "bound": doc["minimax"]}]
    return {"id": condition.id, "label": condition.label, "robot": "robust", "worst_case": worst}


def _bounds(worst: list[dict]) -> str:
    def k(x):
        return "inf" if x["k"] is None else str(x["k"])

    return ", ".join(f"k={k(x)}: {x['bound']:g}" for x in worst)
