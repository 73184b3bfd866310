"""Small game DAGs for the arl tests."""

from asp.game.dag import ANY, HUMAN, ROBOT, GameDAG, from_edges
from tests.asp.figures import FIGURE4_EDGES, figure4  # noqa: F401  (re-exported)


def sided_time_dag() -> GameDAG:
    """Robot-only, human-only and shared moves with durations; the human passes at ``a``."""
    edges = [("s", "a"), ("s", "b"), ("a", "c"), ("a", "d"), ("b", "c"), ("c", "e"), ("d", "e")]
    sides = [ROBOT, ANY, ROBOT, ROBOT, HUMAN, ANY, HUMAN]
    costs = [2.0, 1.5, 3.0, 1.0, 2.5, 0.5, 4.0]
    return from_edges(
        ["s", "a", "b", "c", "d", "e"], edges, sides=sides, costs=costs, cost_model="time"
    )
