"""``report.html``: one self-contained page a person reads (no network: pictures are PNG data URIs).

It shows the metrics, the price-of-robustness curve and the Gantt charts of the concurrent
game (when it could be solved; drawn by :mod:`asmplan.report.gantt`), the CP-SAT schedule's Gantt
chart, the relations table, the principal line as pictures of the assembly growing step by
step (:mod:`asmplan.report.steps`: rendered from the part meshes, the parts of each step
highlighted, an arrow for each way in) and, for an alternate plan, the game DAG picture. One
solution, one set of figures: a concurrent plan's page shows its concurrent game's figures
only (the curve and the timelines), never an alternating game's DAG.

The page is a function of the plan document (``plan.json``, whose ``concurrent_preview``
holds an alternate plan's concurrent game, computed by :mod:`asmplan.pipeline`) and the
``dag.png`` beside an alternate plan: nothing is solved here, so ``asmplan report PLAN_DIR``
redraws it.
"""

from __future__ import annotations

import html
from pathlib import Path

from asmplan.report.png import data_uri
from asmplan.report.steps import assembly_steps
from asp.game.turns import turn_of


def _img(uri: str, alt: str, width: int | None = None) -> str:
    w = f' width="{width}"' if width else ""
    return f'<img src="{uri}" alt="{html.escape(alt)}"{w}>'


# --------------------------------------------------------------------------- figures


def _concurrent(doc: dict) -> bool:
    return turn_of(doc.get("turn_model")).plan_curve


def concurrent_part(doc: dict) -> dict:
    """The concurrent game's part of a plan document: the plan's own keys (``robustness``,
    ``concurrent``, ``schedule``) with the turn model ``concurrent``, else its
    ``concurrent_preview`` (empty when it has none; ``{"why": ...}`` when not solved)."""
    if _concurrent(doc):
        return doc
    return doc.get("concurrent_preview") or {}


def report_figures(doc: dict) -> dict[str, bytes]:
    """The curve and Gantt PNGs of the report (:mod:`asmplan.report.gantt`), by name,
    drawn from the plan document alone (nothing is solved here).

    The curve and the two timelines come from the concurrent game's part of ``doc``
    (:func:`concurrent_part`); without it, ``"why"`` says why they are missing. The CP-SAT
    schedule's Gantt chart comes from ``doc["schedule"]``.
    """
    import tempfile

    from asmplan.report.gantt import document_bars, plot_gantt, plot_robustness

    out: dict[str, bytes] = {}
    part = concurrent_part(doc)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        if "robustness" in part and "concurrent" in part:
            game = part["concurrent"]
            out["robustness"] = plot_robustness(
                part["robustness"],
                folder / "r.png",
                schedule=(part.get("schedule") or {}).get("objective"),
                schedule_rows=game["schedule_worst_case"],
            ).read_bytes()
            for name in ("cooperative", "worst"):
                who = "follows the plan" if name == "cooperative" else "is the worst"
                makespan = game[name]["makespan"]
                out[f"gantt_{name}"] = plot_gantt(
                    document_bars(game[name]["bars"]),
                    folder / f"{name}.png",
                    makespan=makespan,
                    title=f"concurrent: the person {who}, makespan {makespan:g} s",
                ).read_bytes()
        elif "why" in part:
            out["why"] = str(part["why"]).encode()
        rows = (doc.get("schedule") or {}).get("schedule") or []
        if rows:
            sched = doc["schedule"]
            out["gantt_schedule"] = plot_gantt(
                document_bars(rows, operation="task"),
                folder / "s.png",
                title=f"CP-SAT schedule: makespan {sched.get('objective')} s "
                f"({sched.get('status')})",
            ).read_bytes()
    return out


def plan_report(doc: dict, dag_png: bytes | None = None) -> str:
    """``report.html`` of a plan document: :func:`report_html` with :func:`report_figures`
    and, for an alternate plan, the game DAG picture ``dag_png`` (``dag.png``'s bytes;
    ignored for a concurrent plan, whose figures are its own game's)."""
    figures = report_figures(doc)
    if dag_png and not _concurrent(doc):
        figures["dag"] = dag_png
    return report_html(doc, figures)


