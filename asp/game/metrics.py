"""The paper's metrics, made exact (``../shared/DESIGN.md``, "Metrics").

For a robot policy (by default the robust one):

- TCT and W* come from :func:`asp.game.solve.solve`;
- the certified WCPL is the policy's cost against an exact best-response human;
- against a uniformly random human, the exact mean, minimum and maximum come from
  :func:`asp.game.solve.evaluate_policy` (the random human plays every line with positive
  probability, so the maximum is the certified WCPL and the minimum the helpful human's
  cost): no distribution is needed for them;
- the resilience ratio RR = P(cost <= b) for a bound b is exact by
  :func:`probability_within`, a forward dynamic program over "the budget left" that only
  follows the budgets that can still matter (a budget at least the state's worst case is
  won, one below its best case lost). Against the certified WCPL it is 1 at once. Where
  more than :data:`MAX_RR_ARRIVALS` (state, budget) arrivals would be needed (long games
  with fractional costs) RR is taken from the seeded simulation instead and
  ``exact_distribution`` is false;
- the paper's seeded simulation of 1,000 games stays beside them, vectorised over games.

The whole exact distribution (:func:`random_cost_distribution`) is kept for small games
(tests, reports) under its own cap (:data:`MAX_DISTRIBUTION_ENTRIES`). The rules of play
come from :mod:`asp.game.rules`.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numba
import numpy as np

from asp.errors import GameError
from asp.game import rules
from asp.game.dag import GameDAG
from asp.game.rules import HUMAN, ROBOT, close_kernel, edge_cost
from asp.game.solve import PolicyEvaluation, Solution, evaluate_policy, node_order, play, solve
from asp.numbers import plain

DEFAULT_GAMES = 1000
MAX_DISTRIBUTION_STATES = 200_000
"""Above this many reachable game states the whole distribution is not computed."""
MAX_DISTRIBUTION_ENTRIES = 250_000
"""Cap on the (game state, cost) pairs of :func:`random_cost_distribution` (Python dicts);
past it the answer is ``None`` (about 2 s and 100 MB at most)."""
MAX_RR_ARRIVALS = 1_000_000
"""Cap on the (game state, budget) arrivals of :func:`probability_within` (compiled); past it
the answer is ``None`` and RR is sampled (about 1 s and 100 MB at most on one core,
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
    robot_policy : (n,) int64 edge indices (see :func:`asp.game.solve.as_policy_array`)
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
    max_entries: int = MAX_RR_ARRIVALS,
) -> float | None:
    """Exact P(cost <= ``bound``) of ``robot_policy`` against a uniformly random human.

    A forward dynamic program over game states in topological order, carrying the
    probability of arriving with each budget (``bound`` minus the cost so far). A budget
    at least the state's worst case (:attr:`PolicyEvaluation.worst`) is won whatever
    happens, one below its best case is lost: only budgets in between are followed, so RR
    against the certified WCPL costs nothing and RR against a lower bound follows only the
    lines that can still decide it. Arrivals at a state with the same budget (within the
    cost tolerance) are merged (compiled: a heap ordered by state, then budget).

    Returns
    -------
    float or None
        The probability rounded to 12 decimals, or ``None`` when more than ``max_entries``
        (state, budget) arrivals would be needed (the caller then samples).
    """
    ev = evaluate_policy(dag, robot_policy) if evaluation is None else evaluation
    t = rules.kernel_tables(dag)
    order = node_order(dag)
    position = np.empty(dag.n_nodes, dtype=np.int64)
    position[order] = np.arange(dag.n_nodes)
    prob = _within_kernel(
        t.indptr,
        t.targets,
        t.cost,
        t.code,
        t.may,
        np.asarray(robot_policy, dtype=np.int64),
        order,
        position,
        ev.worst,
        ev.best,
        dag.start,
        float(bound),
        t.tol,
        int(max_entries),
    )
    return None if prob < 0 else round(prob, 12)


@numba.njit(cache=True)
def _heap_push(hs, hb, hp, size, skey, budget, prob):  # pragma: no cover - compiled
    """Push ``(skey, budget) -> prob`` on the min-heap of ``size`` entries; return the arrays
    (grown when full) and the new size."""
    if size == hs.shape[0]:
        hs = np.concatenate((hs, np.empty_like(hs)))
        hb = np.concatenate((hb, np.empty_like(hb)))
        hp = np.concatenate((hp, np.empty_like(hp)))
    i = size
    while i > 0:
        parent = (i - 1) // 2
        if hs[parent] < skey or (hs[parent] == skey and hb[parent] <= budget):
            break
        hs[i], hb[i], hp[i] = hs[parent], hb[parent], hp[parent]
        i = parent
    hs[i], hb[i], hp[i] = skey, budget, prob
    return hs, hb, hp, size + 1


