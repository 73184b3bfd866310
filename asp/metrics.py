"""The paper's metrics, made exact (``../shared/DESIGN.md``, "Metrics").

For a robot policy (by default the robust one):

- TCT and W* come from :func:`asp.solve.solve`;
- the certified WCPL is the policy's cost against an exact best-response human;
- against a uniformly random human, the exact mean, minimum and maximum come from
  :func:`asp.solve.evaluate_policy` (the random human plays every line with positive
  probability, so the maximum is the certified WCPL and the minimum the helpful human's
  cost): no distribution is needed for them;
- the resilience ratio RR = P(cost <= b) for a bound b is exact by
  :func:`probability_within`, a forward dynamic program over "the budget left" that only
  follows the budgets that can still matter (a budget at least the state's worst case is
  won, one below its best case lost). Against the certified WCPL it is 1 at once. Where
  more than :data:`MAX_DISTRIBUTION_ENTRIES` (state, budget) pairs would be needed (long
  games with fractional costs) RR is taken from the seeded simulation instead and
  ``exact_distribution`` is false;
- the paper's seeded simulation of 1,000 games stays beside them, vectorised over games.

The whole exact distribution (:func:`random_cost_distribution`) is kept for small games
(tests, reports) under the same cap. The rules of play come from :mod:`asp.rules`.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import asdict, dataclass

import numpy as np

from asp import rules
from asp.dag import GameDAG
from asp.errors import GameError
from asp.numbers import plain
from asp.rules import HUMAN, ROBOT
from asp.solve import PolicyEvaluation, Solution, evaluate_policy, node_order, play, solve

DEFAULT_GAMES = 1000
MAX_DISTRIBUTION_STATES = 200_000
"""Above this many reachable game states the whole distribution is not computed."""
MAX_DISTRIBUTION_ENTRIES = 250_000
"""Cap on the (game state, cost or budget) pairs an exact dynamic program may hold; past it
:func:`random_cost_distribution` and :func:`probability_within` answer ``None``, which bounds
their time and memory (about 2 s and 100 MB in the worst case on one core;
``benchmarks/fractional_costs.py``)."""


def human_move_table(dag: GameDAG) -> tuple[np.ndarray, np.ndarray]:
    """CSR of the human's moves: ``(indptr (n+1,), edges (k,))`` over edge indices."""
    return rules.move_table(dag, HUMAN)


def simulate_random_human(
    dag: GameDAG, robot_policy: np.ndarray, n_games: int = DEFAULT_GAMES, seed: int = 0
) -> np.ndarray:
    """Costs of ``n_games`` games of ``robot_policy`` against a uniformly random human.

    Parameters
    ----------
    robot_policy : (n,) int64 edge indices (see :func:`asp.solve.as_policy_array`)
    n_games : int
    seed : int
        Seed of ``numpy.random.default_rng``; the same seed gives the same costs.

    Returns
    -------
    (n_games,) float64
    """
    if n_games < 1:
        raise GameError(f"n_games: expected a positive integer, got {n_games}")
    rng = np.random.default_rng(seed)
    h_indptr, h_edges = rules.move_table(dag, HUMAN)
    can_move = rules.has_move(dag)
    move_cost = rules.move_costs(dag)
    node = np.full(n_games, dag.start, dtype=np.int64)
    player = np.full(n_games, rules.FIRST_PLAYER, dtype=np.int64)
    cost = np.zeros(n_games)
    for _ in range(2 * dag.n_nodes + 2):
        active = node != dag.end
        if not active.any():
            return cost
        edge = np.full(n_games, rules.PASS, dtype=np.int64)
        robots = active & (player == ROBOT) & can_move[ROBOT, node]
        edge[robots] = robot_policy[node[robots]]
        humans = active & (player == HUMAN)
        count = h_indptr[node[humans] + 1] - h_indptr[node[humans]]
        pick = np.floor(rng.random(humans.sum()) * np.maximum(count, 1)).astype(np.int64)
        chosen = np.full(count.shape, rules.PASS, dtype=np.int64)
        has = count > 0  # a human without a move passes
        chosen[has] = h_edges[h_indptr[node[humans]][has] + pick[has]]
        edge[humans] = chosen
        moving = edge != rules.PASS
        cost[moving] += move_cost[edge[moving]]
        node[moving] = dag.targets[edge[moving]]
        player[active] = rules.other(player[active])
    raise GameError("simulation did not reach the end node: is the graph acyclic?")


def _random_moves(dag: GameDAG, robot_policy, h_indptr, h_edges, v: int, p: int) -> list[int]:
    """The moves the random game may take in state ``(v, p)`` (each equally likely)."""
    if p == ROBOT:
        e = int(robot_policy[v])
        return [e] if e != rules.PASS else []
    return h_edges[h_indptr[v] : h_indptr[v + 1]].tolist()


