"""asp: assembly sequence planning as a robot-vs-human game.

The game DAG (:mod:`asp.game.dag`), the rules of play on it (:mod:`asp.game.rules`), its
file formats (:mod:`asp.game.io`), the synthetic generator (:mod:`asp.game.synth`), the exact
solver (:mod:`asp.game.solve`) and the metrics (:mod:`asp.game.metrics`).
This package never imports torch.
"""

from asp.game.dag import ANY, HUMAN, ROBOT, GameDAG, from_arrays, from_edges, from_networkx
from asp.game.io import load_dag, save_dag
from asp.game.metrics import PlanMetrics, plan_metrics
from asp.game.solve import Solution, certified_worst_case, evaluate_policy, solve
from asp.game.synth import synthetic_dag

__all__ = [
    "ANY",
    "HUMAN",
    "ROBOT",
    "GameDAG",
    "PlanMetrics",
    "Solution",
    "certified_worst_case",
    "evaluate_policy",
    "from_arrays",
    "from_edges",
    "from_networkx",
    "load_dag",
    "plan_metrics",
    "save_dag",
    "solve",
    "synthetic_dag",
]
