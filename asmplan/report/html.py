"""``report.html``: one self-contained page a person reads (no network: pictures are PNG data URIs).

It shows the metrics, the price-of-robustness curve and the Gantt charts of the concurrent
game (when it could be solved), the CP-SAT schedule's Gantt chart, the relations table, the
principal line as pictures of the assembly growing step by step (rendered from the part
meshes, the parts of each step highlighted) and the game DAG picture.

matplotlib is used without pyplot (no global backend, no figure left open).
"""

from __future__ import annotations

import base64
import html
import io

import numpy as np

from asmplan.report.meshes import base_parts, part_meshes

NEW, PLACED, GHOST = "#f28c28", "#4f81bd", "#cccccc"
AGENT_COLOURS = {"H": "#9e9e9e", "R1": "#2e9d4a", "R2": "#f28c28"}
OTHER = ("#3b6fb6", "#8e44ad", "#c0392b", "#16a085")
REPORT_MAX_STATES = 5_000
"""Largest state graph whose concurrent game the report solves itself."""


def _png(fig) -> str:
    """A matplotlib Figure as a ``data:image/png;base64,...`` URI."""
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=90)
    return "data:image/png;base64," + base64.b64encode(buffer.getvalue()).decode("ascii")


def _img(uri: str, alt: str, width: int | None = None) -> str:
    w = f' width="{width}"' if width else ""
    return f'<img src="{uri}" alt="{html.escape(alt)}"{w}>'


# --------------------------------------------------------------------------- pictures


def assembly_steps(plan: dict, *, max_pictures: int = 40) -> list[tuple[dict, str]]:
    """The principal line's steps that place parts, each with a picture (data URI).

    The assembly is drawn from the part meshes: parts placed before the step in blue, the
    step's parts in orange, the parts still to come as faint grey outlines.
    """
    meshes = part_meshes(plan)
    if not meshes:
        return []
    from matplotlib.figure import Figure
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    everything = np.concatenate([v for v, _ in meshes.values()])
    lo, hi = everything.min(axis=0), everything.max(axis=0)
    placed = set(base_parts(plan))
    out = []
    for step in plan.get("robust_plan", []):
        if not step.get("parts") or len(out) >= max_pictures:
            continue
        new = set(step["parts"])
        fig = Figure(figsize=(3.2, 3.0))
        ax = fig.add_subplot(projection="3d")
        for pid, (v, f) in meshes.items():
            if pid in new:
                colour, alpha = NEW, 1.0
            elif pid in placed:
                colour, alpha = PLACED, 1.0
            else:
                colour, alpha = GHOST, 0.06
            poly = Poly3DCollection(v[f], facecolor=colour, edgecolor="none", alpha=alpha)
            ax.add_collection3d(poly)
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_zlim(lo[2], hi[2])
        ax.set_box_aspect(hi - lo + 1e-9)
        ax.view_init(elev=22, azim=-60)
        ax.set_axis_off()
        ax.set_title(
            f"{step['operation']} ({step['agent']}): {', '.join(step['parts'])}", fontsize=8
        )
        out.append((step, _png(fig)))
        placed |= new
    return out


def gantt(rows: list[dict], title: str) -> str:
    """A Gantt chart of ``{"agent", "operation"|"task", "start", "end"}`` rows (data URI)."""
    from matplotlib.figure import Figure

    agents = sorted({str(r["agent"]) for r in rows})
    fig = Figure(figsize=(9, 0.55 * len(agents) + 1.3))
    ax = fig.subplots()
    for r in rows:
        a = str(r["agent"])
        colour = AGENT_COLOURS.get(a, OTHER[agents.index(a) % len(OTHER)])
        start, end = float(r["start"]), float(r["end"])
        edge = "#d62728" if r.get("deviation") else "black"
        ax.barh(agents.index(a), end - start, left=start, color=colour, edgecolor=edge, lw=0.6)
        label = r.get("operation", r.get("task", ""))
        ax.text((start + end) / 2, agents.index(a), label, ha="center", va="center", fontsize=6)
    ax.set_yticks(range(len(agents)), agents)
    ax.set_xlabel("time")
    ax.set_title(title, fontsize=10)
    return _png(fig)


def robustness_curve(curve: list[dict], unit: str) -> str:
    """The price of robustness ``k -> W*(k)`` with ``W*(inf)`` as a dashed line (data URI)."""
    from matplotlib.figure import Figure

    finite = [c for c in curve if c["k"] is not None]
    top = [c["bound"] for c in curve if c["k"] is None]
    fig = Figure(figsize=(5, 3))
    ax = fig.subplots()
    ax.plot([c["k"] for c in finite], [c["bound"] for c in finite], "o-", color="#3b6fb6")
    if top:
        ax.axhline(top[0], ls="--", color="#d62728", label=f"W*(inf) = {top[0]:g}{unit}")
        ax.legend(fontsize=8, frameon=False)
    ax.set_xlabel("deviation budget k")
    ax.set_ylabel(f"W*(k){unit}")
    ax.set_xticks([c["k"] for c in finite])
    ax.set_title("price of robustness", fontsize=10)
    return _png(fig)