def random_cost_distribution(
    dag: GameDAG, robot_policy: np.ndarray, max_entries: int = MAX_DISTRIBUTION_ENTRIES
) -> dict[float, float] | None:
    """Exact distribution of the cost of ``robot_policy`` against a uniformly random human.

    Returns a mapping cost -> probability (summing to 1; costs rounded to 9 decimals), or
    ``None`` when the policy reaches more than :data:`MAX_DISTRIBUTION_STATES` game states
    or the distributions would hold more than ``max_entries`` (state, cost) pairs (with
    fractional costs nearly every line has its own total).
    """
    h_indptr, h_edges = rules.move_table(dag, HUMAN)
    reach = rules.reachable_states(dag, robot_policy)
    if int(reach.sum()) > MAX_DISTRIBUTION_STATES:
        return None
    move_cost = rules.move_costs(dag)
    entries = 0
    dist: dict[tuple[int, int], dict[float, float]] = {}
    for v in node_order(dag)[::-1]:
        v = int(v)
        passes = []
        for p in rules.PLAYERS:
            if not reach[v, p]:
                continue
            if v == dag.end:
                dist[v, p] = {0.0: 1.0}
                continue
            moves = _random_moves(dag, robot_policy, h_indptr, h_edges, v, p)
            if not moves:
                passes.append(p)
                continue
            out: dict[float, float] = {}
            share = 1.0 / len(moves)
            for e in moves:
                c, t = float(move_cost[e]), int(dag.targets[e])
                for value, prob in dist[t, rules.other(p)].items():
                    key = round(value + c, 9)
                    out[key] = out.get(key, 0.0) + prob * share
            entries += len(out)
            if entries > max_entries:
                return None
            dist[v, p] = out
        for p in passes:  # a pass costs nothing: same distribution as the other side's turn
            dist[v, p] = dist[v, rules.other(p)]
    return dict(sorted(dist[dag.start, ROBOT].items()))


def probability_within(
    dag: GameDAG,
    robot_policy: np.ndarray,
    bound: float,
    *,
    evaluation: PolicyEvaluation | None = None,
    max_entries: int = MAX_DISTRIBUTION_ENTRIES,
) -> float | None:
    """Exact P(cost <= ``bound``) of ``robot_policy`` against a uniformly random human.

    A forward dynamic program over game states in topological order, carrying the
    probability of arriving with each budget (``bound`` minus the cost so far). A budget
    at least the state's worst case (:attr:`PolicyEvaluation.worst`) is won whatever
    happens, one below its best case is lost: only budgets in between are followed, so RR
    against the certified WCPL costs nothing and RR against a lower bound follows only the
    lines that can still decide it.

    Returns
    -------
    float or None
        The probability rounded to 12 decimals, or ``None`` when more than ``max_entries``
        (state, budget) pairs would be needed (the caller then samples).
    """
    ev = evaluate_policy(dag, robot_policy) if evaluation is None else evaluation
    worst, best = ev.worst, ev.best
    h_indptr, h_edges = rules.move_table(dag, HUMAN)
    can_move = rules.has_move(dag)
    move_cost = rules.move_costs(dag)
    order = node_order(dag)
    position = np.empty(dag.n_nodes, dtype=np.int64)
    position[order] = np.arange(dag.n_nodes)
    won: list[float] = []
    pending: dict[tuple[int, int], dict[float, float]] = {}
    heap: list[tuple[int, int, int, int]] = []
    entries = 0

    def send(v: int, p: int, budget: float, prob: float) -> bool:
        """Move ``prob`` to state ``(v, p)`` with ``budget`` left; False past the cap."""
        nonlocal entries
        if rules.cost_at_most(worst[v, p], budget):
            won.append(prob)
            return True
        if budget < best[v, p] and not rules.costs_close(budget, best[v, p]):
            return True  # lost whatever happens
        state = pending.get((v, p))
        if state is None:
            state = pending[v, p] = {}
            # At a node the side that passes goes first: its mass flows to the other side.
            heapq.heappush(heap, (int(position[v]), int(can_move[p, v]), v, p))
        key = round(budget, 9)
        if key not in state:
            entries += 1
            if entries > max_entries:
                return False
        state[key] = state.get(key, 0.0) + prob
        return True

    if not send(dag.start, rules.FIRST_PLAYER, float(bound), 1.0):
        return None
    while heap:
        _, _, v, p = heapq.heappop(heap)
        masses = pending.pop((v, p))
        moves = _random_moves(dag, robot_policy, h_indptr, h_edges, v, p)
        for budget, prob in masses.items():
            if not moves:  # a pass: same budget, the other side on turn
                ok = send(v, rules.other(p), budget, prob)
            else:
                share = prob / len(moves)
                ok = all(
                    send(int(dag.targets[e]), rules.other(p), budget - float(move_cost[e]), share)
                    for e in moves
                )
            if not ok:
                return None
    return round(math.fsum(won), 12)


