"""Every metric of `asmplan solve` on a 100,000-node game DAG with random fractional costs.

Issue 14: the exact random-human distribution kept one probability per distinct total cost,
so a 110-node graph with fractional costs took 114 s and 5.3 GB. The metrics now need no
distribution (mean, minimum and maximum come from the exact evaluation; RR from a bounded
dynamic program over the budget left, see `asp.game.metrics.probability_within`).

Prints, for the metrics of the robust policy (RR against the certified WCPL, as `asmplan
solve` does) and for RR against a lower reference WCPL (between the average and the
maximum: the dynamic program works until its cap, then the seeded simulation answers):
seconds and the process's peak resident memory. Targets: under 2 s and under 1 GB.

    python benchmarks/fractional_costs.py [--nodes 100000] [--out-degree 3] [--seed 0]
"""

from __future__ import annotations

import argparse
import resource
import time

import numpy as np
from solve_scale import layered_dag

from asp.game.dag import ANY, HUMAN, ROBOT, from_arrays
from asp.game.metrics import plan_metrics


def peak_mb() -> float:
    """Peak resident memory of this process so far, MB (Linux reports KB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def fractional_game(n: int, out_degree: int, seed: int):
    """A layered DAG with costs uniform in [0.1, 3) (3 decimals) and mixed sides."""
    base = layered_dag(n, out_degree, 100, seed)
    rng = np.random.default_rng(seed)
    costs = np.round(rng.uniform(0.1, 3.0, base.n_edges), 3)
    sides = rng.choice([ANY, ROBOT, HUMAN], size=base.n_edges, p=[0.6, 0.2, 0.2])
    # Every node keeps its first edge open to both players, so no one is ever stuck twice.
    sides[base.indptr[:-1][np.diff(base.indptr) > 0]] = ANY
    return from_arrays(
        base.node_ids, base.sources, base.targets, costs, sides.astype(np.int8), start=0, end=n - 1
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", type=int, default=100_000)
    parser.add_argument("--out-degree", type=int, default=3)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    plan_metrics(fractional_game(300, 3, 1))  # compile / load the kernels
    before = peak_mb()
    dag = fractional_game(args.nodes, args.out_degree, args.seed)

    t0 = time.perf_counter()
    m = plan_metrics(dag)
    solve_s = time.perf_counter() - t0
    solve_mb = peak_mb()

    lower = (m.avg_random + m.max_random) / 2
    t0 = time.perf_counter()
    low = plan_metrics(dag, wcpl=lower)
    lower_s = time.perf_counter() - t0

    print(f"nodes / edges        {dag.n_nodes:,} / {dag.n_edges:,}")
    print(f"TCT {m.tct:.3f}  W* {m.minimax:.3f}  avg random {m.avg_random:.3f}")
    print(f"solve metrics s      {solve_s:8.3f}   (target < 2 s); RR exact: {m.exact_distribution}")
    print(f"peak memory MB       {solve_mb:8.0f}   (target < 1024; {before:.0f} before the graph)")
    print(
        f"RR vs WCPL {lower:.3f} s {lower_s:6.3f}   rr {low.rr:.4f}, exact: "
        f"{low.exact_distribution} (sampled {low.rr_sampled:.4f})"
    )
    print(f"peak memory MB       {peak_mb():8.0f}   after both")


if __name__ == "__main__":
    main()
