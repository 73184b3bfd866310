"""The paper's published numbers (section 4.3, Tables 3 and 4; section 5.2).

These are **the paper's values, copied from its text**, kept only to compare our runs with
them. They are not results of this project and nothing here is computed. Checked against
``../shared/seed/*.txt`` (Tables 3 and 4, and the averages quoted in section 5.2).

The paper's WCPL is the cost of the learned robot policy played against the learned human
policy (``../shared/DESIGN.md``, "Metrics"), and its RR is the share of 1,000 random-human
games with cost <= that WCPL.
"""

from __future__ import annotations

from dataclasses import dataclass

PAPER = "the paper (section 4.3, Tables 3-4)"
"""How summaries cite the source of these numbers."""


@dataclass(frozen=True)
class PaperTable3Row:
    """One row of the paper's Table 3: a synthetic graph per configuration (4 actions max)."""

    layers: int
    max_nodes: int
    tct: int
    wcpl: int
    max_random: int
    avg_random: float
    rr: float
    """Resilience ratio as a fraction (0.879 for the paper's 87.90%)."""

    @property
    def label(self) -> str:
        """``"layers/max nodes"``, the paper's row label."""
        return f"{self.layers}/{self.max_nodes}"


@dataclass(frozen=True)
class PaperTable4Row:
    """One trial of the paper's Table 4: ten 20/10 graphs (4 actions max)."""

    trial: int
    nodes: int
    tct: int
    wcpl: int
    avg_random: float
    rr: float
    """Resilience ratio as a fraction."""


PAPER_TABLE3: tuple[PaperTable3Row, ...] = (
    PaperTable3Row(4, 10, tct=1, wcpl=4, max_random=5, avg_random=3.86, rr=0.879),
    PaperTable3Row(10, 4, tct=2, wcpl=7, max_random=8, avg_random=4.57, rr=0.942),
    PaperTable3Row(10, 10, tct=2, wcpl=9, max_random=11, avg_random=8.18, rr=0.934),
    PaperTable3Row(15, 10, tct=5, wcpl=10, max_random=12, avg_random=8.18, rr=0.933),
    PaperTable3Row(20, 10, tct=4, wcpl=11, max_random=18, avg_random=10.75, rr=0.71),
    PaperTable3Row(20, 20, tct=3, wcpl=14, max_random=19, avg_random=12.28, rr=0.85),
)
"""The paper's Table 3, in its row order."""

PAPER_TABLE4: tuple[PaperTable4Row, ...] = (
    PaperTable4Row(1, nodes=76, tct=5, wcpl=11, avg_random=11.3, rr=0.626),
    PaperTable4Row(2, nodes=70, tct=6, wcpl=17, avg_random=13.32, rr=0.970),
    PaperTable4Row(3, nodes=59, tct=2, wcpl=11, avg_random=10.29, rr=0.545),
    PaperTable4Row(4, nodes=56, tct=4, wcpl=8, avg_random=7.54, rr=0.615),
    PaperTable4Row(5, nodes=62, tct=3, wcpl=5, avg_random=9.32, rr=0.283),
    PaperTable4Row(6, nodes=64, tct=6, wcpl=10, avg_random=10.16, rr=0.630),
    PaperTable4Row(7, nodes=73, tct=3, wcpl=16, avg_random=12.31, rr=0.987),
    PaperTable4Row(8, nodes=69, tct=4, wcpl=15, avg_random=10.23, rr=0.977),
    PaperTable4Row(9, nodes=77, tct=6, wcpl=13, avg_random=12.11, rr=0.625),
    PaperTable4Row(10, nodes=68, tct=5, wcpl=11, avg_random=10.77, rr=0.668),
)
"""The paper's Table 4, trials 1-10."""

PAPER_15_10_GRAPH = {"nodes": 60, "edges": 162, "tct": 5, "wcpl": 10, "rr": 0.933}
"""The 15/10 graph the paper analyses in section 5.1 (its Figures 10 and 11)."""

PAPER_TABLE4_QUOTED = {"mean_wcpl": 11.7, "mean_avg_random": 10.73, "tax_over": 2.5}
"""Averages the paper quotes in section 5.2: mean WCPL 11.7 steps, mean average random
length 10.73 steps, and the human forcing paths "over 2.5 times longer on average" than
the shortest route."""


def paper_table3_row(layers: int, max_nodes: int) -> PaperTable3Row | None:
    """The paper's Table 3 row of a configuration, or ``None`` if it has none."""
    for row in PAPER_TABLE3:
        if (row.layers, row.max_nodes) == (layers, max_nodes):
            return row
    return None


def paper_table4_row(trial: int) -> PaperTable4Row | None:
    """The paper's Table 4 row of a trial (1-based), or ``None`` beyond trial 10."""
    for row in PAPER_TABLE4:
        if row.trial == trial:
            return row
    return None
