"""W*(0) of the concurrent game against the CP-SAT makespan on every Scholl ``.IN2`` graph.

DESIGN.md ("The concurrent game"): every schedule whose operations start at time 0 or at a
completion is a policy of the cooperative game, so ``W*(0)`` must equal the CP-SAT optimum
on the same constraints. ``tests/asp/schedule/test_concurrent_baseline.py`` checks the graphs of up
to 5,000 states; this script checks every graph whose concurrent game fits in
``--max-nodes`` (SAWYER30 included) and prints, per graph, the states, both values, the
CP-SAT status and the seconds of each side. It exits 1 on a disagreement.

Data: Scholl (1993), Data of Assembly Line Balancing Problems, read from
``../shared/data/salbp``.

    python benchmarks/concurrent_cpsat_agreement.py [--max-nodes 3000000] [--time-limit 300]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from asp.concurrent.build import build_game
from asp.concurrent.model import concurrent_model
from asp.concurrent.robustness import value
from asp.errors import AsmplanError
from asp.game.solve import solve
from asp.graph.state_graph import build_state_graph
from asp.schedule.assembly_makespan import assembly_makespan
from asp.spec import load_spec

SALBP = Path(__file__).resolve().parents[2] / "shared" / "data" / "salbp"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-nodes", type=int, default=3_000_000)
    parser.add_argument("--time-limit", type=float, default=300.0)
    args = parser.parse_args()
    print(
        f"{'graph':10s} {'states':>9s} {'W*(0)':>8s} {'CP-SAT':>8s} {'status':>8s} "
        f"{'game s':>7s} {'cp-sat s':>8s}  agree"
    )
    bad = 0
    for path in sorted(SALBP.glob("*.IN2")):
        spec = load_spec(path)
        try:
            graph = build_state_graph(spec)
            t0 = time.perf_counter()
            game = build_game(concurrent_model(spec, graph), 0, max_nodes=args.max_nodes)
            cooperative = value(game, solve(game.dag), 0)
            t_game = time.perf_counter() - t0
        except AsmplanError as exc:
            print(f"{path.stem:10s} does not fit: {str(exc).splitlines()[0][:90]}")
            continue
        t0 = time.perf_counter()
        _, result = assembly_makespan(spec, graph, time_limit=args.time_limit)
        t_cp = time.perf_counter() - t0
        agree = result.status == "OPTIMAL" and result.objective == cooperative
        bad += not agree
        print(
            f"{path.stem:10s} {graph.n_states:9,d} {cooperative:8g} {result.objective!s:>8s} "
            f"{result.status:>8s} {t_game:7.1f} {t_cp:8.1f}  {'yes' if agree else 'NO'}",
            flush=True,
        )
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
