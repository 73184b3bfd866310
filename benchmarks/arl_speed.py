"""Speed and quality of alternating PPO: the ``paper`` config against ``fast``.

For each of ``--graphs`` seeded synthetic 15/10/4 graphs (``synthetic_dag(15, 10, 4, seed=i)``)
every config trains from seed 0 until its stop rule fires (or ``--max-cycles``); the table
gives the wall time to stop, the cycles, the certified WCPL of the greedy robot against an
exact best-response human, W* and whether the robot is robust-optimal (certified == W*).
The summary gives the median per-graph time ratio paper/fast and each robust-optimal share.

Usage::

    .venv/bin/python benchmarks/arl_speed.py --graphs 10
    .venv/bin/python benchmarks/arl_speed.py --graphs 3 --configs fast --max-cycles 20
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import torch  # noqa: E402

from arl.config import get_config  # noqa: E402
from arl.trainer import train  # noqa: E402
from asp.atomic import write_text  # noqa: E402
from asp.game.solve import solve  # noqa: E402
from asp.game.synth import synthetic_dag  # noqa: E402


def _warm_up() -> None:
    """Pay the one-off import and first-model costs before any timing."""
    tiny = get_config("fast").replace(n_envs=4, n_steps=16, batch_size=64, phase_steps=64)
    train(synthetic_dag(3, 3, 2, seed=0), tiny.replace(max_cycles=1), seed=0)
    train(
        synthetic_dag(3, 3, 2, seed=0),
        get_config("paper").replace(n_steps=64, phase_steps=64, n_epochs=1, max_cycles=1),
        seed=0,
    )


def run(args: argparse.Namespace) -> dict:
    configs = [c.strip() for c in args.configs.split(",") if c.strip()]
    rows = []
    print(
        f"{'graph':>5} {'nodes':>5} {'edges':>5} {'W*':>4} "
        + " ".join(f"{c + ' s':>9} {'cyc':>3} {'cert':>4} {'rob':>3}" for c in configs),
        flush=True,
    )
    for i in range(args.graphs):
        dag = synthetic_dag(args.layers, args.max_nodes, args.max_actions, seed=i)
        w_star = solve(dag).minimax
        row = {"graph": i, "nodes": dag.n_nodes, "edges": dag.n_edges, "minimax": w_star}
        for name in configs:
            cfg = get_config(name)
            if args.max_cycles is not None:
                cfg = cfg.replace(max_cycles=args.max_cycles)
            t0 = time.perf_counter()
            result = train(dag, cfg, seed=args.seed)
            wall = time.perf_counter() - t0
            first_robust = next(
                (c["cycle"] for c in result.cycles if c["certified_wcpl"] == w_star), None
            )
            row[name] = {
                "wall_s": wall,
                "cycles": len(result.cycles),
                "converged": result.converged,
                "wcpl": result.wcpl,
                "certified_wcpl": result.certified_wcpl,
                "robust_optimal": result.robust_optimal,
                "first_robust_cycle": first_robust,
            }
        rows.append(row)
        print(
            f"{i:>5} {dag.n_nodes:>5} {dag.n_edges:>5} {w_star:>4g} "
            + " ".join(
                f"{row[c]['wall_s']:>9.2f} {row[c]['cycles']:>3} "
                f"{row[c]['certified_wcpl']:>4g} {'yes' if row[c]['robust_optimal'] else 'no':>3}"
                for c in configs
            ),
            flush=True,
        )
    summary: dict = {}
    for name in configs:
        summary[name] = {
            "median_wall_s": statistics.median(r[name]["wall_s"] for r in rows),
            "robust_optimal": sum(r[name]["robust_optimal"] for r in rows),
            "graphs": len(rows),
        }
        print(
            f"{name}: median {summary[name]['median_wall_s']:.2f} s, robust-optimal "
            f"{summary[name]['robust_optimal']}/{len(rows)}"
        )
    if "paper" in configs and "fast" in configs:
        ratios = [r["paper"]["wall_s"] / r["fast"]["wall_s"] for r in rows]
        summary["median_ratio_paper_fast"] = statistics.median(ratios)
        print(f"median time ratio paper/fast: {summary['median_ratio_paper_fast']:.1f}x")
    return {"args": vars(args), "rows": rows, "summary": summary}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--graphs", type=int, default=10, help="number of seeded graphs")
    parser.add_argument("--configs", default="paper,fast", help="comma-separated configs")
    parser.add_argument("--max-cycles", type=int, default=None, help="cap on cycles")
    parser.add_argument("--seed", type=int, default=0, help="training seed")
    parser.add_argument("--layers", type=int, default=15)
    parser.add_argument("--max-nodes", type=int, default=10)
    parser.add_argument("--max-actions", type=int, default=4)
    parser.add_argument("--threads", type=int, default=1, help="torch threads (both configs)")
    parser.add_argument("--output", type=Path, default=None, help="write the results as JSON")
    args = parser.parse_args(argv)
    torch.set_num_threads(args.threads)
    _warm_up()
    results = run(args)
    if args.output is not None:
        write_text(args.output, json.dumps(results, indent=1, default=str) + "\n")


if __name__ == "__main__":
    main()
