"""The concurrent game of real products by the on-the-fly search, with defaults.

For each public CAD file (under ``$ASMPLAN_REAL_CAD``, default ``/tmp/realcad``; absent
files are skipped, none is in the repository): the FreeCAD APLAN shear mold
(``asm_shear_mold.step``, 17 parts), the bolted brackets (``as1-oc-214.stp``, 18), the
bearing tower (``rod.3DXML``, 29) and the cycloidal drive (``cycloidal.3DXML``, 72), the
steps ``asmplan plan --turn-model concurrent`` takes: the state graph (alike parts in a
fixed order, which the rules undo exactly, :mod:`asp.concurrent.rules`; ``--loose``: the
graph reduced in a loose order, larger), the CP-SAT schedule (its bound is ``L`` at
``k = 0``, its rows the search's first guesses and a certified policy), then
:func:`asp.concurrent.curve.solve_curve` with its default limits (``--time-limit`` here:
seconds for the search, default none).

Each file runs in a child process; one row per file: operations, states, the graph's and
CP-SAT's seconds, CP-SAT's makespan and bound, ``W*(k)`` (``[L, U]`` where not exact), how
far exact goes, the search's positions and seconds (wall and CPU), the peak memory of the
child. Run: ``.venv/bin/python benchmarks/concurrent_real.py [FILE ...] [--time-limit S]``
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FILES = ("asm_shear_mold.step", "as1-oc-214.stp", "rod.3DXML", "cycloidal.3DXML")


def one(path: Path, time_limit: float | None, loose: bool = False, memory: float = 0) -> dict:
    """The figures of one file (in this process)."""
    from asmplan import pipeline
    from asp.concurrent.curve import solve_curve
    from asp.concurrent.rules import concurrent_rules
    from asp.concurrent.search import Limits

    warnings.simplefilter("ignore")
    t0 = time.perf_counter()
    assembly = pipeline.load(path)
    graph = pipeline.state_graph(assembly, concurrent=loose)
    assembly = pipeline.Assembly(graph.spec, assembly.relations)
    t1 = time.perf_counter()
    sched = pipeline.schedule(assembly, graph)
    result = sched.result
    t2 = time.perf_counter()
    cpu0 = time.process_time()
    rules = concurrent_rules(graph.spec, graph)
    lower = max(sched.lower_bound, result.bound or 0.0)
    curve = solve_curve(
        rules,
        schedule=result.detail.get("schedule"),
        lower=lower,
        limits=Limits(time_limit=time_limit, **({"memory": int(memory * 2**30)} if memory else {})),
        progress=True,
    )
    t3 = time.perf_counter()
    rows = curve.to_list()
    exact_to = None
    for r in rows[:-1]:
        if not r["exact"]:
            break
        exact_to = r["k"]
    return {
        "file": path.name,
        "ops": len(graph.spec.operations),
        "states": graph.n_states,
        "graph_s": round(t1 - t0, 1),
        "cpsat_s": round(t2 - t1, 1),
        "cpsat": [result.objective, result.bound, result.status],
        "curve": [
            [r["k"], r["lower"], r["upper"]] if not r["exact"] else [r["k"], r["lower"]]
            for r in rows
        ],
        "flat": curve.flat,
        "exact_to": exact_to,
        "stopped": curve.stopped,
        "policy": curve.policy,
        "schedule_worst": [r["bound"] for r in curve.schedule_worst],
        "positions": curve.positions,
        "nodes": curve.nodes,
        "search_s": round(t3 - t2, 1),
        "search_cpu_s": round(time.process_time() - cpu0, 1),
        "wall_s": round(t3 - t0, 1),
        "peak_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024),
        "max_gap_pct": round(max(curve.gap(i) for i in range(len(curve.lower))), 2),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("files", nargs="*", type=Path)
    parser.add_argument("--time-limit", type=float, default=None)
    parser.add_argument("--loose", action="store_true", help="the loose-order graph")
    parser.add_argument("--memory", type=float, default=0, help="GiB for the search")
    parser.add_argument("--one", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(one(args.one, args.time_limit, args.loose, args.memory)), flush=True)
        return
    folder = Path(os.environ.get("ASMPLAN_REAL_CAD", "/tmp/realcad"))
    files = args.files or [folder / f for f in FILES]
    for path in files:
        if not path.exists():
            print(f"{path}: absent, skipped", flush=True)
            continue
        cmd = [sys.executable, __file__, "--one", str(path)]
        if args.time_limit is not None:
            cmd += ["--time-limit", str(args.time_limit)]
        if args.loose:
            cmd.append("--loose")
        if args.memory:
            cmd += ["--memory", str(args.memory)]
        env = {**os.environ, "PYTHONPATH": str(ROOT)}
        # the child's progress (and any error) goes straight to stderr
        out = subprocess.run(cmd, stdout=subprocess.PIPE, text=True, env=env)
        lines = [x for x in out.stdout.splitlines() if x.startswith("{")]
        if out.returncode or not lines:
            print(f"{path.name}: exit {out.returncode} (its stderr above)", flush=True)
            continue
        print(lines[-1], flush=True)


if __name__ == "__main__":
    main()
