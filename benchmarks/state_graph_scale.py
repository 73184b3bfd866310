"""State graph, game DAG and exact solve on Scholl's precedence graphs (``.IN2``).

Prints, per file, the assembly state graph (uint64 words per state key, states, transitions,
exact number of feasible sequences), the game DAG and the seconds of each stage, and the
process's peak RSS. Target: KILBRID (45 tasks, 626,575 states, 4,866,716 transitions, one-word
keys) in under 5 s for the state graph, the game DAG and the exact solve together. A last row,
RAND90, is a seeded random precedence graph on 90 tasks (two-word keys), to time the multi-word
path on a size like Scholl's LUTZ2/LUTZ3 (89 tasks).

Data: Scholl, A. (1993), Data of Assembly Line Balancing Problems, TH Darmstadt.

Usage: ``python benchmarks/state_graph_scale.py [FOLDER]``
"""

from __future__ import annotations

import random
import resource
import sys
import time
from pathlib import Path

from asp.game.solve import solve
from asp.game.synth import synthetic_dag
from asp.graph.game_dag import game_dag
from asp.graph.state_graph import build_state_graph
from asp.spec import Agent, AssemblySpec, Constraints, Operation, load_spec

DEFAULT = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "salbp"
TARGET_S = 5.0


def peak_rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # Linux: KiB


def random_spec(n: int = 90, density: float = 0.12, seed: int = 3) -> AssemblySpec:
    """A random precedence graph: each pair of a shuffled order kept with ``density``."""
    rng = random.Random(seed)
    order = list(range(n))
    rng.shuffle(order)
    after: list[list[str]] = [[] for _ in range(n)]
    for i in range(n):
        for j in range(i + 1, n):
            if rng.random() < density:
                after[order[j]].append(str(order[i] + 1))
    ops = tuple(
        Operation(
            id=str(k + 1),
            description=f"task {k + 1}",
            durations=(("any", float(rng.randint(1, 9))),),
            after=tuple(after[k]),
        )
        for k in range(n)
    )
    return AssemblySpec(
        name=f"RAND{n}",
        operations=ops,
        agents=(Agent("any", "any"),),
        constraints=Constraints(topological=True, stability=False, functional=False),
        source=f"random-{n}",
    )


def main(folder: Path = DEFAULT) -> None:
    files = sorted(folder.glob("*.IN2"), key=lambda p: len(p.read_text(encoding="latin-1")))
    if not files:
        raise SystemExit(f"no .IN2 files in {folder}")
    solve(synthetic_dag(3, 3, 2, 0))  # load the compiled solver kernels once
    header = (
        f"{'file':10s} {'ops':>4s} {'W':>2s} {'states':>9s} {'transitions':>12s} "
        f"{'sequences':>10s} {'graph s':>8s} {'dag s':>7s} {'solve s':>8s} {'total s':>8s} "
        f"{'TCT':>5s} {'peak MB':>8s}"
    )
    print(header)
    print("-" * len(header))
    for spec in [*(load_spec(path) for path in files), random_spec()]:
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
        flag = "" if spec.name != "KILBRID" else ("  ok" if total < TARGET_S else "  SLOW")
        print(
            f"{spec.name:10s} {len(spec.operations):4d} {graph.model.n_words:2d} "
            f"{graph.n_states:9,d} "
            f"{graph.n_transitions:12,d} {seq:>10s} {t1 - t0:8.2f} {t2 - t1:7.2f} "
            f"{t3 - t2:8.2f} {total:8.2f} {sol.tct:5g} {peak_rss_mb():8.0f}{flag}"
        )
    print("total s = state graph + game DAG + exact solve (sequence count not included)")
    print("Data: Scholl (1993), Data of Assembly Line Balancing Problems, TH Darmstadt.")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else DEFAULT)
