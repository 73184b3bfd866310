"""Pictures of the concurrent game: the price-of-robustness curve and Gantt charts.

Figures are drawn on :class:`matplotlib.figure.Figure` (no pyplot, no global backend);
PNGs are written atomically.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from pathlib import Path

from asmplan.report.png import write_png

AGENT_COLOURS = {"H": "#9e9e9e", "R1": "#2e9d4a", "R2": "#f28c28"}
"""The paper's Figure 9 colours: operator grey, R1 green, R2 orange."""
OTHER_COLOURS = ("#3b6fb6", "#8e44ad", "#c0392b", "#16a085", "#7f8c8d")
DEVIATION_COLOUR = "#d62728"


def _figure(figsize: tuple[float, float], dpi: int):
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, dpi=dpi)
    return fig, fig.subplots()


def plot_robustness(
    rows: Sequence[dict],
    path: str | os.PathLike[str],
    *,
    schedule: float | None = None,
    schedule_rows: Sequence[dict] | None = None,
    title: str = "",
) -> Path:
    """The curve ``k -> W*(k)`` with ``W*(inf)`` at the right and the CP-SAT makespan.

    Parameters
    ----------
    rows : list of {"k": int or None, "bound": float}
        The robustness list of the plan (``k`` None: the unbounded adversary).
    schedule : float, optional
        The CP-SAT makespan (a horizontal line).
    schedule_rows : list of {"k", "bound"}, optional
        The CP-SAT schedule's certified worst case under the same budgets.
    """
    xs = list(range(len(rows)))
    labels = ["inf" if r["k"] is None else str(r["k"]) for r in rows]
    fig, ax = _figure((6.4, 4.0), 110)
    ax.plot(xs, [r["bound"] for r in rows], "o-", color="#1f4e9c", label="robust plan W*(k)")
    if schedule_rows:
        ax.plot(
            xs[: len(schedule_rows)],
            [r["bound"] for r in schedule_rows],
            "s--",
            color=DEVIATION_COLOUR,
            label="CP-SAT schedule, certified worst case",
        )
    if schedule is not None:
        ax.axhline(schedule, color="#555555", lw=1, ls=":", label=f"CP-SAT makespan {schedule:g}")
    ax.set_xticks(xs, labels)
    ax.set_xlabel("deviations the person may make (k)")
    ax.set_ylabel("guaranteed makespan (s)")
    ax.set_title(title or "price of robustness", fontsize=10)
    ax.legend(fontsize=8, frameon=False, loc="best")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return write_png(fig, path)


SHOWN_WIDTH = 11.5
"""Inches a Gantt chart is drawn at: the report's width (1150 px at 100 px per inch), so
its text is shown at the size it is set in."""
GANTT_DPI = 200
"""Pixels per inch of a Gantt PNG: twice the size shown, sharp on any screen."""
LABEL_PT = 9.0
"""Size of the operation ids in the bars and of the axes' text, points at the size shown."""
AXES_SHARE = 0.86
"""The part of the figure's width the time axis takes (the rest: agent names, margins)."""


def label_fits(label: str, bar: float, span: float, *, width: float = SHOWN_WIDTH) -> bool:
    """Whether ``label`` fits inside a bar ``bar`` long on a time axis ``span`` long drawn
    :data:`AXES_SHARE` of ``width`` inches wide, at :data:`LABEL_PT` (a character is taken
    as 0.62 em wide, with a quarter em of room on each side)."""
    inches = bar / max(span, 1e-9) * width * AXES_SHARE
    need = (0.62 * len(label) + 0.5) * LABEL_PT / 72
    return inches >= need


def plot_gantt(
    bars: Sequence,
    path: str | os.PathLike[str],
    *,
    makespan: float | None = None,
    title: str = "",
    unit: str = "s",
) -> Path:
    """Bars per agent on one time axis, with a legend: each agent's colour, deviations from
    the plan outlined in red and hatched, the makespan line.

    The chart is drawn at the report's width (:data:`SHOWN_WIDTH`) at :data:`GANTT_DPI`, so
    its text reads at :data:`LABEL_PT` where it is shown; an operation's id is written in
    its bar when it fits there (:func:`label_fits`; the line tables name every operation).

    Parameters
    ----------
    bars : sequence of :class:`asp.concurrent.describe.Bar`
    unit : str
        The time unit of the axis and the makespan (``s``).
    """
    fig, ax = _figure((SHOWN_WIDTH, 1.7 + 0.55 * len({b.agent for b in bars})), GANTT_DPI)
    draw_gantt(ax, bars, makespan=makespan, unit=unit)
    ax.set_title(title, fontsize=LABEL_PT + 1)
    fig.tight_layout()
    return write_png(fig, path)


