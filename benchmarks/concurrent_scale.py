"""How the concurrent game grows with operations, agents and human duration ranges.

A job of ``n`` operations in ``chains`` parallel chains (each operation after the one
before it in its chain, the last operation of every chain before a final check), agents
``H`` and ``R1..Rr``; every third operation is the person's (a duration range of
``spread`` seconds on the grid of 1 s), the others a robot's or either side's; ``R1``
screws with a bit the person changes twice (tool changes). Prints the on-the-fly search's
curve W*(0..k) and W*(inf) (:func:`asp.concurrent.curve.solve_curve`, the CP-SAT schedule
as its first guesses and its bound as ``L``), its positions, seconds and the peak memory;
with ``--enumerate`` also the full enumeration's (:func:`asp.concurrent.robustness`, the
oracle: game nodes and edges, the same values).

    python benchmarks/concurrent_scale.py                 # the 20-operation, 3-agent job
    python benchmarks/concurrent_scale.py --sweep         # growth with operations and agents
"""

from __future__ import annotations

import argparse
import resource
import time

from asp.concurrent.curve import solve_curve
from asp.concurrent.model import concurrent_model
from asp.concurrent.robustness import robustness
from asp.concurrent.rules import concurrent_rules
from asp.graph.state_graph import build_state_graph
from asp.schedule.assembly_makespan import assembly_makespan
from asp.spec import Agent, AssemblySpec, Operation, Tool


def job(n_ops: int = 20, robots: int = 2, chains: int = 4, spread: int = 4) -> AssemblySpec:
    """The synthetic cell job (module docstring); the same arguments give the same job."""
    agents = [Agent("H", "human")] + [Agent(f"R{i + 1}", "robot") for i in range(robots)]
    ops = []
    for i in range(n_ops - 1):
        pos = i // chains
        after = (f"o{i - chains}",) if pos > 0 else ()
        base = 4 + (7 * i) % 9
        ranges = ()
        if i % 3 == 0:
            durations = (("H", base + spread),)
            ranges = (("H", base, base + spread),) if spread else ()
        elif i % 3 == 1:
            durations = ((f"R{1 + (i // 3) % robots}", base),)
        else:
            durations = ((f"R{1 + (i // 3 + 1) % robots}", base), ("H", base + 2))
        ops.append(Operation(f"o{i}", "", durations=durations, after=after, ranges=ranges))
    # R1 screws o5 with the cross bit and o13 with the hex bit; the person changes the bit.
    if n_ops >= 16:
        ops[5] = Operation(
            "o5", "", (("R1", 8),), after=ops[5].after, requires=(("R1.bit", "cross"),)
        )
        ops[13] = Operation(
            "o13", "", (("R1", 8),), after=ops[13].after, requires=(("R1.bit", "hex"),)
        )
        ops[2] = Operation("o2", "", (("H", 5),), sets=(("R1.bit", "cross"),))
        ops[10] = Operation(
            "o10", "", (("H", 5),), after=("o5",), requires=(("R1.bit", "cross"),),
            sets=(("R1.bit", "hex"),),
        )  # fmt: skip
    last = tuple(f"o{i}" for i in range(max(0, n_ops - 1 - chains), n_ops - 1))
    ops.append(Operation(f"o{n_ops - 1}", "final check", (("H", 3),), after=last))
    return AssemblySpec(
        name=f"cell job {n_ops} ops, {1 + robots} agents",
        operations=tuple(ops),
        agents=tuple(agents),
        tools=(Tool("R1.bit", "hex", 2.0),) if n_ops >= 16 else (),
        cost="time",
        turn_model="concurrent",
    )


_loaded: list = []
"""Not empty once a solve has loaded the compiled kernels in this process."""


def search(n_ops: int, robots: int, spread: int, max_k: int) -> None:
    """The on-the-fly search's figures (module docstring): its CPU once the compiled kernels
    are loaded (the process's first solve, timed apart, loads them from numba's cache)."""
    spec = job(n_ops, robots, spread=spread)
    t0 = time.perf_counter()
    graph = build_state_graph(spec)
    sched, result = assembly_makespan(spec, graph, time_limit=10.0)
    lower = max(sched.lower_bound, result.bound or 0.0)
    rows = result.detail.get("schedule")
    first = 0.0
    if not _loaded:  # the first solve of a process loads the kernels from numba's cache
        cpu = time.process_time()
        solve_curve(concurrent_rules(spec, graph), max_k=max_k, schedule=rows, lower=lower)
        first = time.process_time() - cpu
        _loaded.append(True)
    t1 = time.perf_counter()
    cpu = time.process_time()
    rules = concurrent_rules(spec, graph)
    curve = solve_curve(rules, max_k=max_k, schedule=rows, lower=lower)
    t2 = time.perf_counter()
    mem = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    cells = [
        f"{r['lower']:g}" if r["exact"] else f"[{r['lower']:g}, {r['upper']:g}]"
        for r in curve.to_list()
    ]
    print(
        f"{n_ops:3d} ops {1 + robots} agents spread {spread}: state graph {graph.n_states:,} "
        f"states, CP-SAT {result.objective:g} ({t1 - t0:.2f} s); search k=0..{curve.k}: "
        f"{curve.positions:,} positions, curve {cells[:-1]} W*(inf) {cells[-1]}, "
        f"flat {curve.flat}; {t2 - t1:.2f} s ({time.process_time() - cpu:.2f} s of CPU"
        + (f"; {first:.2f} s the first time, loading the compiled kernels" if first else "")
        + f"); peak {mem:,.0f} MB",
        flush=True,
    )


def run(n_ops: int, robots: int, spread: int, max_k: int) -> None:
    """The full enumeration's figures (the oracle)."""
    spec = job(n_ops, robots, spread=spread)
    t0 = time.perf_counter()
    graph = build_state_graph(spec)
    model = concurrent_model(spec, graph)
    t1 = time.perf_counter()
    curve = robustness(model, max_k=max_k)
    t2 = time.perf_counter()
    mem = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(
        f"{n_ops:3d} ops {1 + robots} agents spread {spread}: state graph {graph.n_states:,} "
        f"states ({t1 - t0:.2f} s); game k=0..{curve.k}: {curve.game.dag.n_nodes:,} nodes "
        f"{curve.game.dag.n_edges:,} edges; unbounded {curve.adversary.dag.n_nodes:,} nodes "
        f"{curve.adversary.dag.n_edges:,} edges; curve {[round(b, 1) for b in curve.bounds]} "
        f"W*(inf) {curve.unbounded:g}; {t2 - t1:.2f} s; peak {mem:,.0f} MB",
        flush=True,
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sweep", action="store_true")
    parser.add_argument("--ops", type=int, default=20)
    parser.add_argument("--robots", type=int, default=2)
    parser.add_argument("--spread", type=int, default=4)
    parser.add_argument("--max-k", type=int, default=12)
    parser.add_argument("--enumerate", action="store_true", help="the full enumeration too")
    args = parser.parse_args()
    sizes = [(args.ops, args.robots)]
    if args.sweep:
        sizes = [(n, robots) for robots in (1, 2, 3) for n in (8, 12, 16, 20)]
    for n, robots in sizes:
        search(n, robots, args.spread, args.max_k)
        if args.enumerate:
            run(n, robots, args.spread, args.max_k)


if __name__ == "__main__":
    main()
