"""Plan file size and write/read times for the largest plans, both turn models.

Usage: python benchmarks/plan_size.py [--concurrent [--max-k K]] [NAME.IN2 | ASSEMBLY ...]
(default: SAWYER30 and KILBRID; with ``--concurrent``: the pump with the person's ranges and
MITCHELL in the concurrent game, budgets 0..K, K = 2 by default; SAWYER30 fits with K = 0).
Prints, per plan: game nodes, policy states and moves, solve / plan / write / read seconds, MB.
Data: Scholl (1993), read from ../shared/data/salbp (never copied into the repository).
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

from asmplan.pipeline import plan_document
from asmplan.planfile import read_plan, write_plan
from asp.game.solve import solve
from asp.graph.game_dag import game_dag
from asp.graph.game_states import alternate_states
from asp.graph.state_graph import build_state_graph

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data" / "salbp"


def _spec(name: str):
    from asp.fromcad.generate import load_any

    path = Path(name)
    if not path.exists():
        path = DATA / name if name.endswith(".IN2") else REPO / "examples" / name
    return load_any(path)


def _alternate(spec):
    graph = build_state_graph(spec)
    dag = game_dag(graph, labels=False)
    sol = solve(dag)
    return dag, lambda: plan_document(
        spec=spec, dag=dag, solution=sol, describe=alternate_states(graph, dag)
    )


def _concurrent(spec, max_k: int = 2):
    from asp.concurrent.model import concurrent_model
    from asp.concurrent.robustness import robustness

    graph = build_state_graph(spec)
    curve = robustness(concurrent_model(spec, graph), max_k=max_k)
    game = curve.game
    return game.dag, lambda: plan_document(
        spec=spec, dag=game.dag, solution=curve.solution, game=game
    )


def main(args: list[str]) -> None:
    concurrent = "--concurrent" in args
    max_k = 2
    if "--max-k" in args:
        at = args.index("--max-k")
        max_k = int(args[at + 1])
        args = args[:at] + args[at + 2 :]
    names = [a for a in args if a != "--concurrent"]
    if not names:
        names = (
            ["vacuum_pump_ranges", "MITCHELL.IN2"]
            if concurrent
            else ["SAWYER30.IN2", "KILBRID.IN2"]
        )
    for name in names:
        spec = _spec(name)
        t0 = time.perf_counter()
        dag, document = _concurrent(spec, max_k) if concurrent else _alternate(spec)
        t1 = time.perf_counter()
        doc = document()
        t2 = time.perf_counter()
        with tempfile.TemporaryDirectory() as tmp:
            path = write_plan(Path(tmp) / "plan.json", doc)
            t3 = time.perf_counter()
            size = path.stat().st_size
            read_plan(path)
            t4 = time.perf_counter()
        pol = doc["policy"]
        print(
            f"{name} ({pol['turn_model']}): {dag.n_nodes:,} game nodes, policy "
            f"{pol['n_states']:,} states, {pol['n_moves']:,} moves; solve {t1 - t0:.2f} s, "
            f"plan {t2 - t1:.2f} s, write {t3 - t2:.2f} s, read {t4 - t3:.2f} s, "
            f"{size / 1e6:.2f} MB",
            flush=True,
        )


if __name__ == "__main__":
    main(sys.argv[1:])