def draw_gantt(ax, bars: Sequence, *, makespan: float | None = None, unit: str = "s") -> dict:
    """Draw the chart of :func:`plot_gantt` on the matplotlib axes ``ax``; returns what it
    wrote: ``{"labels": [operation ids written in bars], "legend": [legend entries]}``."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    agents = sorted({b.agent for b in bars}, key=lambda a: (not a.startswith("H"), a))
    row = {a: i for i, a in enumerate(agents)}
    palette = dict(AGENT_COLOURS)
    for a in agents:
        palette.setdefault(a, OTHER_COLOURS[len(palette) % len(OTHER_COLOURS)])
    end = max([makespan or 0.0, *(b.end for b in bars)])
    written: list[str] = []
    span = end * 1.02 if end else 1.0
    for b in bars:
        y = row[b.agent]
        ax.barh(
            y,
            b.end - b.start,
            left=b.start,
            height=0.6,
            color=palette[b.agent],
            edgecolor=DEVIATION_COLOUR if b.deviation else "black",
            linewidth=2.0 if b.deviation else 0.6,
            hatch="//" if b.deviation else None,
        )
        if label_fits(b.operation, b.end - b.start, span):
            written.append(b.operation)
            ax.text(
                (b.start + b.end) / 2,
                y,
                b.operation,
                ha="center",
                va="center",
                fontsize=LABEL_PT,
                bbox={"boxstyle": "round,pad=0.1", "fc": "white", "ec": "none", "alpha": 0.7},
            )
    handles = [Patch(facecolor=palette[a], edgecolor="black", label=a) for a in agents]
    if any(b.deviation for b in bars):
        handles.append(
            Patch(facecolor="white", edgecolor=DEVIATION_COLOUR, hatch="//", label="deviation")
        )
    if makespan is not None:
        ax.axvline(makespan, color="black", lw=1, ls="--")
        handles.append(
            Line2D([], [], color="black", ls="--", label=f"makespan {makespan:g} {unit}")
        )
    ax.set_yticks(range(len(agents)), agents, fontsize=LABEL_PT)
    ax.tick_params(axis="x", labelsize=LABEL_PT)
    ax.invert_yaxis()
    ax.set_xlabel(f"time ({unit})", fontsize=LABEL_PT)
    ax.set_xlim(0, span)
    ax.grid(axis="x", alpha=0.3)
    ax.legend(
        handles=handles,
        fontsize=LABEL_PT,
        frameon=False,
        loc="upper center",
        bbox_to_anchor=(0.5, -0.2 if len(agents) > 2 else -0.4),
        ncol=len(handles),
    )
    return {"labels": written, "legend": [h.get_label() for h in handles]}


def write_figures(doc: dict, folder: str | os.PathLike[str] | Callable) -> list[Path]:
    """Write ``robustness.png``, ``gantt_cooperative.png`` and ``gantt_worst.png`` of a
    concurrent plan document (its ``robustness``, ``concurrent`` and ``schedule``), so they
    are a function of ``plan.json`` like ``report.html``.

    ``folder`` is a folder, or a function from a file name to its path (an
    :class:`asp.atomic.OutputSet`'s ``path``).
    """
    path_of = folder if callable(folder) else Path(folder).joinpath
    name = doc.get("assembly", "plan")
    game = doc["concurrent"]
    k = game["plan_budget"]
    written = [
        plot_robustness(
            doc["robustness"],
            path_of("robustness.png"),
            schedule=(doc.get("schedule") or {}).get("objective"),
            schedule_rows=game["schedule_worst_case"],
            title=f"{name}\nguaranteed makespan against a person who may deviate k times",
        )
    ]
    lines = (
        ("gantt_cooperative.png", game["cooperative"], "the person follows it"),
        ("gantt_worst.png", game["worst"], "against the worst person"),
    )
    for file, line, who in lines:
        makespan = line["makespan"]
        title = f"{name}: robust plan (k = {k}), {who}: makespan {makespan:g} s"
        bars = document_bars(line["bars"])
        written.append(plot_gantt(bars, path_of(file), makespan=makespan, title=title))
    return written


def document_bars(rows: list[dict], operation: str = "operation") -> list:
    """Timeline bars (:class:`asp.concurrent.describe.Bar`) of a plan document's rows
    (``operation``: the key naming the task)."""
    from asp.concurrent.describe import Bar

    return [
        Bar(
            str(r["agent"]),
            str(r[operation]),
            float(r["start"]),
            float(r["end"]),
            bool(r.get("deviation", False)),
        )
        for r in rows
    ]
