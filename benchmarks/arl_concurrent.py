"""The paper's learner on the concurrent game, certified against the greedy and CP-SAT policies.

Issue 23 item 3: on a product, alternating PPO played from the game's rules
(:func:`arl.concurrent_trainer.train_concurrent`, config ``concurrent``) gives a robot
policy; its certified worst case (the exact best response of the human side,
:func:`asp.concurrent.certify.certify`) per budget ``k`` is printed beside the exact value
``W*(k)`` (:func:`asp.concurrent.curve.solve_curve`, where it fits), the greedy adaptive
policy's and the CP-SAT schedule run as a plan (both certified the same way), with the
training cost (environment steps, seconds). Lower is better; every figure is exact.

    nice -n 10 .venv/bin/python benchmarks/arl_concurrent.py
    nice -n 10 .venv/bin/python benchmarks/arl_concurrent.py --seeds 3 --config concurrent
    nice -n 10 .venv/bin/python benchmarks/arl_concurrent.py ASSEMBLY --time-limit 120
    nice -n 5 .venv/bin/python benchmarks/arl_concurrent.py cycloidal.3DXML \
        --budgets 0,1,2,3,inf --cycles 12 --seeds 2 --time-limit 120

Past the exact size the fixed policies are certified by values only
(:func:`asp.concurrent.certify.best_response_values`, ``--certify-time`` search seconds a
budget) and the learned robot at the budgets whose policy game fits
(:func:`arl.concurrent_trainer.certify_fitting`); ``-`` marks a budget not certified.
On the 72-part cycloidal drive (2026-12-04): L(k) 192 at k = 0..3 and inf; U(k) 192 / 192 /
192 / 216; greedy 316; CP-SAT schedule 195 / 204 / 212 / 216; ARL seed 0 195 / 203 / 203 / 203,
seed 1 198 / 199 / 200 / 201 (24,576 steps, 162-178 s CPU each); nothing certified at k = inf
(README, "Learning the robot policy").

Measured (2026-12-02, the shared 2-core machine, config ``concurrent``: 9 cycles, 18,432
environment steps; certified worst case at k = 0 / 1 / 2 / inf; seconds are the training's,
certificates included):

- ``examples/vacuum_pump_ranges`` (21 operations, 3 workers, 109 states): W* 297 at every
  k; greedy 341; CP-SAT schedule 297 / 330 / 330 / 330; ARL seed 0: 297 at every k (the
  robot of cycle 3, 339 s), seed 1: 297 at every k (cycle 9, 269 s). ARL is
  robust-optimal: 44 s better than greedy at every k, 33 s better than the schedule at
  every k >= 1.
- bolted brackets (``as1_pe_203.stp`` of pythonocc-demos, generated spec, 18 operations,
  2 workers, 794 states): W* 66 / 66 / 66 / 68; greedy 101 at every k; CP-SAT schedule
  66 / 71 / 76 / 89; ARL seed 0: 66 / 67 / 74 / 74 (cycle 4, 365 s), seed 1:
  67 / 74 / 74 / 74 (cycle 2, 140 s). Better than greedy everywhere; better than the
  schedule at k = inf by 15 s (74 against 89) and at k = 2; 6 s (8.8 %) above W*(inf). The
  robot's policy is blind to the budget and the run keeps the robot of least worst case
  at k = inf, so at k = 0 the schedule (the optimum) can be better.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))


def budgets_of(text: str) -> list:
    """``"0,1,2,inf"`` -> ``[0, 1, 2, None]``."""
    return [None if x.strip() == "inf" else int(x) for x in text.split(",")]


def row(name: str, values: dict, budgets: list) -> str:
    cells = (values.get(b) for b in budgets)
    return f"{name:<22}" + "".join(f"{'-' if v is None else f'{v:g}':>9}" for v in cells)


def main() -> None:
    from arl.concurrent_trainer import get_config, train_concurrent
    from asmplan import pipeline
    from asp.concurrent.certify import best_response_values
    from asp.concurrent.curve import solve_curve
    from asp.concurrent.rules import concurrent_rules
    from asp.concurrent.search import GREEDY, SCHEDULE, Limits, Search
    from asp.schedule.assembly_makespan import assembly_makespan

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("assembly", nargs="?", default=str(REPO / "examples/vacuum_pump_ranges"))
    parser.add_argument("--seeds", type=int, default=1, help="training seeds: how many")
    parser.add_argument("--first-seed", type=int, default=0, help="the first training seed")
    parser.add_argument("--config", default="concurrent", help="arl.concurrent_trainer config")
    parser.add_argument("--cycles", type=int, default=None, help="cycles (default: the config's)")
    parser.add_argument("--budgets", default="0,1,2,inf", help="budgets certified, e.g. 0,1,2,3")
    parser.add_argument("--time-limit", type=float, default=300.0, help="seconds of exact search")
    parser.add_argument(
        "--certify-time", type=float, default=60.0, help="search seconds per fixed policy's budget"
    )
    args = parser.parse_args()
    budgets = budgets_of(args.budgets)
    assembly = pipeline.load(Path(args.assembly))
    spec, graph = assembly.spec, pipeline.state_graph(assembly)
    rules = concurrent_rules(spec, graph)
    print(
        f"{spec.name}: {rules.model.n_ops} operations, {rules.n_workers} workers, "
        f"{graph.n_states:,} assembly states",
        flush=True,
    )
    t0 = time.perf_counter()
    _, result = assembly_makespan(spec, graph, seed=0)
    rows = result.detail.get("schedule") or []
    print(
        f"CP-SAT makespan {result.objective:g} ({result.status}, {time.perf_counter() - t0:.1f} s)"
    )
    t0 = time.perf_counter()
    top = max([b for b in budgets if b is not None], default=0)
    curve = solve_curve(
        rules, max_k=top, min_k=top, limits=Limits(time_limit=args.time_limit), schedule=rows
    )
    ks = [*range(len(curve.lower) - 1), None]
    lower = {b: v for b, v in zip(ks, curve.lower, strict=True) if math.isfinite(v)}
    upper = {b: v for b, v in zip(ks, curve.upper, strict=True) if math.isfinite(v)}
    exact = {b: e for b, e in zip(ks, curve.exact, strict=True)}
    print(
        f"exact search {time.perf_counter() - t0:.1f} s "
        f"({'exact' if all(curve.exact) else f'stopped by the {curve.stopped}'}, "
        f"{curve.nodes:,} positions); exact at k = "
        + ", ".join("inf" if b is None else str(b) for b in ks if exact[b])
    )

    # The fixed policies: values only (no policy game), each budget in its own time.
    search = Search(rules, schedule=rows)
    fixed = {}
    for name, kind in (("greedy", GREEDY), ("CP-SAT schedule", SCHEDULE)):
        fixed[name] = {}
        for b in budgets:
            got = best_response_values(
                search, kind, [b], schedule=rows if kind == SCHEDULE else None,
                time_limit=args.certify_time,
            )  # fmt: skip
            if got is not None:
                fixed[name][b] = got[b]
    print(
        f"{'certified worst case':<22}"
        + "".join(f"{'k=' + ('inf' if b is None else str(b)):>9}" for b in budgets)
    )
    print(row("L(k) (search)", lower, budgets))
    print(row(f"U(k) ({curve.policy})", upper, budgets))
    for name, values in fixed.items():
        print(row(name, values, budgets))
    cfg = get_config(args.config)
    if args.cycles is not None:
        cfg = cfg.replace(cycles=args.cycles)
    for seed in range(args.first_seed, args.first_seed + args.seeds):
        t0 = time.process_time()
        run = train_concurrent(rules, cfg, seed=seed, budgets=budgets, progress=True)
        cpu = time.process_time() - t0
        print(row(f"ARL seed {seed}", run.certified, budgets), flush=True)
        both = [b for b in run.certified]
        verdict = []
        for name, other in fixed.items():
            common = [b for b in both if b in other]
            if not common:
                continue
            better = [b for b in common if run.certified[b] < other[b]]
            worse = [b for b in common if run.certified[b] > other[b]]
            verdict.append(
                f"{name}: better at {len(better)}, worse at {len(worse)} of {len(common)} budgets"
            )
        gaps = [
            f"k={'inf' if b is None else b}: {100 * (run.certified[b] - lower[b]) / lower[b]:.1f} %"
            for b in both
            if b in lower
        ]
        print(
            f"  {run.steps:,} steps, {run.seconds:.0f} s wall, {cpu:.0f} s CPU "
            f"(best cycle {run.best_cycle}); {'; '.join(verdict)}; above L: {', '.join(gaps)}",
            flush=True,
        )


if __name__ == "__main__":
    main()
