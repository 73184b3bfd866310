"""The paper's metrics, made exact (``../shared/DESIGN.md``, "Metrics").

For a robot policy (by default the robust one):

- TCT and W* come from :func:`asp.solve.solve`;
- the certified WCPL is the policy's cost against an exact best-response human;
- the cost distribution against a uniformly random human is computed exactly by dynamic
  programming over the states the policy can reach (a probability per cost value), giving
  the exact mean, maximum and resilience ratio (RR);
- the paper's seeded simulation of 1,000 games stays beside them, vectorised over games.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from asp.dag import ANY, HUMAN, ROBOT, GameDAG
from asp.solve import Solution, evaluate_policy, node_order, play, solve

DEFAULT_GAMES = 1000
MAX_DISTRIBUTION_STATES = 200_000
"""Above this many reachable game states the exact distribution is skipped (RR sampled)."""


def human_move_table(dag: GameDAG) -> tuple[np.ndarray, np.ndarray]:
    """CSR of the human's moves: ``(indptr (n+1,), edges (k,))`` over edge indices."""
    allowed = (dag.sides == ANY) | (dag.sides == HUMAN)
    counts = np.bincount(dag.sources[allowed], minlength=dag.n_nodes)
    indptr = np.zeros(dag.n_nodes + 1, dtype=np.int64)
    np.cumsum(counts, out=indptr[1:])
    return indptr, np.flatnonzero(allowed).astype(np.int64)


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
        raise ValueError(f"n_games: expected a positive integer, got {n_games}")
    rng = np.random.default_rng(seed)
    h_indptr, h_edges = human_move_table(dag)
    robot_can = np.zeros(dag.n_nodes, dtype=bool)
    robot_sides = (dag.sides == ANY) | (dag.sides == ROBOT)
    robot_can[dag.sources[robot_sides]] = True
    node = np.full(n_games, dag.start, dtype=np.int64)
    player = np.full(n_games, ROBOT, dtype=np.int64)
    cost = np.zeros(n_games)
    for _ in range(2 * dag.n_nodes + 2):
        active = node != dag.end
        if not active.any():
            return cost
        edge = np.full(n_games, -1, dtype=np.int64)
        robots = active & (player == ROBOT) & robot_can[node]
        edge[robots] = robot_policy[node[robots]]
        humans = active & (player == HUMAN)
        count = h_indptr[node[humans] + 1] - h_indptr[node[humans]]
        pick = np.floor(rng.random(humans.sum()) * np.maximum(count, 1)).astype(np.int64)
        chosen = np.full(count.shape, -1, dtype=np.int64)
        has = count > 0  # a human without a move passes
        chosen[has] = h_edges[h_indptr[node[humans]][has] + pick[has]]
        edge[humans] = chosen
        moving = edge >= 0
        cost[moving] += dag.costs[edge[moving]]
        node[moving] = dag.targets[edge[moving]]
        player[active] = 1 - player[active]
    raise ValueError("simulation did not reach the end node: is the graph acyclic?")


def random_cost_distribution(dag: GameDAG, robot_policy: np.ndarray) -> dict[float, float] | None:
    """Exact distribution of the cost of ``robot_policy`` against a uniformly random human.

    Returns a mapping cost -> probability (summing to 1), or ``None`` when the policy
    reaches more than :data:`MAX_DISTRIBUTION_STATES` game states.
    """
    h_indptr, h_edges = human_move_table(dag)
    reach = _reachable_states(dag, robot_policy, h_indptr, h_edges)
    if reach is None:
        return None
    dist: dict[tuple[int, int], dict[float, float]] = {}
    for v in node_order(dag)[::-1]:
        v = int(v)
        passes = []
        for p in (ROBOT, HUMAN):
            if not reach[v, p]:
                continue
            if v == dag.end:
                dist[v, p] = {0.0: 1.0}
                continue
            if p == ROBOT:
                e = int(robot_policy[v])
                moves = [e] if e >= 0 else []
            else:
                moves = h_edges[h_indptr[v] : h_indptr[v + 1]].tolist()
            if not moves:
                passes.append(p)
                continue
            out: dict[float, float] = {}
            share = 1.0 / len(moves)
            for e in moves:
                c, t = float(dag.costs[e]), int(dag.targets[e])
                for value, prob in dist[t, 1 - p].items():
                    key = round(value + c, 9)
                    out[key] = out.get(key, 0.0) + prob * share
            dist[v, p] = out
        for p in passes:  # a pass costs nothing: same distribution as the other side's turn
            dist[v, p] = dist[v, 1 - p]
    return dict(sorted(dist[dag.start, ROBOT].items()))


def _reachable_states(dag, robot_policy, h_indptr, h_edges) -> np.ndarray | None:
    seen = np.zeros((dag.n_nodes, 2), dtype=bool)
    stack = [(dag.start, ROBOT)]
    seen[dag.start, ROBOT] = True
    count = 1
    while stack:
        v, p = stack.pop()
        if v == dag.end:
            continue
        if p == ROBOT:
            e = int(robot_policy[v])
            heads = [int(dag.targets[e])] if e >= 0 else [v]
        else:
            moves = h_edges[h_indptr[v] : h_indptr[v + 1]]
            heads = dag.targets[moves].tolist() if moves.size else [v]
        for t in heads:
            if not seen[t, 1 - p]:
                seen[t, 1 - p] = True
                count += 1
                if count > MAX_DISTRIBUTION_STATES:
                    return None
                stack.append((t, 1 - p))
    return seen


def resilience_ratio(costs: np.ndarray | dict, wcpl: float) -> float:
    """Share (0..1) of games with cost <= ``wcpl``: from sampled costs or an exact distribution."""
    if isinstance(costs, dict):
        # Products of move probabilities carry rounding error: 1.0 must read as 1.0.
        return round(math.fsum(p for c, p in costs.items() if c <= wcpl + 1e-9), 12)
    costs = np.asarray(costs, dtype=np.float64)
    return float(np.mean(costs <= wcpl + 1e-9))


@dataclass(frozen=True)
class PlanMetrics:
    """The metrics of one robot policy on one game DAG (costs in the DAG's cost model).

    ``rr``: exact share of random-human games within the reference WCPL (the paper's, when
    given, else the certified one); ``rr_certified``: within the certified WCPL (1.0 by
    construction). ``*_sampled``: the paper's seeded simulation.
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
    adversarial_tax: float
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
    dist = random_cost_distribution(dag, policy)
    sampled = simulate_random_human(dag, policy, n_games=n_games, seed=seed)
    if dist is not None:
        rr, rr_cert = resilience_ratio(dist, reference), resilience_ratio(dist, certified)
        min_random = min(dist)
    else:
        rr, rr_cert = resilience_ratio(sampled, reference), 1.0
        min_random = float(evaluation.best[s])
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
        robust_optimal=bool(abs(certified - solution.minimax) <= 1e-9),
        robust_path=[_plain(dag.node_ids[v]) for v in path],
        avg_random=float(evaluation.expected[s]),
        max_random=certified,
        min_random=float(min_random),
        rr=rr,
        rr_certified=rr_cert,
        avg_random_sampled=float(sampled.mean()),
        max_random_sampled=float(sampled.max()),
        rr_sampled=resilience_ratio(sampled, reference),
        games=int(n_games),
        seed=int(seed),
        adversarial_tax=(solution.minimax / solution.tct) if solution.tct > 0 else 1.0,
        exact_distribution=dist is not None,
    )


def _plain(x):
    return x.item() if hasattr(x, "item") else x
