"""Scholl's assembly-line balancing precedence graphs (``.IN2``) as assembly specifications.

Format (Scholl 1993, ``README.DOC``): line 1 the number n of tasks, lines 2..n+1 the integer
task times, then direct precedence relations ``i,j`` (tasks numbered from 1), and an
optional end mark ``-1,-1``; anything after the end mark is ignored.

Each task becomes an operation open to either side: one agent ``any`` (side ``any``) whose
duration is the task time. :func:`in2_assembly` gives the ``assembly.yaml`` mapping of a
file, which :func:`asp.spec.load_spec` validates like any other spec (so this reader does not
depend on the spec model). In the game either player may take it; in the CP-SAT schedule
the ``any`` agent stands for one worker of each side working in parallel.

Data: Scholl, A. (1993), *Data of Assembly Line Balancing Problems*, TH Darmstadt.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from asp.errors import FormatError

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
            raise FormatError(f"{path}: unexpected end of file")
        pos += 1
        return pos, lines[pos - 1]

    lineno, text = next_line()
    try:
        n = int(text)
    except ValueError:
        raise FormatError(
            f"{path}: line {lineno}: expected the number of tasks, got {text!r}"
        ) from None
    if n < 1:
        raise FormatError(f"{path}: line {lineno}: expected a positive number of tasks, got {n}")
    times = []
    for _ in range(n):
        lineno, text = next_line()
        try:
            t = int(text)
        except ValueError:
            raise FormatError(
                f"{path}: line {lineno}: expected a task time, got {text!r}"
            ) from None
        if t < 0:
            raise FormatError(f"{path}: line {lineno}: negative task time {t}")
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
            raise FormatError(f"{path}: line {lineno}: expected 'i,j', got {text!r}") from None
        if (i, j) == (-1, -1):
            break
        for x in (i, j):
            if not 1 <= x <= n:
                raise FormatError(f"{path}: line {lineno}: task {x} is not in 1..{n}")
        if i == j:
            raise FormatError(f"{path}: line {lineno}: task {i} precedes itself")
        pairs.append((i, j))
    return SalbpInstance(name=path.stem, times=tuple(times), precedences=tuple(pairs))


def in2_assembly(path: str | os.PathLike[str]) -> dict:
    """The ``assembly.yaml`` mapping of a ``.IN2`` file: task ``k`` is operation ``"k"``.

    One agent ``any`` (side ``any``) may do every task, in its task time. No parts, no tools;
    only the topological constraint applies. Validate it with :func:`asp.spec.spec_from_dict`
    (``asp.spec.load_spec`` does both).
    """
    inst = read_in2(path)
    preds: dict[int, list[int]] = {k: [] for k in range(1, inst.n_tasks + 1)}
    for i, j in inst.precedences:
        if i not in preds[j]:
            preds[j].append(i)
    return {
        "name": inst.name,
        "agents": {"any": {"side": "any", "description": "either side"}},
        "constraints": {"topological": True, "stability": False, "functional": False},
        "operations": [
            {
                "id": str(k),
                "description": f"task {k}",
                "agents": {"any": float(inst.times[k - 1])},
                "after": [str(i) for i in preds[k]],
            }
            for k in range(1, inst.n_tasks + 1)
        ],
        "credit": CREDIT,
    }


__all__ = [
    "SalbpInstance",
    "in2_assembly",
    "read_in2",
]
"""What other modules may use (asmplan and arl among them)."""
