"""asp: assembly sequence planning as a robot-vs-human game.

Rooms, from the ground up (each imports its own and lower floors only): the ground modules
(:mod:`asp.errors`, :mod:`asp.numbers`, :mod:`asp.atomic`, :mod:`asp.heap`,
:mod:`asp.cad_keys`, :mod:`asp.lazy`); :mod:`asp.game` (the game DAG with no assembly spec);
:mod:`asp.salbp` and :mod:`asp.spec`; :mod:`asp.graph` (the assembly state graph);
:mod:`asp.schedule` (CP-SAT) and :mod:`asp.fromcad` (a spec from a CAD file);
:mod:`asp.concurrent` and :mod:`asp.subassemblies`. Each room names what other packages may
use in its ``__all__`` (a sub-package's ``__init__``, a module's own).

Here: the game DAG's API for a notebook (:mod:`asp.game.dag`, :mod:`asp.game.io`,
:mod:`asp.game.solve`, :mod:`asp.game.synth`, :mod:`asp.game.metrics`).
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