def resilience_ratio(costs: np.ndarray | dict, wcpl: float) -> float:
    """Share (0..1) of games with cost <= ``wcpl``: from sampled costs or an exact distribution."""
    if isinstance(costs, dict):
        # Products of move probabilities carry rounding error: 1.0 must read as 1.0.
        return round(math.fsum(p for c, p in costs.items() if rules.cost_at_most(c, wcpl)), 12)
    costs = np.asarray(costs, dtype=np.float64)
    return float(np.mean(rules.cost_at_most(costs, wcpl)))


def is_robust_optimal(certified_wcpl: float, minimax: float) -> bool:
    """Whether a policy's certified WCPL equals the game value W* (within the tolerance)."""
    return bool(rules.costs_close(certified_wcpl, minimax))


@dataclass(frozen=True)
class PlanMetrics:
    """The metrics of one robot policy on one game DAG (costs in the DAG's cost model).

    ``rr``: exact share of random-human games within the reference WCPL (the paper's, when
    given, else the certified one); ``rr_certified``: within the certified WCPL (1.0 by
    construction). ``*_sampled``: the paper's seeded simulation. ``exact_distribution``:
    whether ``rr`` is exact (else it is the simulation's, see :func:`probability_within`).
    """

    nodes: int
    edges: int
    tct: float
    minimax: float
    wcpl: float
    certified_wcpl: float
    robust_optimal: bool
    robust_path: list
    avg_random: float
    max_random: float
    min_random: float
    rr: float
    rr_certified: float
    avg_random_sampled: float
    max_random_sampled: float
    rr_sampled: float
    games: int
    seed: int
    adversarial_tax: float | None
    exact_distribution: bool

    def to_dict(self) -> dict:
        return asdict(self)


def plan_metrics(
    dag: GameDAG,
    *,
    solution: Solution | None = None,
    robot_policy: np.ndarray | None = None,
    wcpl: float | None = None,
    n_games: int = DEFAULT_GAMES,
    seed: int = 0,
) -> PlanMetrics:
    """All metrics of ``robot_policy`` (default: the robust policy) on ``dag``.

    Parameters
    ----------
    solution : Solution, optional
        The exact solution (computed when not given).
    robot_policy : (n,) int64, optional
        The policy to evaluate; default the robust one.
    wcpl : float, optional
        The paper's WCPL (learned robot vs learned human) to compute RR against; default
        the certified WCPL.
    """
    solution = solve(dag) if solution is None else solution
    policy = solution.robot_policy if robot_policy is None else robot_policy
    evaluation = evaluate_policy(dag, policy)
    s = (dag.start, ROBOT)
    certified = float(evaluation.worst[s])
    reference = certified if wcpl is None else float(wcpl)
    sampled = simulate_random_human(dag, policy, n_games=n_games, seed=seed)
    rr = probability_within(dag, policy, reference, evaluation=evaluation)
    rr_cert = probability_within(dag, policy, certified, evaluation=evaluation)
    exact = rr is not None and rr_cert is not None
    if rr is None:
        rr = resilience_ratio(sampled, reference)
    if rr_cert is None:
        rr_cert = 1.0  # pragma: no cover - the certified WCPL is always won at the start
    # The path when the policy meets its best-response human (for the robust policy: both
    # sides play minimax).
    path, _ = play(dag, policy, evaluation.human_best_response)
    return PlanMetrics(
        nodes=dag.n_nodes,
        edges=dag.n_edges,
        tct=solution.tct,
        minimax=solution.minimax,
        wcpl=reference,
        certified_wcpl=certified,
        robust_optimal=is_robust_optimal(certified, solution.minimax),
        robust_path=[plain(dag.node_ids[v]) for v in path],
        avg_random=float(evaluation.expected[s]),
        max_random=certified,
        min_random=float(evaluation.best[s]),
        rr=rr,
        rr_certified=rr_cert,
        avg_random_sampled=float(sampled.mean()),
        max_random_sampled=float(sampled.max()),
        rr_sampled=resilience_ratio(sampled, reference),
        games=int(n_games),
        seed=int(seed),
        adversarial_tax=adversarial_tax(solution.tct, solution.minimax),
        exact_distribution=exact,
    )


def adversarial_tax(tct: float, minimax: float) -> float | None:
    """``W* / TCT``: how much an adversarial human can cost over full cooperation.

    1.0 when both are 0 (nothing to do, nothing to lose); undefined (``None``, ``null`` in
    JSON) when TCT is 0 but W* is not: no finite ratio says "free when cooperating, costly
    against an adversary".
    """
    if tct > rules.COST_TOL:
        return minimax / tct
    return 1.0 if minimax <= rules.COST_TOL else None
