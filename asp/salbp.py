"""Scholl's assembly-line balancing precedence graphs (``.IN2``) as assembly specifications.

Format (Scholl 1993, ``README.DOC``): line 1 the number n of tasks, lines 2..n+1 the integer
task times, then direct precedence relations ``i,j`` (tasks numbered from 1), and an
optional end mark ``-1,-1``; anything after the end mark is ignored.

Each task becomes an operation open to either side: one agent ``any`` (side ``any``) whose
duration is the task time. In the game either player may take it; in the CP-SAT schedule
the ``any`` agent stands for one worker of each side working in parallel.

Data: Scholl, A. (1993), *Data of Assembly Line Balancing Problems*, TH Darmstadt.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from asp.spec import Agent, AssemblySpec, Constraints, Operation, check_predecessors

CREDIT = "Precedence graph from Scholl (1993), Data of Assembly Line Balancing Problems"


@dataclass(frozen=True)
class SalbpInstance:
    """A precedence graph: task times and direct precedence pairs (1-based task numbers).

    Attributes
    ----------
    name : str
    times : tuple of int, length n
    precedences : tuple of (int, int)
    """

    name: str
    times: tuple[int, ...]
    precedences: tuple[tuple[int, int], ...]

    @property
    def n_tasks(self) -> int:
        return len(self.times)


def read_in2(path: str | os.PathLike[str]) -> SalbpInstance:
    """Read a ``.IN2`` file; raise ``ValueError`` naming the file and line on bad input."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file")
    lines = [ln.strip() for ln in path.read_text(encoding="latin-1").splitlines()]
    pos = 0

    def next_line() -> tuple[int, str]:
        nonlocal pos
        while pos < len(lines) and not lines[pos]:
            pos += 1
        if pos >= len(lines):
            raise ValueError(f"{path}: unexpected end of file")
        pos += 1
        return pos, lines[pos - 1]

    lineno, text = next_line()
    try:
        n = int(text)
    except ValueError:
        raise ValueError(
            f"{path}: line {lineno}: expected the number of tasks, got {text!r}"
        ) from None
    if n < 1:
        raise ValueError(f"{path}: line {lineno}: expected a positive number of tasks, got {n}")
    times = []
    for _ in range(n):
        lineno, text = next_line()
        try:
            t = int(text)
        except ValueError:
            raise ValueError(f"{path}: line {lineno}: expected a task time, got {text!r}") from None
        if t < 0:
            raise ValueError(f"{path}: line {lineno}: negative task time {t}")
        times.append(t)
    pairs = []
    while pos < len(lines):
        lineno, text = pos + 1, lines[pos]
        pos += 1
        if not text:
            continue
        fields = text.replace(" ", "").split(",")
        try:
            i, j = (int(x) for x in fields)
        except ValueError:
            raise ValueError(f"{path}: line {lineno}: expected 'i,j', got {text!r}") from None
        if (i, j) == (-1, -1):
            break
        for x in (i, j):
            if not 1 <= x <= n:
                raise ValueError(f"{path}: line {lineno}: task {x} is not in 1..{n}")
        if i == j:
            raise ValueError(f"{path}: line {lineno}: task {i} precedes itself")
        pairs.append((i, j))
    return SalbpInstance(name=path.stem, times=tuple(times), precedences=tuple(pairs))


def salbp_spec(path: str | os.PathLike[str]) -> AssemblySpec:
    """The assembly specification of a ``.IN2`` file: task ``k`` is operation ``"k"``.

    One agent ``any`` (side ``any``) may do every task, in its task time. No parts, no tools.
    """
    inst = read_in2(path)
    preds: dict[int, list[int]] = {k: [] for k in range(1, inst.n_tasks + 1)}
    for i, j in inst.precedences:
        if i not in preds[j]:
            preds[j].append(i)
    ops = tuple(
        Operation(
            id=str(k),
            description=f"task {k}",
            durations=(("any", float(inst.times[k - 1])),),
            after=tuple(str(i) for i in preds[k]),
        )
        for k in range(1, inst.n_tasks + 1)
    )
    check_predecessors(ops, str(path))
    return AssemblySpec(
        name=inst.name,
        operations=ops,
        agents=(Agent("any", "any", "either side"),),
        constraints=Constraints(topological=True, stability=False, functional=False),
        source=str(path),
        credit=CREDIT,
    )
