"""The paper's Figures 11-13 for a sweep, as PNG bytes.

- Figure 11: training rewards of one ARL run (raw per-episode rewards faint, 50-episode
  moving averages bold; robot blue, human orange, as in the paper).
- Figure 12: resilience ratio per trial: ours (paper's definition), ours certified (100%),
  and the paper's published value beside it.
- Figure 13: shortest path (TCT), average random length and robust policy length per
  trial (with ARL: also its learned-vs-learned and certified WCPL), ours next to the
  paper's.

Figures are drawn on :class:`matplotlib.figure.Figure` objects (no pyplot state), so they
are safe to draw from any thread or process.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.figure import Figure

from arl.plots import MOVING_AVERAGE, rewards_png
from asmplan.experiments.paper_values import paper_table3_row, paper_table4_row
from asmplan.experiments.tasks import ResultRow
from asmplan.report.png import png_bytes


def primary_rows(rows: Sequence[ResultRow]) -> list[ResultRow]:
    """One row per graph: the ARL row when ARL ran (the paper's method), else the exact one."""
    chosen: dict[tuple, ResultRow] = {}
    for r in rows:
        key = (r.experiment, r.config, r.trial)
        if key not in chosen or r.solver == "arl":
            chosen[key] = r
    return list(chosen.values())


def row_label(row: ResultRow, experiment: str, many_trials: bool) -> str:
    """The x-axis label of a graph: its trial (Table 4) or configuration (Table 3)."""
    if experiment == "table4":
        return str(row.trial)
    return f"{row.config} #{row.trial}" if many_trials else row.config


def paper_row(row: ResultRow):
    """The paper's row matching ``row`` (Table 3 by configuration, Table 4 by trial)."""
    if row.experiment == "table4":
        return paper_table4_row(row.trial)
    return paper_table3_row(row.layers, row.max_nodes) if row.trial == 1 else None


def _png(fig: Figure) -> bytes:
    return png_bytes(fig, dpi=130, bbox_inches="tight")


def figure11_training(
    episode_rewards: dict[str, Sequence[float]], title: str = "", window: int = MOVING_AVERAGE
) -> bytes:
    """Figure 11: per-episode rewards of robot and human with moving averages."""
    return rewards_png(
        episode_rewards, title or "Training reward dynamics (ARL, alternating PPO)", window
    )


def figure12_resilience(experiment: str, rows: Sequence[ResultRow]) -> bytes:
    """Figure 12: resilience ratio per trial, ours (paper's RR and certified) and the paper's."""
    rows = primary_rows(rows)
    many = len({r.trial for r in rows}) > 1
    labels = [row_label(r, experiment, many) for r in rows]
    ours = np.array([100 * r.rr for r in rows])
    certified = np.array([100 * r.rr_certified for r in rows])
    paper = np.array([_paper_value(r, "rr", 100.0) for r in rows])
    method = "ARL" if any(r.solver == "arl" for r in rows) else "exact robust policy"

    x = np.arange(len(rows))
    width = 0.27
    fig = Figure(figsize=(max(7.0, 0.75 * len(rows) + 3), 4.8))
    ax = fig.subplots()
    ax.bar(x - width, ours, width, color="tab:green", label=f"Ours: RR vs WCPL ({method})")
    ax.bar(x, certified, width, color="tab:gray", label="Ours: RR vs certified WCPL")
    if not np.all(np.isnan(paper)):
        ax.bar(x + width, paper, width, color="tab:purple", alpha=0.75, label="Paper (published)")
    for xi, v in zip(x - width, ours, strict=True):
        ax.text(xi, v + 1, f"{v:.1f}", ha="center", va="bottom", fontsize=7)
    ax.set_xticks(x, labels, rotation=0 if experiment == "table4" else 20)
    ax.set_xlabel("Trial" if experiment == "table4" else "Layers / max nodes")
    ax.set_ylabel("Resilience ratio (%)")
    ax.set_ylim(0, 110)
    ax.set_title("Resilience ratio per trial (cf. paper Figure 12)")
    ax.grid(axis="y", alpha=0.3)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=3, fontsize=8)
    return _png(fig)


def figure13_path_lengths(experiment: str, rows: Sequence[ResultRow]) -> bytes:
    """Figure 13: shortest path, average random and robust policy length per trial."""
    primary = primary_rows(rows)
    many = len({r.trial for r in primary}) > 1
    labels = [row_label(r, experiment, many) for r in primary]
    arl = any(r.solver == "arl" for r in primary)
    series = [
        ("Shortest path (TCT)", [r.tct for r in primary], "tab:green"),
        ("Avg random length", [r.avg_random for r in primary], "tab:orange"),
        ("Robust policy (W*, exact)", [r.minimax for r in primary], "tab:blue"),
    ]
    if arl:
        series.append(("ARL WCPL (learned vs learned)", [r.wcpl for r in primary], "tab:red"))
        series.append(("ARL certified WCPL", [r.certified_wcpl for r in primary], "tab:purple"))
    paper = [
        ("Shortest path (TCT)", [_paper_value(r, "tct") for r in primary], "tab:green"),
        ("Avg random length", [_paper_value(r, "avg_random") for r in primary], "tab:orange"),
        ("Optimal policy (WCPL)", [_paper_value(r, "wcpl") for r in primary], "tab:blue"),
    ]
    has_paper = not all(np.isnan(v) for _, values, _ in paper for v in values)

    panels = [("Ours", series)] + ([("Paper (published)", paper)] if has_paper else [])
    fig = Figure(figsize=(max(7.0, 0.8 * len(primary) + 3) * len(panels) * 0.8, 4.8))
    axes = np.atleast_1d(fig.subplots(1, len(panels), sharey=True))
    x = np.arange(len(primary))
    top = np.nanmax([v for _, values, _ in series + paper for v in values] + [1.0])
    for ax, (title, data) in zip(axes, panels, strict=True):
        width = 0.8 / len(data)
        for i, (name, values, color) in enumerate(data):
            ax.bar(x + (i - (len(data) - 1) / 2) * width, values, width, color=color, label=name)
        ax.set_xticks(x, labels, rotation=0 if experiment == "table4" else 20)
        ax.set_xlabel("Trial" if experiment == "table4" else "Layers / max nodes")
        ax.set_title(title)
        ax.grid(axis="y", alpha=0.3)
        ax.legend(loc="upper left", ncol=2, fontsize=8)
    axes[0].set_ylim(0, 1.3 * top)  # room for the legends above the bars
    axes[0].set_ylabel("Path length (steps)")
    fig.suptitle("Shortest path vs average random vs robust policy (cf. paper Figure 13)")
    return _png(fig)


def _paper_value(row: ResultRow, name: str, scale: float = 1.0) -> float:
    paper = paper_row(row)
    return float("nan") if paper is None else scale * float(getattr(paper, name))
