"""CP-SAT makespan on every PSPLIB instance beside the project, against the published optima.

Data: PSPLIB j30 (Kolisch, R. and Sprecher, A. (1996), "PSPLIB - A project scheduling
problem library", European Journal of Operational Research 96, 205-216).

Usage: ``python benchmarks/psplib_all.py [FOLDER] [--time-limit 60] [--workers 2]``
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

from asp.schedule.makespan import min_makespan
from asp.schedule.psplib import read_sm

DEFAULT = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "psplib_j30"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", nargs="?", type=Path, default=DEFAULT)
    parser.add_argument("--time-limit", type=float, default=60.0)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    with open(args.folder / "optimum.csv", encoding="utf-8") as handle:
        optimum = {r["problem"]: int(r["optimum"]) for r in csv.DictReader(handle)}
    header = (
        f"{'instance':12s} {'jobs':>4s} {'optimum':>7s} {'CP-SAT':>6s} {'bound':>6s} "
        f"{'status':>8s} {'wall s':>7s}  match"
    )
    print(header)
    print("-" * len(header))
    matched = 0
    for name in sorted(optimum, key=lambda n: (len(n), n)):
        problem = read_sm(args.folder / name)
        r = min_makespan(problem, time_limit=args.time_limit, workers=args.workers, seed=args.seed)
        ok = r.objective is not None and round(r.objective) == optimum[name]
        matched += ok
        print(
            f"{name:12s} {len(problem.tasks):4d} {optimum[name]:7d} {r.objective or 0:6g} "
            f"{r.bound or 0:6g} {r.status:>8s} {r.wall_s:7.2f}  {'yes' if ok else 'NO'}"
        )
    print(f"{matched}/{len(optimum)} instances at the published optimum")
    print("Data: PSPLIB j30, Kolisch and Sprecher (1996), Eur. J. Oper. Res. 96, 205-216.")


if __name__ == "__main__":
    main()