# --------------------------------------------------------------------------- the page


def report_html(plan: dict, figures: dict[str, bytes] | None = None) -> str:
    """The report page of a plan document (``asmplan-plan/2``) as one HTML string.

    ``figures``: PNGs by name (``dag``, ``robustness``, ``gantt_cooperative``,
    ``gantt_worst``, ``gantt_schedule``; :func:`report_figures`) and ``why`` (bytes), the
    reason the concurrent ones are missing. ``dag`` is drawn for an alternate plan only.
    """
    figures = figures or {}
    esc = html.escape
    unit = "" if plan.get("cost") == "steps" else " s"
    m = plan.get("metrics", {})
    sched = plan.get("schedule") or {}
    # The plan's game: the policy, lines and metrics are those of its turn model.
    game = "concurrent game" if _concurrent(plan) else "alternating game"
    rows = [
        ("assembly", plan.get("assembly", "")),
        ("turn model / cost", f"{plan.get('turn_model', '')} / {plan.get('cost', '')}"),
        (
            "assembly states / transitions",
            f"{plan.get('states', '-')} / {plan.get('transitions', '-')}",
        ),
        ("feasible sequences", plan.get("sequences", "-")),
        ("game nodes / edges", f"{plan.get('game_nodes', '-')} / {plan.get('game_edges', '-')}"),
        (f"TCT ({game}, cooperative minimum)", f"{plan.get('tct', 0):g}{unit}"),
        (f"W* ({game}, against any human)", f"{plan.get('minimax', 0):g}{unit}"),
        (f"the person follows the plan ({game})", f"{m.get('w0', 0):g}{unit}"),
        ("adversarial tax W*/TCT", f"{m.get('adversarial_tax', 1):.2f}"),
        ("policy states / moves", f"{m.get('policy_states', '-')} / {m.get('policy_moves', '-')}"),
    ]
    for r in plan.get("robustness") or []:
        k = "inf" if r["k"] is None else r["k"]
        rows.append(
            (
                f"concurrent game: W*({k}), the person deviates at most {k} times",
                f"{r['bound']:g} s",
            )
        )
    if sched:
        rows.append(
            (
                "CP-SAT makespan (agents in parallel)",
                f"{sched.get('objective')} s ({sched.get('status')}), lower bound "
                f"{sched.get('lower_bound', '-')} s",
            )
        )
    body = [f"<h1>{esc(str(plan.get('assembly', 'plan')))}: the robust plan</h1>"]
    body.append("<h2>Metrics</h2><table>")
    body += [f"<tr><th>{esc(k)}</th><td>{esc(str(v))}</td></tr>" for k, v in rows]
    body.append("</table>")

    body.append("<h2>Price of robustness and the concurrent game</h2>")
    if "robustness" in figures:
        if note := _graph_note(plan):
            body.append(note)
        body.append(_img(data_uri(figures["robustness"]), "price of robustness"))
        for name in ("gantt_cooperative", "gantt_worst"):
            body.append(_img(data_uri(figures[name]), name.replace("_", " ")))
    else:
        reason = figures.get("why", b"not computed").decode()
        body.append(f"<p class='note'>The concurrent game was not solved: {esc(reason)}.</p>")
    if "gantt_schedule" in figures:
        body.append("<h2>CP-SAT schedule</h2>")
        body.append(_img(data_uri(figures["gantt_schedule"]), "CP-SAT Gantt chart"))
    if sched.get("status_note"):
        body.append(f"<p class='note'>CP-SAT: {esc(sched['status_note'])}</p>")

    principal = plan.get("robust_plan", [])
    body.append("<h2>The principal line (the person follows the plan)</h2>")
    pictures = assembly_steps(plan)
    if pictures:
        body.append("<div class='steps'>")
        for step, uri in pictures:
            caption = (
                f"step {step['step']}: {step['operation']} by {step['agent']}, "
                f"{step['description']} (cost so far {step['elapsed']:g}{unit})"
            )
            body.append(
                f"<figure>{_img(uri, caption)}<figcaption>{esc(caption)}</figcaption></figure>"
            )
        body.append("</div>")
    else:
        body.append("<p class='note'>No part meshes: no pictures of the assembly.</p>")
    body.append(_line_table(principal, unit))
    body.append("<h2>The worst line (the person delays all she can)</h2>")
    body.append(_line_table(plan.get("worst_line", []), unit))

    relations = plan.get("relations") or []
    if relations:
        body.append(
            "<h2>Part relations</h2><table><tr><th>part</th><th>touches (directions)</th>"
            "<th>free directions in the assembly</th></tr>"
        )
        for r in relations:
            touches = "; ".join(f"{q} ({', '.join(ds)})" for q, ds in r["contacts"].items())
            body.append(
                f"<tr><td>{esc(r['part'])}</td><td>{esc(touches or '-')}</td>"
                f"<td>{esc(' '.join(r['free']) or 'none')}</td></tr>"
            )
        body.append("</table>")
    if "dag" in figures and not _concurrent(plan):
        body.append("<h2>The game DAG</h2>")
        body.append(_img(data_uri(figures["dag"]), "game DAG", width=1100))
    if plan.get("credit"):
        body.append(f"<p class='note'>{esc(plan['credit'])}</p>")
    return PAGE.format(title=esc(str(plan.get("assembly", "plan"))), body="\n".join(body))


