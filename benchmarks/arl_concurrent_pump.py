"""The ``fast`` config on the vacuum pump's concurrent game (issue 13, part 5).

The concurrent game against the unbounded adversary (:func:`asp.concurrent.build_game`) is
trained with ``fast`` for each seed; a run is robust-optimal when the exact best response
(:func:`asp.concurrent.certified_worst_case`) to its greedy robot equals W*(inf). Printed
per seed: cycles, seconds, certified makespan; then the robust-optimal share. ``--unscaled``
trains with ``reward_scale="none"`` (PPO on rewards in seconds) for comparison; ``--n-steps``
another PPO ``n_steps`` (``fast`` on the concurrent game uses 32: 10 of 10 seeds robust-optimal,
12.5-19.6 s each on the loaded 2-core machine; 16 gave 7 of 10).

Usage::

    .venv/bin/python benchmarks/arl_concurrent_pump.py --seeds 10
    .venv/bin/python benchmarks/arl_concurrent_pump.py --seeds 5 --unscaled
    .venv/bin/python benchmarks/arl_concurrent_pump.py --seeds 10 --n-steps 32
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

import torch  # noqa: E402

from arl.config import get_config  # noqa: E402
from arl.trainer import train  # noqa: E402
from asmplan import pipeline  # noqa: E402
from asp.concurrent.build import build_game  # noqa: E402
from asp.concurrent.model import concurrent_model  # noqa: E402
from asp.concurrent.robustness import certified_worst_case  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10, help="training seeds 0..N-1")
    parser.add_argument("--unscaled", action="store_true", help="reward_scale none")
    parser.add_argument("--n-steps", type=int, default=None, help="PPO n_steps (default: fast's)")
    args = parser.parse_args()
    torch.set_num_threads(1)
    assembly = pipeline.load(REPO / "examples" / "vacuum_pump")
    t0 = time.perf_counter()
    game = build_game(concurrent_model(assembly.spec, pipeline.state_graph(assembly)), None)
    print(
        f"pump, concurrent game vs the unbounded adversary: {game.dag.n_nodes} nodes, "
        f"{game.dag.n_edges} edges ({time.perf_counter() - t0:.2f} s)"
    )
    cfg = get_config("fast", "concurrent")
    if args.unscaled:
        cfg = cfg.replace(name="fast-unscaled", reward_scale="none")
    if args.n_steps is not None:
        cfg = cfg.replace(name=f"{cfg.name}-n_steps={args.n_steps}", n_steps=args.n_steps)
    hits = 0
    for seed in range(args.seeds):
        t0 = time.perf_counter()
        result = train(game.dag, cfg, seed=seed)
        seconds = time.perf_counter() - t0
        exact = certified_worst_case(game, result.robot_policy)
        hit = abs(exact - result.minimax) <= 1e-9
        hits += hit
        print(
            f"seed {seed}: {len(result.cycles)} cycles, {seconds:.1f} s, certified "
            f"{exact:g} s, W*(inf) {result.minimax:g} s{'  robust-optimal' if hit else ''}",
            flush=True,
        )
    print(f"{cfg.name}: robust-optimal {hits}/{args.seeds}")


if __name__ == "__main__":
    main()
