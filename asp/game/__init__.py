"""The game DAG the robot and the human play on, with no assembly spec (what ``arl`` needs).

:mod:`~asp.game.rules` (the rules of play, written once), :mod:`~asp.game.dag` (the
array-backed DAG), :mod:`~asp.game.io` (its JSON and GraphML files),
:mod:`~asp.game.synth` (synthetic DAGs), :mod:`~asp.game.solve` (the exact solver),
:mod:`~asp.game.metrics` (the paper's metrics, exact), :mod:`~asp.game.plan` (the robust
plan as steps), :mod:`~asp.game.policy` (the robust policy as a table of states and
moves), :mod:`~asp.game.play` (a person playing one side),
:mod:`~asp.game.alike` (alike operations at run time) and :mod:`~asp.game.turns` (the turn
models, one entry each: what differs between them).
"""

from asp.lazy import lazy_exports

__all__, __getattr__ = lazy_exports(
    __name__,
    {
        "alike": ("AlikeMap",),
        "dag": (
            "ANY",
            "HUMAN",
            "ROBOT",
            "CodedLabels",
            "GameDAG",
            "from_arrays",
            "from_edges",
            "from_networkx",
            "ids_topological",
            "index_dtype",
        ),
        "io": ("load_dag", "save_dag"),
        "metrics": ("PlanMetrics", "adversarial_tax", "is_robust_optimal", "plan_metrics"),
        "plan": ("PlanStep", "relations_summary", "robust_plan"),
        "policy": (
            "PlayedPolicy",
            "PolicyTable",
            "StateDescriber",
            "played_policy",
            "policy_table",
        ),
        "play": ("ROBOT_KINDS", "GameSession", "fast_greedy_policy", "fmt", "side_name"),
        "rules": (
            "COST_MODELS",
            "SIDE_NAMES",
            "close_kernel",
            "cost_at_most",
            "costs_close",
            "edge_cost",
        ),
        "solve": ("Solution", "certified_worst_case", "evaluate_policy", "node_order", "solve"),
        "synth": ("synthetic_dag",),
        "turns": (
            "ALTERNATE",
            "CONCURRENT",
            "DEFAULT_TURN",
            "TURNS",
            "TurnModel",
            "expected_names",
            "turn_of",
        ),
    },
)
