"""Wall time of the paper's sweeps (Tables 3 and 4) on each backend.

Runs ``table3`` (6 graphs x ``--trials``) and ``table4`` (``--trials`` 20/10 graphs) into
fresh temporary folders on: this process (serial), a local process pool of ``--workers``,
and a private local Ray instance (when Ray is installed), then checks that every backend
gave the same rows and prints the times.

Run: ``.venv/bin/python benchmarks/experiments_sweep.py [--solver exact] [--trials 10]``
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a checkout

from asmplan.experiments.runner import run_experiment  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--solver", default="exact", choices=("exact", "arl", "both"))
    parser.add_argument("--config", default="fast", choices=("paper", "fast"))
    parser.add_argument("--trials", type=int, default=10, help="Table 4 graphs (Table 3: 1).")
    parser.add_argument("--workers", type=int, default=os.cpu_count())
    parser.add_argument("--no-ray", action="store_true", help="Skip the Ray backend.")
    args = parser.parse_args()

    backends = [("serial", "local", 1), ("pool", "local", args.workers)]
    if not args.no_ray:
        try:
            import ray  # noqa: F401
        except ImportError:
            print("ray not installed: skipping the Ray backend")
        else:
            backends.append(("ray", "ray", args.workers))

    print(f"solver {args.solver}, config {args.config}, {os.cpu_count()} cores")
    print(f"{'backend':8} {'experiment':10} {'tasks':>5} {'seconds':>8}")
    for experiment, trials in (("table3", 1), ("table4", args.trials)):
        reference = None
        for label, backend, workers in backends:
            with tempfile.TemporaryDirectory() as tmp:
                t0 = time.perf_counter()
                report = run_experiment(
                    experiment,
                    tmp,
                    trials=trials,
                    solver=args.solver,
                    config=args.config,
                    backend=backend,
                    address="local",
                    workers=workers,
                    progress=False,
                )
                seconds = time.perf_counter() - t0
            rows = [r.comparable() for r in report.rows]
            same = "" if reference is None else ("same rows" if rows == reference else "DIFFER")
            reference = rows if reference is None else reference
            print(f"{label:8} {experiment:10} {len(report.results):5d} {seconds:8.2f}  {same}")


if __name__ == "__main__":
    main()