def _graph_note(plan: dict) -> str:
    """What an alternate plan's concurrent preview was solved on (empty for a concurrent
    plan, whose metrics say it): the concurrent plan's state graph, alike parts in any
    order, beside the alternating game's, where they go in a fixed order."""
    preview = plan.get("concurrent_preview") or {}
    if _concurrent(plan) or "states" not in preview:
        return ""
    return (
        "<p class='note'>The concurrent game is solved on the state graph a concurrent plan "
        f"uses (alike parts in any order): {preview['states']} states, "
        f"{preview['sequences']} feasible sequences; the alternating game's has alike parts "
        f"in a fixed order ({plan.get('states', '-')} states, {plan.get('sequences', '-')} "
        "feasible sequences).</p>"
    )


def _line_table(steps: list[dict], unit: str) -> str:
    esc = html.escape
    out = [
        "<table class='line'><tr><th>#</th><th>side</th><th>operation</th><th>agent</th>"
        "<th>description</th><th>parts</th><th>cost</th><th>so far</th><th>bound left</th></tr>"
    ]
    for s in steps:
        if not s["operation"]:
            continue
        out.append(
            f"<tr><td>{s['step']}</td><td>{esc(s['player'])}</td><td>{esc(s['operation'])}</td>"
            f"<td>{esc(s['agent'])}</td><td>{esc(s['description'])}</td>"
            f"<td>{esc(', '.join(s['parts']))}</td><td>{s['cost']:g}{unit}</td>"
            f"<td>{s['elapsed']:g}{unit}</td><td>{s['bound']:g}{unit}</td></tr>"
        )
    out.append("</table>")
    return "\n".join(out)


PAGE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{title}: asmplan report</title>
<style>
body {{ font-family: system-ui, sans-serif; margin: 1.5em auto; max-width: 1150px; color: #222; }}
table {{ border-collapse: collapse; margin: 0.5em 0 1em; font-size: 0.9em; }}
th, td {{ border: 1px solid #ccc; padding: 0.25em 0.6em; text-align: left; }}
th {{ background: #f0f3f7; }}
.steps {{ display: flex; flex-wrap: wrap; gap: 0.5em; }}
img {{ max-width: 100%; height: auto; }}
figure {{ margin: 0; width: 290px; font-size: 0.8em; }}
figure img {{ width: 290px; }}
.note {{ color: #666; }}
</style></head>
<body>
{body}
</body></html>
"""
