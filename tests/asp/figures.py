"""Graphs from the paper, built in code."""

from asp.game.dag import GameDAG, from_edges

FIGURE4_EDGES = [
    (1, 2),
    (1, 3),
    (2, 9),
    (2, 6),
    (6, 7),
    (7, 8),
    (8, 9),
    (3, 4),
    (3, 5),
    (4, 9),
    (5, 9),
]


def figure4() -> GameDAG:
    """The paper's Figure 4: fast path 1-2-9, robust choice 3 (start 1, end 9)."""
    return from_edges(list(range(1, 10)), FIGURE4_EDGES, start=1, end=9)


SOLVE_KEYS = (
    "nodes",
    "edges",
    "tct",
    "minimax",
    "robust_path",
    "avg_random",
    "max_random",
    "rr",
    "adversarial_tax",
)
"""The keys issue 2 requires of ``asmplan solve --format json``."""
