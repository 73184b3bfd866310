"""The assembly state graph: which operations are feasible from which states.

:mod:`~asp.graph.feasibility` (the insertion oracle), :mod:`~asp.graph.state_keys` (the
state-key codec: which operations are enabled in which states),
:mod:`~asp.graph.enabled_kernel` (its numba inner loops), :mod:`~asp.graph.state_graph`
(the graph, built layer by layer), :mod:`~asp.graph.precedences` (derived
precedences and infeasibility proofs), :mod:`~asp.graph.symmetry` (the interchangeable-part
reduction), :mod:`~asp.graph.fasteners` (joining parts in one order, past the state limit),
:mod:`~asp.graph.fixed_order`
(that reduction undone for schedules), :mod:`~asp.graph.together` (which operations may run
at once, one rule), :mod:`~asp.graph.game_dag` (from the state graph to the game DAG),
:mod:`~asp.graph.game_states` (the game's states named) and
:mod:`~asp.graph.checker` (an independent plan checker that shares no code with the rest).
"""

from asp.lazy import lazy_exports

__all__, __getattr__ = lazy_exports(
    __name__,
    {
        "checker": ("check_line", "line_directions", "plan_operations"),
        "feasibility": ("insertion_oracle", "load_relations", "spec_relations"),
        "game_dag": ("game_dag",),
        "game_states": ("AlternateStates", "alternate_states"),
        "state_graph": ("StateGraph", "build_state_graph"),
        "precedences": ("Refutation", "infeasibility", "refutation", "with_derived_precedences"),
        "state_keys": ("OperationModel", "operation_model"),
        "symmetry": ("reduced_state_graph",),
    },
)
