"""``results.csv`` and ``results.md``: the rows of a sweep as tables.

The CSV holds every field of :class:`~asmplan.experiments.tasks.ResultRow`. The Markdown table
starts with the paper's columns in the paper's order (Table 3: configuration, TCT, WCPL,
max and average random length, RR; Table 4: trial, total nodes, TCT, WCPL, average random
length, RR), then the columns this project adds.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Callable, Sequence
from dataclasses import asdict

from asmplan.experiments.tasks import ResultRow
from asp.numbers import cost_text

Column = tuple[str, Callable[[ResultRow], str]]


def _num(x: float | None) -> str:
    if x is None:
        return ""
    return cost_text(x, ".2f")


def _pct(x: float) -> str:
    return f"{100 * x:.2f}%"


def _yes(x: bool | None) -> str:
    return "" if x is None else ("yes" if x else "no")


CONFIG: Column = ("Layers / Max nodes", lambda r: r.config)
TRIAL: Column = ("Trial", lambda r: str(r.trial))
NODES: Column = ("Total Nodes", lambda r: str(r.nodes))
TCT: Column = ("TCT", lambda r: _num(r.tct))
WCPL: Column = ("WCPL", lambda r: _num(r.wcpl))
MAX_RANDOM: Column = ("Max Random Length", lambda r: _num(r.max_random))
AVG_RANDOM: Column = ("Avg Random Length", lambda r: _num(r.avg_random))
RR: Column = ("RR", lambda r: _pct(r.rr))

PAPER_COLUMNS: dict[str, tuple[Column, ...]] = {
    "table3": (CONFIG, TCT, WCPL, MAX_RANDOM, AVG_RANDOM, RR),
    "table4": (TRIAL, NODES, TCT, WCPL, AVG_RANDOM, RR),
}
"""The paper's columns of each table, in its order."""

NEW_COLUMNS: tuple[Column, ...] = (
    ("Solver", lambda r: r.solver),
    ("Edges", lambda r: str(r.edges)),
    ("W*", lambda r: _num(r.minimax)),
    ("Certified WCPL", lambda r: _num(r.certified_wcpl)),
    ("Robust-optimal", lambda r: _yes(r.robust_optimal)),
    ("RR certified", lambda r: _pct(r.rr_certified)),
    ("Max Random (1000 games)", lambda r: _num(r.max_random_sampled)),
    ("Avg Random (1000 games)", lambda r: _num(r.avg_random_sampled)),
    ("RR (1000 games)", lambda r: _pct(r.rr_sampled)),
    (
        "Adversarial tax W*/TCT",
        lambda r: "-" if r.adversarial_tax is None else f"{r.adversarial_tax:.2f}",
    ),
    ("Converged", lambda r: _yes(r.converged)),
    ("Time (s)", lambda r: f"{r.train_s:.2f}"),
)
"""The columns this project adds after the paper's."""


def markdown_columns(experiment: str) -> list[Column]:
    """All Markdown columns of an experiment: the paper's, the other identity ones, ours."""
    paper = PAPER_COLUMNS[experiment]
    identity = [c for c in (CONFIG, TRIAL, NODES, MAX_RANDOM) if c not in paper]
    return [*paper, *identity, *NEW_COLUMNS]


def results_markdown(experiment: str, rows: Sequence[ResultRow]) -> str:
    """A Markdown table of the rows (paper's columns first)."""
    columns = markdown_columns(experiment)
    lines = [
        "| " + " | ".join(name for name, _ in columns) + " |",
        "|" + "|".join("---" for _ in columns) + "|",
    ]
    lines += ["| " + " | ".join(cell(r) for _, cell in columns) + " |" for r in rows]
    return "\n".join(lines) + "\n"


def results_csv(rows: Sequence[ResultRow]) -> str:
    """CSV text of the rows with every :class:`ResultRow` field as a column."""
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=ResultRow.field_names(), lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({k: ("" if v is None else v) for k, v in asdict(row).items()})
    return buffer.getvalue()
