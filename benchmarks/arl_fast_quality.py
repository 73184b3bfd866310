"""Quality of the ``fast`` config over many graphs, sizes and training seeds.

For every size ``L/N`` (``synthetic_dag(L, N, --max-actions, seed=g)``, graph seeds
``0..--graphs-1``) and every training seed, ``fast`` trains until its stop rule fires; a run is
robust-optimal when the certified WCPL of its greedy robot (against an exact best-response
human) equals W*. Printed per size and seed: the robust-optimal share, the median and max wall
time, the median cycles, the runs that stopped without converging and the misses
(graph, W*, certified WCPL, cycles).

Usage::

    .venv/bin/python benchmarks/arl_fast_quality.py
    .venv/bin/python benchmarks/arl_fast_quality.py --graphs 5 --sizes 15/10 --seeds 0
    .venv/bin/python benchmarks/arl_fast_quality.py --first-graph 100 --output q.json
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
from asp.game.synth import synthetic_dag  # noqa: E402


def _sizes(text: str) -> list[tuple[int, int]]:
    sizes = []
    for part in text.split(","):
        if part.strip():
            layers, nodes = part.strip().split("/")
            sizes.append((int(layers), int(nodes)))
    return sizes


def _ints(text: str) -> list[int]:
    return [int(x) for x in text.split(",") if x.strip()]


def _overrides(items: list[str]) -> dict:
    """``key=value`` pairs, values parsed as JSON (``net_arch=[64,64]``, ``ent_coef=0.02``)."""
    out = {}
    for item in items:
        key, _, value = item.partition("=")
        try:
            out[key] = json.loads(value)
        except json.JSONDecodeError:
            out[key] = value
        if key == "net_arch":
            out[key] = tuple(out[key])
    return out


def _warm_up(config: str) -> None:
    """Pay the one-off import and first-model costs before any timing."""
    tiny = get_config(config).replace(n_envs=4, n_steps=16, batch_size=64, phase_steps=64)
    train(synthetic_dag(3, 3, 2, seed=0), tiny.replace(max_cycles=1), seed=0)


def run(args: argparse.Namespace) -> dict:
    cfg = get_config(args.config)
    if args.max_cycles is not None:
        cfg = cfg.replace(max_cycles=args.max_cycles)
    if args.set:
        cfg = cfg.replace(**_overrides(args.set))
    graphs = range(args.first_graph, args.first_graph + args.graphs)
    rows, summary = [], []
    for layers, nodes in _sizes(args.sizes):
        dags = [synthetic_dag(layers, nodes, args.max_actions, seed=g) for g in graphs]
        for seed in _ints(args.seeds):
            runs = []
            for g, dag in zip(graphs, dags, strict=True):
                t0 = time.perf_counter()
                res = train(dag, cfg, seed=seed)
                wall = time.perf_counter() - t0
                run_ = {
                    "size": f"{layers}/{nodes}",
                    "graph": g,
                    "seed": seed,
                    "nodes": dag.n_nodes,
                    "minimax": res.minimax,
                    "certified_wcpl": res.certified_wcpl,
                    "wcpl": res.wcpl,
                    "robust_optimal": res.robust_optimal,
                    "converged": res.converged,
                    "cycles": len(res.cycles),
                    "wall_s": wall,
                }
                runs.append(run_)
                if args.verbose:
                    print(
                        f"  {layers}/{nodes} seed {seed} graph {g}: W* {res.minimax:g} "
                        f"certified {res.certified_wcpl:g} cycles {len(res.cycles)} "
                        f"{wall:.2f} s",
                        flush=True,
                    )
            rows.extend(runs)
            walls = [r["wall_s"] for r in runs]
            misses = [r for r in runs if not r["robust_optimal"]]
            item = {
                "size": f"{layers}/{nodes}",
                "seed": seed,
                "graphs": len(runs),
                "robust_optimal": len(runs) - len(misses),
                "median_wall_s": statistics.median(walls),
                "max_wall_s": max(walls),
                "median_cycles": statistics.median(r["cycles"] for r in runs),
                "not_converged": [r["graph"] for r in runs if not r["converged"]],
                "misses": [(r["graph"], r["minimax"], r["certified_wcpl"]) for r in misses],
            }
            summary.append(item)
            miss_text = (
                ", ".join(
                    f"g{r['graph']} W*={r['minimax']:g} cert={r['certified_wcpl']:g} "
                    f"({r['cycles']} cyc{'' if r['converged'] else ', not converged'})"
                    for r in misses
                )
                or "-"
            )
            print(
                f"{item['size']:>6} seed {seed}: robust-optimal {item['robust_optimal']}/"
                f"{item['graphs']}, median {item['median_wall_s']:.2f} s, max "
                f"{item['max_wall_s']:.2f} s, median cycles {item['median_cycles']:g}, "
                f"not converged {len(item['not_converged'])}; misses: {miss_text}",
                flush=True,
            )
    total = len(rows)
    good = sum(r["robust_optimal"] for r in rows)
    print(f"total: robust-optimal {good}/{total}")
    return {"args": vars(args), "config": cfg.to_dict(), "rows": rows, "summary": summary}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default="fast", help="config name (default: fast)")
    parser.add_argument("--sizes", default="15/10,20/10", help="comma-separated layers/nodes")
    parser.add_argument("--max-actions", type=int, default=4)
    parser.add_argument("--graphs", type=int, default=20, help="graphs per size")
    parser.add_argument("--first-graph", type=int, default=0, help="first graph seed")
    parser.add_argument("--seeds", default="0,1", help="comma-separated training seeds")
    parser.add_argument(
        "--set", action="append", default=[], metavar="KEY=VALUE", help="override a config field"
    )
    parser.add_argument("--max-cycles", type=int, default=None, help="cap on cycles")
    parser.add_argument("--threads", type=int, default=1, help="torch threads")
    parser.add_argument("--verbose", action="store_true", help="print every run")
    parser.add_argument("--output", type=Path, default=None, help="write the results as JSON")
    args = parser.parse_args(argv)
    torch.set_num_threads(args.threads)
    _warm_up(args.config)
    results = run(args)
    if args.output is not None:
        write_text(args.output, json.dumps(results, indent=1, default=str) + "\n")


if __name__ == "__main__":
    main()
