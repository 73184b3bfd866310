"""``report.html``: one self-contained page (no network) with every part the issue lists."""

from __future__ import annotations

import re
from pathlib import Path

from asmplan.pipeline import PREVIEW_MAX_STATES, build_plan, concurrent_preview
from asmplan.report.html import report_figures, report_html
from tests.asmplan.plans import cell_game, cell_plan

PUMP = Path(__file__).resolve().parents[2] / "examples" / "vacuum_pump"


def _external_references(page: str) -> list[str]:
    refs = re.findall(r"""(?:src|href)\s*=\s*["']([^"']+)["']""", page)
    return [r for r in refs if not r.startswith("data:")] + re.findall(r"https?://", page)


def test_cell_report_is_self_contained_with_curve_and_gantt():
    spec, graph, _, _ = cell_game()
    doc = {**cell_plan(), "concurrent_preview": concurrent_preview(spec, graph)}
    figures = report_figures(doc)
    assert {"robustness", "gantt_cooperative", "gantt_worst"} <= set(figures), figures.get("why")
    page = report_html(doc, figures)
    assert _external_references(page) == []
    for heading in ("Metrics", "Price of robustness", "The principal line", "The worst line"):
        assert heading in page
    assert page.count("<img") >= 3  # curve and two Gantt charts
    assert "No part meshes" in page


def test_report_says_why_a_part_is_missing():
    page = report_html(cell_plan(), {"why": b"too large"})
    assert "The concurrent game was not solved: too large" in page
    assert "not solved: not computed" in report_html(cell_plan(), report_figures(cell_plan()))


def test_a_graph_too_large_for_the_preview_says_so(monkeypatch):
    spec, graph, _, _ = cell_game()
    assert graph.n_states <= PREVIEW_MAX_STATES
    monkeypatch.setattr("asmplan.pipeline.PREVIEW_MAX_STATES", graph.n_states - 1)
    preview = concurrent_preview(spec, graph)
    assert preview == {
        "why": f"{graph.n_states} assembly states (the report solves the concurrent game "
        f"up to {graph.n_states - 1})"
    }
    figures = report_figures({**cell_plan(), "concurrent_preview": preview})
    assert figures == {"why": preview["why"].encode()}


def test_pump_report_pictures_each_step_that_places_parts():
    doc = build_plan(PUMP)
    page = report_html(doc, {"dag": b"\x89PNG fake"})
    steps = [s for s in doc["robust_plan"] if s["parts"]]
    assert page.count("<figure>") == len(steps) == 7
    assert "step 6: 1.4 by H" in page
    assert _external_references(page) == []


def test_report_shows_the_cp_sat_status_note():
    note = "not proven optimal within 30 s: the best schedule found, replayed"
    schedule = {"status": "FEASIBLE", "objective": 105, "bound": 86, "lower_bound": 80}
    with_note = {**cell_plan(), "schedule": {**schedule, "status_note": note}}
    assert f"CP-SAT: {note}" in report_html(with_note, {})
    assert "CP-SAT: " not in report_html({**cell_plan(), "schedule": schedule}, {})
