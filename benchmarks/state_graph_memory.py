"""The state graph builder's memory estimate against the memory it takes (issue 26 item 3).

For ``n`` free operations (``2**n`` states, the worst case of a spec's free parts), each in
a fresh process: the states and transitions, the highest estimate the build checked
(:func:`asp.graph.state_graph.graph_bytes`), the peak RSS over the process's before the
build, and their ratio (target: 0.7 to 1.5; the constants of ``graph_bytes`` come from
these rows). Then the stop: 28 free operations and ``--max-states 1e9`` (34 GB or more
if built) on a machine said to have 4 GiB available: the build stops with one line, peak
RSS and seconds printed.

Measured (2 shared cores, 22 GB available): n = 18, 20, 22, 24: 2.4 M to 201 M
transitions, ratio 0.78, 0.88, 0.91, 1.18 (24: 3.0 GB peak over 0.3 GB); the stop: exit 2
after 19 s at 1.86 GB peak RSS (before the bound: 5.0 GB at 42 s, then a numpy
MemoryError traceback under ``ulimit -v 6000000``; without a ulimit it takes what the
machine has).

Usage: ``python benchmarks/state_graph_memory.py [N ...]``
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from pathlib import Path

ONE = """
import os, resource, sys
import asp.graph.state_graph as sg
from asp.spec import spec_from_dict

def free(n):
    ops = [{"id": str(k), "agents": {"any": 1}} for k in range(n)]
    return spec_from_dict({"agents": {"any": {"side": "any"}}, "operations": ops})

n = int(sys.argv[1])
sg.build_state_graph(free(6))
before = int(open("/proc/self/statm").read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
top, estimate = [0], sg.graph_bytes
def spy(*a, **k):
    top[0] = max(top[0], estimate(*a, **k))
    return top[0]
sg.graph_bytes = spy
g = sg.build_state_graph(free(n), max_states=10**9)
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 - before
print(f"{n:>3} {g.n_states:>12,} {g.n_transitions:>13,} {top[0] / 2**30:>9.2f} "
      f"{peak / 2**30:>9.2f} {top[0] / peak:>6.2f}")
"""

STOP = """
import sys
from asp import heap
heap.available_memory = lambda: 4 << 30
from asmplan.cli import main
sys.exit(main(sys.argv[1:]))
"""


def main(ns: list[int]) -> None:
    print("  n       states   transitions  est. GB  peak GB  ratio")
    for n in ns:
        subprocess.run([sys.executable, "-c", ONE, str(n)], check=True)
    with tempfile.TemporaryDirectory() as folder:
        spec = Path(folder) / "free28.yaml"
        ops = "".join(f"  - {{id: o{k}, agents: {{any: 1}}}}\n" for k in range(28))
        spec.write_text(f"agents: {{any: {{side: any}}}}\noperations:\n{ops}")
        t0 = time.perf_counter()
        run = subprocess.run(
            ["/usr/bin/time", "-f", "%M", sys.executable, "-c", STOP, "graph", str(spec)]
            + ["--max-states", "1000000000"],
            capture_output=True,
            text=True,
        )
        lines = [x for x in run.stderr.strip().splitlines() if not x.startswith("Command exited")]
        print(
            f"stop (4 GiB available): exit {run.returncode} after {time.perf_counter() - t0:.1f} s"
        )
        print(f"  peak RSS {int(lines[-1]) / 2**20:.2f} GB; {lines[-2][:160]} ...")


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]] or [18, 20, 22])
