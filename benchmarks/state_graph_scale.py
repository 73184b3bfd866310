"""State graph, game DAG and exact solve on Scholl's precedence graphs (``.IN2``).

Prints, per file, the assembly state graph (states, transitions, exact number of feasible
sequences), the game DAG and the seconds of each stage, and the process's peak RSS.
Target: KILBRID (45 tasks, 626,575 states, 4,866,716 transitions) in under 5 s for the
state graph and the exact solve together.

Data: Scholl, A. (1993), Data of Assembly Line Balancing Problems, TH Darmstadt.

Usage: ``python benchmarks/state_graph_scale.py [FOLDER]``
"""

from __future__ import annotations

import resource
import sys
import time
from pathlib import Path

from asp.game import game_dag
from asp.salbp import salbp_spec
from asp.solve import solve
from asp.state_graph import build_state_graph
from asp.synth import synthetic_dag

DEFAULT = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "salbp"
TARGET_S = 5.0


def peak_rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # Linux: KiB


def main(folder: Path = DEFAULT) -> None:
    files = sorted(folder.glob("*.IN2"), key=lambda p: len(p.read_text(encoding="latin-1")))
    if not files:
        raise SystemExit(f"no .IN2 files in {folder}")
    solve(synthetic_dag(3, 3, 2, 0))  # load the compiled solver kernels once
    header = (
        f"{'file':10s} {'ops':>4s} {'states':>9s} {'transitions':>12s} {'sequences':>10s} "
        f"{'graph s':>8s} {'dag s':>7s} {'solve s':>8s} {'total s':>8s} {'TCT':>5s} "
        f"{'peak MB':>8s}"
    )
    print(header)
    print("-" * len(header))
    for path in files:
        spec = salbp_spec(path)
        t0 = time.perf_counter()
        graph = build_state_graph(spec)
        t1 = time.perf_counter()
        dag = game_dag(graph)
        t2 = time.perf_counter()
        sol = solve(dag)
        t3 = time.perf_counter()
        count = graph.count_sequences()
        seq = f"{count:.3e}" if count >= 10**9 else str(count)
        total = t3 - t0
        flag = "" if path.stem != "KILBRID" else ("  ok" if total < TARGET_S else "  SLOW")
        print(
            f"{path.stem:10s} {len(spec.operations):4d} {graph.n_states:9,d} "
            f"{graph.n_transitions:12,d} {seq:>10s} {t1 - t0:8.2f} {t2 - t1:7.2f} "
            f"{t3 - t2:8.2f} {total:8.2f} {sol.tct:5g} {peak_rss_mb():8.0f}{flag}"
        )
    print("total s = state graph + game DAG + exact solve (sequence count not included)")
    print("Data: Scholl (1993), Data of Assembly Line Balancing Problems, TH Darmstadt.")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else DEFAULT)
