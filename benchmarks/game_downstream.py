"""Everything downstream of a multi-million-state assembly state graph: time and memory.

Stages (those of ``asmplan plan`` after the state graph): counting sequences, the game DAG
(:func:`asp.graph.game_dag.game_dag`), the exact solve, the robust plan, what the outputs
take from the game (:func:`asmplan.pipeline.played_game`: the policy table, named; the
figure), after which the game and its solution are let go, the CP-SAT schedule (limit 5 s;
only with ``--cpsat``, else an empty schedule), the plan document (``AssemblyPlan.to_dict``)
and writing plan.json, dag.png and report.html. Each row gives wall seconds, CPU seconds
(the machine is shared) and the process's peak RSS after the stage. Target (issue 12, the
4.19M-state graph of a 72-part cycloidal drive): game DAG + solve + plan document + writing
under 10 s, the peak of the whole downstream (graph in memory) under 1.6 GB.

Default graph, built here: ``K`` independent chains of ``L`` operations each (every
operation done by the person or the robot), ``(L + 1) ** K`` states: 6 chains of 12 give
4.8M states, 26.7M transitions and a 53M-edge game, like the cycloidal drive's. With a path,
a pickled :class:`asp.graph.state_graph.StateGraph` instead.

Run: ``.venv/bin/python benchmarks/game_downstream.py [--chains K] [--length L] [--cpsat]
[GRAPH.pkl]``
"""

from __future__ import annotations

import argparse
import pickle
import resource
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a checkout

from asp.spec import Agent, AssemblySpec, Constraints, Operation  # noqa: E402

TARGET_S = 10.0
TARGET_GB = 1.6


def chains_spec(chains: int, length: int) -> AssemblySpec:
    """``chains`` independent chains of ``length`` operations, each done by H or R1."""
    ops = []
    for c in range(chains):
        for k in range(length):
            ops.append(
                Operation(
                    id=f"c{c + 1}_{k + 1}",
                    description=f"chain {c + 1}, step {k + 1}",
                    durations=(("H", float(2 + k % 3)), ("R1", float(3 + c % 2))),
                    after=(f"c{c + 1}_{k}",) if k else (),
                )
            )
    return AssemblySpec(
        name=f"chains_{chains}x{length}",
        operations=tuple(ops),
        agents=(Agent("H", "human"), Agent("R1", "robot")),
        constraints=Constraints(topological=True, stability=False, functional=False),
        source=f"chains-{chains}x{length}",
    )


class Stages:
    """Wall time, CPU time and peak RSS per stage."""

    def __init__(self) -> None:
        self.rows: list[tuple[str, float, float, float]] = []
        self.wall, self.cpu = time.perf_counter(), time.process_time()

    def lap(self, name: str) -> None:
        wall, cpu = time.perf_counter(), time.process_time()
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024**2  # KiB -> GB
        self.rows.append((name, wall - self.wall, cpu - self.cpu, peak))
        print(
            f"  {name:34s} {wall - self.wall:7.2f} s  cpu {cpu - self.cpu:7.2f} s  "
            f"peak {peak:5.2f} GB",
            flush=True,
        )
        self.wall, self.cpu = wall, cpu


def main(argv: list[str]) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("graph", nargs="?", help="a pickled StateGraph (default: chains)")
    parser.add_argument("--chains", type=int, default=6)
    parser.add_argument("--length", type=int, default=12)
    parser.add_argument("--cpsat", action="store_true", help="run the CP-SAT schedule too")
    args = parser.parse_args(argv)

    from asmplan import pipeline
    from asp.graph.state_graph import build_state_graph

    stages = Stages()
    if args.graph:
        with open(args.graph, "rb") as f:
            graph = pickle.load(f)  # noqa: S301 - the user's own file
        stages.lap("load graph")
    else:
        graph = build_state_graph(chains_spec(args.chains, args.length))
        stages.lap("state graph")
    print(f"{graph.spec.name}: {graph.n_states:,} states, {graph.n_transitions:,} transitions")
    assembly = pipeline.Assembly(graph.spec, None)
    sequences = graph.count_sequences()
    stages.lap("count sequences")
    game = pipeline.Game(pipeline.game(graph), assembly.descriptions)
    stages.lap("game DAG")
    dag = game.dag
    print(
        f"  game: {dag.n_nodes:,} nodes, {dag.n_edges:,} edges, targets {dag.targets.dtype}, "
        f"costs {dag.costs.dtype}"
    )
    solution = pipeline.solve_game(dag)
    stages.lap("solve")
    steps = pipeline.robust_plan(game, solution)
    stages.lap("robust plan")
    played = pipeline.played_game(graph, game, solution)  # then the game goes, as in
    tct, minimax = solution.tct, solution.minimax  # asmplan plan (keep_game=False)
    del game, solution, dag
    stages.lap("policy, lines, figure from the game")
    if args.cpsat:
        line = [s.operation for s in steps if s.operation]
        sched = pipeline.schedule(assembly, graph, sequence=line, time_limit=5, seed=0)
        stages.lap("CP-SAT schedule (limit 5 s)")
    else:  # not a stage downstream of the game: an empty schedule in the document
        from asp.schedule.cpsat import BaselineResult

        empty = BaselineResult("schedule", graph.spec.name, "UNKNOWN", None, None, 0.0)
        sched = pipeline.Schedule(empty, 0.0, 0.0, 0.0)
    result = pipeline.AssemblyPlan(
        assembly, graph, sequences, None, None, steps, [], sched, None, [], played
    )
    doc = result.to_dict()
    stages.lap("plan document (to_dict)")
    with tempfile.TemporaryDirectory() as out:
        pipeline.write_plan(result, out)
        stages.lap("write plan.json, dag.png, report")
    print(f"TCT {tct:g}, W* {minimax:g}, {doc['metrics']['policy_states']:,} policy states")
    rows = {name: wall for name, wall, _, _ in stages.rows}
    taken = ("game DAG", "solve", "policy, lines, figure from the game", "plan document (to_dict)")
    down = sum(rows[k] for k in taken)
    down += rows["write plan.json, dag.png, report"]
    print(
        f"game DAG + solve + to_dict + write: {down:.2f} s (target < {TARGET_S:g} s); "
        f"peak {stages.rows[-1][3]:.2f} GB (target < {TARGET_GB:g} GB)"
    )


if __name__ == "__main__":
    main(sys.argv[1:])
