"""Small plans for the application-layer tests (no meshes, built in milliseconds)."""

from __future__ import annotations

from asmplan.pipeline import plan_document
from asp.game.solve import solve
from asp.graph.game_dag import game_dag
from asp.graph.game_states import alternate_states
from asp.graph.state_graph import build_state_graph
from asp.spec import spec_from_dict
from tests.asp.helpers_assembly import CELL

CHOICES = {
    "name": "choices",
    "agents": {"H": {"side": "human"}, "R1": {"side": "robot"}},
    "cost": "time",
    "operations": [
        {"id": "p", "description": "place plate", "agents": {"H": 3}},
        {"id": "q", "description": "place cover", "agents": {"H": 4}},
        {"id": "r", "description": "place pin", "agents": {"H": 2, "R1": 6}},
        {"id": "s", "description": "screw plate", "agents": {"R1": 5}, "after": ["p"]},
        {"id": "t", "description": "screw cover", "agents": {"R1": 4}, "after": ["q"]},
    ],
}
"""A concurrent job where the person has real choices: W*(0) 12, W*(1) 14, W*(2) = W*(inf) 15."""


def with_ranges(data: dict, extra: float = 2) -> dict:
    """The job with every person's duration ``d`` made the range ``[d, d + extra]``."""
    ops = [
        {**op, "agents": {a: ([d, d + extra] if a == "H" else d) for a, d in op["agents"].items()}}
        for op in data["operations"]
    ]
    return {**data, "operations": ops}


def cell_game(cost: str | None = None):
    """(spec, graph, dag, solution) of the small cell."""
    spec = spec_from_dict(CELL, source="cell.yaml")
    graph = build_state_graph(spec)
    dag = game_dag(graph, cost=cost)
    return spec, graph, dag, solve(dag)


def cell_plan(cost: str | None = None) -> dict:
    spec, graph, dag, solution = cell_game(cost)
    return plan_document(
        spec=spec, dag=dag, solution=solution, describe=alternate_states(graph, dag)
    )


def concurrent_cell(data: dict | None = None, *, max_k: int = 2, step: float | None = 1.0):
    """(spec, curve) of a job in the concurrent game (default: the small cell), budgets
    ``0..max_k`` (:func:`asp.concurrent.robustness.robustness`)."""
    from asp.concurrent.model import concurrent_model
    from asp.concurrent.robustness import robustness

    spec = spec_from_dict(data or CELL, source="cell.yaml")
    graph = build_state_graph(spec)
    return spec, robustness(concurrent_model(spec, graph, step=step), max_k=max_k)


def concurrent_plan(data: dict | None = None, *, max_k: int = 2, step: float | None = 1.0):
    """The plan document of a job in the concurrent game (no CP-SAT schedule)."""
    spec, curve = concurrent_cell(data, max_k=max_k, step=step)
    return plan_document(
        spec=spec,
        dag=curve.game.dag,
        solution=curve.solution,
        game=curve.game,
        extra={"robustness": curve.to_list()},
    )


def alike_plan(spec, relations, turn_model: str = "alternate", *, cost: str = "time") -> dict:
    """The plan document of a spec with alike parts, from the state graph reduced by
    symmetry (:func:`asp.graph.symmetry.reduced_state_graph`: the policy knows one canonical
    order of each class; ``interchangeable`` lists the classes). ``concurrent``: budgets
    0 to 2."""
    from asp.graph.symmetry import reduced_state_graph

    concurrent = turn_model == "concurrent"
    graph = reduced_state_graph(spec, relations, concurrent=concurrent)
    classes = graph.model.interchangeable
    if not concurrent:
        dag = game_dag(graph, cost=cost)
        return plan_document(
            spec=graph.spec,
            dag=dag,
            solution=solve(dag),
            describe=alternate_states(graph, dag),
            interchangeable=classes,
        )
    from asp.concurrent.model import concurrent_model
    from asp.concurrent.robustness import robustness

    curve = robustness(concurrent_model(graph.spec, graph, step=1.0), max_k=2)
    return plan_document(
        spec=graph.spec,
        dag=curve.game.dag,
        solution=curve.solution,
        game=curve.game,
        extra={"robustness": curve.to_list()},
        interchangeable=classes,
    )
