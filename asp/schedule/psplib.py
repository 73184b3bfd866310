"""PSPLIB single-mode RCPSP instances (``.sm``) as scheduling problems.

Reads the ``PRECEDENCE RELATIONS`` (job, modes, successors), ``REQUESTS/DURATIONS`` (job,
mode, duration, one demand per renewable resource) and ``RESOURCEAVAILABILITIES`` sections.
Jobs become tasks ``"1" .. "n"`` (the supersource and supersink included, duration 0), with
no agent; each renewable resource becomes a cumulative constraint of its capacity.

Data: PSPLIB, Kolisch, R. and Sprecher, A. (1996), "PSPLIB - A project scheduling problem
library", European Journal of Operational Research 96, 205-216.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from asp.errors import FormatError
from asp.schedule.makespan import ScheduleProblem, Task

CREDIT = "PSPLIB instance (Kolisch and Sprecher 1996, European J. Operational Research 96)"


def read_sm(path: str | os.PathLike[str]) -> ScheduleProblem:
    """Read a single-mode ``.sm`` file; raise ``ValueError`` naming the file and section."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file")
    lines = path.read_text(encoding="latin-1").splitlines()

    def section(title: str) -> int:
        for k, line in enumerate(lines):
            if line.strip().upper().startswith(title):
                return k
        raise FormatError(f"{path}: missing section {title!r}: is this a PSPLIB .sm file?")

    def rows_after(start: int, skip: int) -> list[list[int]]:
        out = []
        for line in lines[start + skip :]:
            if line.strip().startswith("*") or not line.strip():
                break
            if line.strip().startswith("-"):
                continue
            try:
                out.append([int(x) for x in line.split()])
            except ValueError:
                raise FormatError(f"{path}: unexpected line {line.strip()!r}") from None
        return out

    n_jobs = None
    for line in lines:
        m = re.match(r"\s*jobs \(incl\. supersource/sink \)\s*:\s*(\d+)", line)
        if m:
            n_jobs = int(m.group(1))
    prec = rows_after(section("PRECEDENCE RELATIONS"), 2)
    reqs = rows_after(section("REQUESTS/DURATIONS"), 2)
    k = section("RESOURCEAVAILABILITIES")
    names_line = lines[k + 1].split()
    names = [f"{a}{b}" for a, b in zip(names_line[::2], names_line[1::2], strict=True)]
    capacities = [int(x) for x in lines[k + 2].split()]
    n = len(prec)
    if n_jobs is not None and n != n_jobs:
        raise FormatError(f"{path}: PRECEDENCE RELATIONS: expected {n_jobs} jobs, found {n}")
    if len(reqs) != n:
        raise FormatError(f"{path}: REQUESTS/DURATIONS: expected {n} jobs, found {len(reqs)}")
    if len(capacities) != len(names):
        raise FormatError(f"{path}: RESOURCEAVAILABILITIES: expected {len(names)} capacities")
    renewable = [i for i, name in enumerate(names) if name.startswith("R")]
    tasks = []
    for row in reqs:
        job, mode, duration, *demand = row
        if mode != 1:
            raise FormatError(f"{path}: job {job} has mode {mode}: only single-mode is supported")
        if len(demand) != len(names):
            raise FormatError(f"{path}: job {job}: expected {len(names)} resource demands")
        tasks.append(
            Task(
                id=str(job),
                modes=(("", duration),),
                demands=tuple(demand[i] for i in renewable),
                description=f"job {job}",
            )
        )
    precedences = []
    for row in prec:
        job, _modes, count, *succ = row
        if len(succ) != count:
            raise FormatError(f"{path}: job {job}: expected {count} successors, got {len(succ)}")
        for s in succ:
            if not 1 <= s <= n:
                raise FormatError(f"{path}: job {job}: unknown successor {s}")
            precedences.append((job - 1, s - 1))
    return ScheduleProblem(
        name=path.name,
        tasks=tuple(tasks),
        precedences=tuple(precedences),
        resources=tuple((names[i], capacities[i]) for i in renewable),
        credit=CREDIT,
    )