# --------------------------------------------------------------------------- the concurrent game


def concurrent_summary(spec, graph, *, max_nodes: int = 200_000) -> dict:
    """The concurrent game's curve and its robust policy's timelines, or why there are none.

    Returns ``{"curve": [...], "follow": rows, "worst": rows, "follow_makespan",
    "worst_makespan"}`` or ``{"error": reason}`` (too large, or the spec cannot run
    concurrently).
    """
    from asp.concurrent import concurrent_model, robustness, timeline

    try:
        model = concurrent_model(spec, graph)
        r = robustness(model, max_nodes=max_nodes)
    except (ValueError, MemoryError) as exc:
        return {"error": str(exc).splitlines()[0]}
    out: dict = {"curve": r.to_list()}
    for human in ("follow", "worst"):
        bars, makespan = timeline(r.game, r.solution.robot_policy, human)
        out[human] = [
            {
                "agent": b.agent,
                "operation": b.operation,
                "start": b.start,
                "end": b.end,
                "deviation": b.deviation,
            }
            for b in bars
        ]
        out[f"{human}_makespan"] = makespan
    return out


# --------------------------------------------------------------------------- the page


def report_html(plan: dict, *, dag_png: bytes | None = None, concurrent: dict | None = None) -> str:
    """The report page of a plan document (``asmplan-plan/2``) as one HTML string."""
    esc = html.escape
    unit = "" if plan.get("cost") == "steps" else " s"
    m = plan.get("metrics", {})
    sched = plan.get("schedule") or {}
    rows = [
        ("assembly", plan.get("assembly", "")),
        ("turn model / cost", f"{plan.get('turn_model', '')} / {plan.get('cost', '')}"),
        (
            "assembly states / transitions",
            f"{plan.get('states', '-')} / {plan.get('transitions', '-')}",
        ),
        ("feasible sequences", plan.get("sequences", "-")),
        ("game nodes / edges", f"{plan.get('game_nodes', '-')} / {plan.get('game_edges', '-')}"),
        ("TCT (cooperative minimum)", f"{plan.get('tct', 0):g}{unit}"),
        ("W* (guaranteed against any human)", f"{plan.get('minimax', 0):g}{unit}"),
        ("W*(0): the person follows the plan", f"{m.get('w0', 0):g}{unit}"),
        ("adversarial tax W*/TCT", f"{m.get('adversarial_tax', 1):.2f}"),
        ("policy states / moves", f"{m.get('policy_states', '-')} / {m.get('policy_moves', '-')}"),
    ]
    if sched:
        rows.append(
            (
                "CP-SAT makespan (agents in parallel)",
                f"{sched.get('objective')} s ({sched.get('status')}), lower bound "
                f"{sched.get('lower_bound', '-')}",
            )
        )
    body = [f"<h1>{esc(str(plan.get('assembly', 'plan')))}: the robust plan</h1>"]
    body.append("<h2>Metrics</h2><table>")
    body += [f"<tr><th>{esc(k)}</th><td>{esc(str(v))}</td></tr>" for k, v in rows]
    body.append("</table>")

    body.append("<h2>Price of robustness and the concurrent game</h2>")
    if concurrent and "curve" in concurrent:
        body.append(_img(robustness_curve(concurrent["curve"], " s"), "price of robustness"))
        body.append(
            _img(
                gantt(
                    concurrent["follow"],
                    f"concurrent, the person follows the plan: makespan "
                    f"{concurrent['follow_makespan']:g} s",
                ),
                "Gantt chart, the person follows",
            )
        )
        body.append(
            _img(
                gantt(
                    concurrent["worst"],
                    f"concurrent, the worst person (deviations outlined red): makespan "
                    f"{concurrent['worst_makespan']:g} s",
                ),
                "Gantt chart, the worst person",
            )
        )
    else:
        reason = (concurrent or {}).get("error", "not computed")
        body.append(f"<p class='note'>The concurrent game was not solved: {esc(reason)}.</p>")
    if sched.get("schedule"):
        body.append("<h2>CP-SAT schedule</h2>")
        title = f"CP-SAT minimum makespan {sched.get('objective')} s ({sched.get('status')})"
        body.append(_img(gantt(sched["schedule"], title), "CP-SAT Gantt chart"))

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
    if dag_png:
        body.append("<h2>The game DAG</h2>")
        uri = "data:image/png;base64," + base64.b64encode(dag_png).decode("ascii")
        body.append(_img(uri, "game DAG", width=1100))
    if plan.get("credit"):
        body.append(f"<p class='note'>{esc(plan['credit'])}</p>")
    return PAGE.format(title=esc(str(plan.get("assembly", "plan"))), body="\n".join(body))


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
            f"<td>{esc(', '.join(s['parts']))}</td><td>{s['cost']:g}</td>"
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
figure {{ margin: 0; width: 290px; font-size: 0.8em; }}
figure img {{ width: 290px; }}
.note {{ color: #666; }}
</style></head>
<body>
{body}
</body></html>
"""