@numba.njit(cache=True)
def _heap_pop(hs, hb, hp, size):  # pragma: no cover - compiled
    """Remove the smallest entry; return it and the new size."""
    skey, budget, prob = hs[0], hb[0], hp[0]
    size -= 1
    ls, lb, lp = hs[size], hb[size], hp[size]
    i = 0
    while True:
        child = 2 * i + 1
        if child >= size:
            break
        right = child + 1
        if right < size and (
            hs[right] < hs[child] or (hs[right] == hs[child] and hb[right] < hb[child])
        ):
            child = right
        if ls < hs[child] or (ls == hs[child] and lb <= hb[child]):
            break
        hs[i], hb[i], hp[i] = hs[child], hb[child], hp[child]
        i = child
    if size > 0:
        hs[i], hb[i], hp[i] = ls, lb, lp
    return skey, budget, prob, size


@numba.njit(cache=True)
def _arrive(
    heap, size, sums, v, p, budget, prob, indptr, may, position, worst, best, tol
):  # pragma: no cover
    """Mass ``prob`` arrives at state ``(v, p)`` with ``budget`` left: won (added to
    ``sums``, a Neumaier-compensated ``[sum, carry, arrivals]``), lost, or pushed on the heap.
    Returns the heap arrays and size."""
    hs, hb, hp = heap
    w, b = worst[v, p], best[v, p]
    if w <= budget or close_kernel(w, budget, tol):  # won whatever happens
        total = sums[0] + prob
        if abs(sums[0]) >= abs(prob):
            sums[1] += (sums[0] - total) + prob
        else:
            sums[1] += (prob - total) + sums[0]
        sums[0] = total
    elif budget >= b or close_kernel(budget, b, tol):  # still open: follow it
        sums[2] += 1.0
        phase = 0
        for e in range(indptr[v], indptr[v + 1]):
            if may[p, e]:
                phase = 1
                break
        hs, hb, hp, size = _heap_push(
            hs, hb, hp, size, 4 * position[v] + 2 * phase + p, budget, prob
        )
    return (hs, hb, hp), size


@numba.njit(cache=True)
def _within_kernel(
    indptr, targets, cost, code, may, policy, order, position, worst, best, start, bound, tol, cap
):  # pragma: no cover - compiled
    """P(cost <= bound) by the forward budget program (see :func:`probability_within`);
    -1 past ``cap`` arrivals.

    A state's heap key is ``4 * position + 2 * phase + player``: states in topological
    order, and at one node the side that passes (phase 0) before the side that moves, so
    that a pass's mass arrives before the other side's state is expanded.
    """
    heap = (np.empty(64, np.int64), np.empty(64, np.float64), np.empty(64, np.float64))
    sums = np.zeros(3)
    tables = (indptr, may, position, worst, best, tol)
    heap, size = _arrive(heap, 0, sums, start, ROBOT, bound, 1.0, *tables)
    while size > 0:
        if sums[2] > cap:
            return -1.0
        # Pop a state's smallest budget and merge every arrival with the same budget.
        hs, hb, hp = heap
        skey, budget, prob, size = _heap_pop(hs, hb, hp, size)
        while size > 0 and hs[0] == skey and close_kernel(hb[0], budget, tol):
            _, _, more, size = _heap_pop(hs, hb, hp, size)
            prob += more
        v, p = order[skey // 4], skey % 2
        # The robot's policy move, each human move alike, or a pass (same node and budget).
        if p == ROBOT and policy[v] >= 0 and may[ROBOT, policy[v]]:
            e = policy[v]
            heap, size = _arrive(
                heap,
                size,
                sums,
                targets[e],
                HUMAN,
                budget - edge_cost(cost, code, e),
                prob,
                *tables,
            )
            continue
        count = 0
        if p == HUMAN:
            for e in range(indptr[v], indptr[v + 1]):
                if may[HUMAN, e]:
                    count += 1
        if count == 0:
            heap, size = _arrive(heap, size, sums, v, 1 - p, budget, prob, *tables)  # a pass
            continue
        for e in range(indptr[v], indptr[v + 1]):
            if may[HUMAN, e]:
                t, left = targets[e], budget - edge_cost(cost, code, e)
                heap, size = _arrive(heap, size, sums, t, ROBOT, left, prob / count, *tables)
    return sums[0] + sums[1]


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
