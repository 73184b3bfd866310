"""The vacuum pump in the concurrent game: every k until flat, timed (target: under 1 s).

Builds the state graph once (relations included, not timed), then times the concurrent
model, the unbounded game and the budgets 0..K until W*(K) == W*(inf), for the pump of the
paper (fixed durations) and the variant with the person's times as ranges.

    python benchmarks/concurrent_pump.py
"""

from __future__ import annotations

import time
from pathlib import Path

from asp.concurrent.model import concurrent_model
from asp.concurrent.robustness import robustness
from asp.graph.feasibility import load_relations
from asp.graph.state_graph import build_state_graph
from asp.spec import load_spec

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def main() -> None:
    for name in ("vacuum_pump", "vacuum_pump_ranges"):
        spec = load_spec(EXAMPLES / name)
        graph = build_state_graph(spec, load_relations(spec))
        robustness(concurrent_model(spec, graph))  # warm-up: numba caches, imports
        t0 = time.perf_counter()
        curve = robustness(concurrent_model(spec, graph))
        seconds = time.perf_counter() - t0
        rows = ", ".join(
            f"W*({'inf' if r['k'] is None else r['k']}) {r['bound']}" for r in curve.to_list()
        )
        print(
            f"{name}: {rows}; games {curve.game.dag.n_nodes:,} nodes / "
            f"{curve.game.dag.n_edges:,} edges (k 0..{curve.k}) + "
            f"{curve.adversary.dag.n_nodes:,} nodes (unbounded); {seconds:.2f} s",
            flush=True,
        )


if __name__ == "__main__":
    main()
