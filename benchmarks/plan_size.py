"""Plan file size and write/read times for Scholl's precedence graphs (the largest plans).

Usage: python benchmarks/plan_size.py [NAME.IN2 ...]   (default: SAWYER30 and KILBRID)
Prints, per graph: game nodes, policy states and moves, build / write / read seconds, MB.
Data: Scholl (1993), read from ../shared/data/salbp (never copied into the repository).
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

from asmplan.planfile import alternate_states, plan_document, read_plan, write_plan
from asp.game import game_dag
from asp.solve import solve
from asp.spec import load_spec
from asp.state_graph import build_state_graph

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "salbp"


def main(names: list[str]) -> None:
    for name in names or ["SAWYER30.IN2", "KILBRID.IN2"]:
        spec = load_spec(DATA / name)
        t0 = time.perf_counter()
        graph = build_state_graph(spec)
        dag = game_dag(graph, labels=False)
        sol = solve(dag)
        t1 = time.perf_counter()
        doc = plan_document(spec=spec, dag=dag, solution=sol, describe=alternate_states(graph, dag))
        t2 = time.perf_counter()
        with tempfile.TemporaryDirectory() as tmp:
            path = write_plan(Path(tmp) / "plan.json", doc)
            t3 = time.perf_counter()
            size = path.stat().st_size
            read_plan(path)
            t4 = time.perf_counter()
        pol = doc["policy"]
        print(
            f"{name}: {dag.n_nodes:,} game nodes, policy {pol['n_states']:,} states, "
            f"{pol['n_moves']:,} moves; solve {t1 - t0:.2f} s, plan {t2 - t1:.2f} s, "
            f"write {t3 - t2:.2f} s, read {t4 - t3:.2f} s, {size / 1e6:.1f} MB",
            flush=True,
        )


if __name__ == "__main__":
    main(sys.argv[1:])
