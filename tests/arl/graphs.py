"""Small game DAGs for the arl tests."""

from asp.dag import ANY, HUMAN, ROBOT, GameDAG, from_edges

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
    """The paper's Figure 4: fast path 1-2-9, robust choice 3 (start 1, end 9), W* = 3."""
    return from_edges(list(range(1, 10)), FIGURE4_EDGES, start=1, end=9)


def sided_time_dag() -> GameDAG:
    """Robot-only, human-only and shared moves with durations; the human passes at ``a``."""
    edges = [("s", "a"), ("s", "b"), ("a", "c"), ("a", "d"), ("b", "c"), ("c", "e"), ("d", "e")]
    sides = [ROBOT, ANY, ROBOT, ROBOT, HUMAN, ANY, HUMAN]
    costs = [2.0, 1.5, 3.0, 1.0, 2.5, 0.5, 4.0]
    return from_edges(
        ["s", "a", "b", "c", "d", "e"], edges, sides=sides, costs=costs, cost_model="time"
    )
