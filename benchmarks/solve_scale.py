"""Exact solve of a 1,000,000-node game DAG; compared with plain-Python backward induction.

Prints nodes, edges, seconds for the compiled solver (after a warm-up call that compiles or
loads the cached kernel) and for a dict-of-lists Python induction on the same graph, and
their ratio. Targets (issue 2): solve under 2 s on the 2-core machine, ratio 20x or more.

    python benchmarks/solve_scale.py [--nodes 1000000] [--out-degree 3] [--seed 0]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from asp.game.dag import ANY, HUMAN, ROBOT, from_arrays
from asp.game.solve import solve


def layered_dag(n: int, out_degree: int, width: int, seed: int):
    """A layered random DAG: ``width`` nodes a layer, ``out_degree`` edges to the next layers."""
    rng = np.random.default_rng(seed)
    src = np.repeat(np.arange(n - 1, dtype=np.int64), out_degree)
    layer_start = (src // width + 1) * width
    span = rng.integers(0, 2 * width, size=src.size)
    dst = np.minimum(layer_start + span, n - 1)
    # Drop duplicate edges, keep every node's first edge.
    key = np.unique(src * n + dst)
    src, dst = key // n, key % n
    indeg = np.bincount(dst, minlength=n)
    orphans = np.flatnonzero(indeg[1:] == 0) + 1
    src = np.concatenate([src, np.maximum(orphans - width, 0)])
    dst = np.concatenate([dst, orphans])
    return from_arrays(np.arange(n), src, dst, start=0, end=n - 1, validate=False)


def python_induction(dag) -> float:
    """Backward induction over (node, player) with dicts and lists: the plain baseline."""
    n = dag.n_nodes
    succ: dict[int, list[tuple[int, float]]] = {v: [] for v in range(n)}
    targets, costs = dag.targets.tolist(), dag.costs.tolist()
    indptr = dag.indptr.tolist()
    for v in range(n):
        succ[v] = [(targets[e], costs[e]) for e in range(indptr[v], indptr[v + 1])]
    value = {(dag.end, ROBOT): 0.0, (dag.end, HUMAN): 0.0}
    for v in range(n - 2, -1, -1):  # ids are topological
        value[v, ROBOT] = min(c + value[t, HUMAN] for t, c in succ[v])
        value[v, HUMAN] = max(c + value[t, ROBOT] for t, c in succ[v])
    return value[dag.start, ROBOT]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", type=int, default=1_000_000)
    parser.add_argument("--out-degree", type=int, default=3)
    parser.add_argument("--width", type=int, default=100)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    t0 = time.perf_counter()
    dag = layered_dag(args.nodes, args.out_degree, args.width, args.seed)
    build_s = time.perf_counter() - t0
    assert np.all(dag.sides == ANY)
    solve(from_arrays([0, 1], np.array([0]), np.array([1])))  # compile / load the kernel

    t0 = time.perf_counter()
    sol = solve(dag)
    solve_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    reference = python_induction(dag)
    python_s = time.perf_counter() - t0
    assert reference == sol.minimax, (reference, sol.minimax)

    print(f"nodes          {dag.n_nodes:>12,}")
    print(f"edges          {dag.n_edges:>12,}")
    print(f"build s        {build_s:>12.3f}")
    print(f"solve s        {solve_s:>12.3f}   (target < 2 s)")
    print(f"python s       {python_s:>12.3f}   (dict-of-lists backward induction)")
    print(f"ratio          {python_s / solve_s:>12.1f}x  (target >= 20x)")
    print(f"TCT {sol.tct:g}, W* {sol.minimax:g}")


if __name__ == "__main__":
    main()
