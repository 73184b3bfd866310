"""The price of robustness, ``W*(k)`` for ``k = 0, 1, ...`` and ``W*(inf)`` (:func:`robustness`),
and what a robot policy guarantees (:func:`certified_worst_case`, :func:`schedule_rule`).

Exactness of W*(0): with budget 0 and fixed durations the robot side controls every start;
the best makespan over event-driven schedules (each operation starts at time 0 or at a
completion) is the optimum over all schedules (a left shift of any feasible schedule is
event-driven), so ``W*(0)`` equals the CP-SAT optimum on the same rules
(:func:`assembly_makespan`).
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from asp.concurrent.build import DEFAULT_MAX_NODES, ConcurrentGame, build_game
from asp.concurrent.model import UNBOUNDED, WAIT, ConcurrentModel
from asp.errors import GameError, GameLimit
from asp.game.dag import HUMAN, ROBOT
from asp.game.rules import costs_close
from asp.game.solve import Solution, evaluate_policy, solve
from asp.numbers import json_number

DEFAULT_MAX_K = 12
"""Largest deviation budget tried when looking for the flat part of the curve."""


@dataclass(frozen=True, eq=False)
class Robustness:
    """The price of robustness: ``W*(k)`` for ``k = 0..K`` and ``W*(inf)``.

    Attributes
    ----------
    bounds : tuple of float
        ``W*(0), W*(1), ..., W*(K)``: at least up to ``k = 2`` and up to a ``k`` with
        ``W*(k) == W*(inf)`` (budgets double until then), or ``max_k``.
    unbounded : float
        ``W*(inf)``, the fully adversarial bound.
    game, solution : ConcurrentGame, Solution
        The game with budgets ``0..K`` and its exact solution: the robust plan is its policy
        from the start of budget ``K`` (it guarantees ``W*(K)`` against any person who
        deviates at most ``K`` times; ``W*(K) == W*(inf)`` when ``flat``).
    adversary, adversary_solution : ConcurrentGame, Solution
        The unbounded game and its solution.
    flat : bool
        Whether ``W*(K) == W*(inf)`` (else ``max_k`` stopped the curve).
    """

    bounds: tuple[float, ...]
    unbounded: float
    game: ConcurrentGame
    solution: Solution
    adversary: ConcurrentGame
    adversary_solution: Solution
    flat: bool
    seconds: float

    @property
    def k(self) -> int:
        """The largest budget of the curve (the robust plan's)."""
        return len(self.bounds) - 1

    def to_list(self) -> list[dict]:
        """``[{"k": 0, "bound": ...}, ..., {"k": None, "bound": W*(inf)}]``."""
        out = [{"k": k, "bound": json_number(b, 6)} for k, b in enumerate(self.bounds)]
        return [*out, {"k": None, "bound": json_number(self.unbounded, 6)}]


def value(game: ConcurrentGame, solution: Solution, budget: int) -> float:
    """``W*(budget)``: the game value at the start node of ``budget``."""
    return float(solution.value[game.starts[budget], ROBOT])


def robustness(
    model: ConcurrentModel,
    *,
    max_k: int = DEFAULT_MAX_K,
    max_nodes: int = DEFAULT_MAX_NODES,
    progress: bool = False,
) -> Robustness:
    """Solve the concurrent game exactly for ``k = 0, 1, ...`` until ``W*(k) == W*(inf)``.

    The curve is non-decreasing and bounded by ``W*(inf)``, which it reaches once the budget
    covers every human decision. Budgets double (2, 4, 8, ...) until the curve is flat;
    ``max_k`` bounds the search, and so does ``max_nodes``: a doubled game over the limit
    leaves the curve as it was (``flat`` False). The first game over the limit is an error
    naming ``--max-k``.
    """
    if max_k < 0:
        raise GameError(f"max_k: expected a deviation budget >= 0, got {max_k}")
    t0 = time.perf_counter()
    adversary = build_game(model, None, max_nodes=max_nodes, progress=progress)
    adv_sol = solve(adversary.dag)
    top = float(adv_sol.value[adversary.starts[UNBOUNDED], ROBOT])
    if progress:
        print(
            f"concurrent game, unbounded adversary: {adversary.dag.n_nodes:,} nodes, "
            f"{adversary.dag.n_edges:,} edges, W*(inf) = {top:g} ({adversary.seconds:.2f} s)",
            file=sys.stderr,
        )
    k = min(2, max_k)
    game = None
    while True:
        try:
            bigger = build_game(model, k, max_nodes=max_nodes, progress=progress)
        except GameLimit:
            if game is None:
                raise
            break  # the curve so far stands; ``flat`` stays False and the report says so
        game = bigger
        sol = solve(game.dag)
        bounds = [value(game, sol, b) for b in range(k + 1)]
        if progress:
            print(
                f"concurrent game, budgets 0..{k}: {game.dag.n_nodes:,} nodes, "
                f"{game.dag.n_edges:,} edges ({game.seconds:.2f} s)",
                file=sys.stderr,
            )
        flat = _same(bounds[-1], top)
        if flat or k >= max_k:
            break
        k = min(2 * k, max_k)
    return Robustness(
        bounds=tuple(bounds),
        unbounded=top,
        game=game,
        solution=sol,
        adversary=adversary,
        adversary_solution=adv_sol,
        flat=flat,
        seconds=time.perf_counter() - t0,
    )


def _same(a: float, b: float) -> bool:
    return bool(costs_close(a, b))


RobotRule = Callable[[ConcurrentGame, int, list[int]], int]
"""A robot policy as a rule: ``(game, robot node, its edge indices) -> the edge taken``."""


def policy_array(game: ConcurrentGame, rule: RobotRule) -> np.ndarray:
    """(n,) int64 edge per robot node of a robot policy given as a rule."""
    dag = game.dag
    out = np.full(dag.n_nodes, -1, dtype=np.int64)
    for v, key in enumerate(game.nodes):
        if key[0] == "R":
            edges = list(dag.out_edges(v))
            if edges:
                out[v] = rule(game, v, edges)
    return out


def certified_worst_case(game: ConcurrentGame, policy, budget: int | None = None) -> float:
    """The exact worst-case makespan of a robot policy against a best-response human.

    Parameters
    ----------
    policy : (n,) int array of robot edges, or a :data:`RobotRule`
    budget : int, optional
        The start's budget (default: the game's largest, or unbounded).
    """
    if callable(policy):
        policy = policy_array(game, policy)
    b = game.budgets[-1] if budget is None else (UNBOUNDED if game.unbounded else int(budget))
    evaluation = evaluate_policy(game.dag, policy)
    return float(evaluation.worst[game.starts[b], ROBOT])


def schedule_rule(rows: list[dict]) -> RobotRule:
    """The robot policy of a fixed schedule (a plan that ignores what the person does).

    ``rows`` are ``{"task", "agent", "start"}`` (a CP-SAT schedule). Each worker keeps the
    list of its operations in start order and wants the first one not yet done or running
    (the person is told it). At an event the rule takes the commitment in which every free
    worker does what it wants, if that is valid; otherwise (a deviation made the wanted
    operation impossible for now) the valid commitment with the most workers as wanted,
    ties by edge order: the schedule has no answer there, it keeps as much of it as it can.
    """
    order: dict[str, list[str]] = {}
    for row in sorted(rows, key=lambda r: (r["start"], r["task"])):
        order.setdefault(str(row["agent"]), []).append(str(row["task"]))

    def rule(game: ConcurrentGame, v: int, edges: list[int]) -> int:
        model = game.model
        _, state, running, budget, _ = game.nodes[v]
        done = model.graph.key(state)
        busy = {o for o, _ in running if o != WAIT}
        ids = model.spec.op_ids
        want = []
        for w, x in enumerate(model.workers):
            if running[w][0] != WAIT or (x.side == HUMAN and budget == UNBOUNDED):
                want.append(None)
                continue
            nxt = WAIT
            for oid in order.get(x.name, []):
                i = ids.index(oid)
                if not done >> i & 1 and i not in busy:
                    nxt = i
                    break
            want.append(nxt)
        # The closest valid commitment: most workers as wanted, ties by edge order.
        best, best_score = edges[0], -1
        for e in edges:
            ops = game.actions[e].ops
            score = sum(1 for w in range(len(want)) if want[w] is not None and ops[w] == want[w])
            exact = all(want[w] is None or ops[w] == want[w] for w in range(len(want)))
            score += 1000 * exact
            if score > best_score:
                best, best_score = e, score
        return best

    return rule
