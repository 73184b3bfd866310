"""CP-SAT makespan stage on small and large cases: time, makespan, status, bound, cuts.

The stage is :func:`asp.schedule.assembly_makespan.assembly_makespan` (``asmplan plan``'s
step 4: the precedences the state graph implies, the replay tables, the list schedules, then
CP-SAT with lazy cuts from the replay). Each case runs with the default of ``asmplan plan``
(``auto``: :data:`asp.schedule.assembly_makespan.AUTO_TIME_LIMIT` search seconds of CP-SAT's
deterministic time, stopping once neither a better schedule nor a new cut has come for
:data:`asp.schedule.assembly_makespan.AUTO_PATIENCE` of them) and with each ``--limits``
value (a CP-SAT time limit in search seconds, as ``--time-limit`` gives). Printed per run: the
stage's wall time and the part of it spent before CP-SAT (the precedences, the replay
tables, the list schedules), status, makespan, proven lower bound, cuts and solves, and who
found the schedule; every schedule printed has passed the replay (checked again here).

Cases (those whose files are missing are skipped):

- ``pump``: the vacuum pump (``examples/``), its state graph and the robust plan's line;
- ``rod``: the 29-part bearing tower, ``/tmp/realcad_pub/rod.3DXML`` (trimesh's public
  models; not part of the repository), loaded as ``asmplan plan`` does;
- ``cyc``: a pickled state graph (``--graph-pickle``, e.g. the 72-part cycloidal drive's
  4.19M-state reduced graph, ``/tmp/cyc/g.pkl``);
- ``file:PATH``: any assembly file or folder, loaded as ``asmplan plan`` does (e.g.
  ``file:/tmp/realcad_pub/cycloidal.3DXML``, the 72-part cycloidal drive);
- ``j30:NAME``: PSPLIB instances (shared data), plain CP-SAT without a state graph
  (:func:`asp.schedule.makespan.min_makespan`; ``auto`` is then the same time limit with the
  patience).

With ``--fixed-order both`` every assembly run is made twice: with the graph's fixed order
of alike parts undone (``undo``, the default of ``asmplan plan``: :mod:`asp.graph.fixed_order`,
the full graph's schedules) and kept (``keep``: the chain a precedence, no two alike parts
at once; the conservative makespan of before).

    python benchmarks/cpsat_large_graph.py [--cases pump rod cyc j30:j3010_1.sm]
        [--limits 30] [--graph-pickle /tmp/cyc/g.pkl] [--fixed-order undo|keep|both]
"""

from __future__ import annotations

import argparse
import pickle
import sys
import time
import warnings
from pathlib import Path

from asmplan.pipeline import Assembly, game, load, robust_plan, solve_game, state_graph
from asp.schedule.assembly_makespan import AUTO_PATIENCE, AUTO_TIME_LIMIT, assembly_makespan
from asp.schedule.makespan import min_makespan
from asp.schedule.replay import replay_model, schedule_violation

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"
ROD = Path("/tmp/realcad_pub/rod.3DXML")
GRAPH = Path("/tmp/cyc/g.pkl")


def assembly_case(path: Path):
    """``(spec, graph, line)`` of an assembly file: the state graph and the robust line."""
    from asmplan.pipeline import Game

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assembly = load(path, progress=False)
    graph = state_graph(assembly)
    if graph.spec is not assembly.spec:
        assembly = Assembly(graph.spec, assembly.relations)
    the_game = Game(game(graph), assembly.descriptions)
    steps = robust_plan(the_game, solve_game(the_game.dag))
    return graph.spec, graph, [s.operation for s in steps if s.operation]


def run_assembly(spec, graph, line, limit, undo: bool = True) -> dict:
    t0 = time.perf_counter()
    _, result = assembly_makespan(spec, graph, time_limit=limit, sequence=line, fixed_order=undo)
    wall = time.perf_counter() - t0
    rows = result.detail.get("schedule")
    replay = replay_model(spec, graph, cuts=False, fixed_order=undo)
    if rows and schedule_violation(replay, rows) is not None:
        raise SystemExit(f"{spec.name}: a reported schedule fails the replay")
    return {"wall": wall, "result": result}


def run_psplib(path: Path, limit) -> dict:
    from asp.schedule.psplib import read_sm

    problem = read_sm(path)
    t0 = time.perf_counter()
    if limit is None:
        result = min_makespan(problem, time_limit=AUTO_TIME_LIMIT, patience=AUTO_PATIENCE)
    else:
        result = min_makespan(problem, time_limit=limit)
    return {"wall": time.perf_counter() - t0, "result": result}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--cases", nargs="+", default=["pump", "rod", "cyc", "j30:j3010_1.sm", "j30:j301_1.sm"]
    )
    parser.add_argument("--limits", type=float, nargs="*", default=[30.0])
    parser.add_argument("--graph-pickle", type=Path, default=GRAPH)
    parser.add_argument("--fixed-order", choices=["undo", "keep", "both"], default="undo")
    args = parser.parse_args()
    orders = {"undo": [True], "keep": [False], "both": [True, False]}[args.fixed_order]
    print(
        f"{'case':16s} {'order':>5s} {'limit':>6s} {'wall s':>7s} {'prep s':>6s} "
        f"{'status':>8s} {'makespan':>9s} "
        f"{'bound':>6s} {'cuts':>5s} {'solves':>6s}  found by"
    )
    for case in args.cases:
        t0 = time.perf_counter()
        if case == "pump":
            prepared = assembly_case(REPO / "examples" / "vacuum_pump")
        elif case == "rod":
            if not ROD.exists():
                print(f"{case}: {ROD} missing, skipped")
                continue
            prepared = assembly_case(ROD)
        elif case == "cyc":
            if not args.graph_pickle.exists():
                print(f"{case}: {args.graph_pickle} missing, skipped")
                continue
            with open(args.graph_pickle, "rb") as handle:
                graph = pickle.load(handle)  # noqa: S301 - a local file the user names
            prepared = (graph.spec, graph, None)
        elif case.startswith("file:"):
            if not Path(case[5:]).exists():
                print(f"{case}: missing, skipped")
                continue
            prepared = assembly_case(Path(case[5:]))
        elif case.startswith("j30:"):
            prepared = DATA / "psplib_j30" / case[4:]
        else:
            raise SystemExit(f"unknown case {case!r}")
        if isinstance(prepared, tuple):
            spec, graph, _ = prepared
            print(
                f"{case}: {len(spec.operations)} operations, {graph.n_states:,} states "
                f"({time.perf_counter() - t0:.1f} s to prepare)",
                flush=True,
            )
        runs = [(limit, undo) for limit in [None, *args.limits] for undo in orders]
        for limit, undo in runs:
            if isinstance(prepared, tuple):
                out = run_assembly(*prepared, limit, undo)
            elif not undo:
                continue  # no state graph
            else:
                out = run_psplib(prepared, limit)
            r = out["result"]
            print(
                f"{case[-16:]:16s} {'undo' if undo else 'keep':>5s} "
                f"{'auto' if limit is None else f'{limit:g}':>6s} {out['wall']:7.1f} "
                f"{r.detail.get('stage_s', r.wall_s) - r.wall_s:6.1f} "
                f"{r.status:>8s} {r.objective or 0:9g} {r.bound or 0:6g} "
                f"{r.detail.get('cuts', 0):5d} {r.detail.get('solves', 0):6d}  "
                f"{r.detail.get('found_by', '-')}",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
