"""What the CP-SAT models share: integer scaling, the solver's parameters, the result.

CP-SAT works on integers: costs and durations are scaled by the smallest power of ten
(up to 10**6) that makes them integral, and scaled back in the results.

Same input, same answer: a solve stops on CP-SAT's *deterministic* time
(``max_deterministic_time``, a count of work, the same on every run and at any load), with
one worker and a fixed seed (:func:`new_solver`), so its result is a function of the model
alone. Time limits stay in seconds, *search seconds*: :data:`DETERMINISTIC_PER_SECOND` units
of deterministic time each, about a second of one core's search on the scheduling models
(:func:`search_seconds` converts back). Wall-clock time only bounds a solve as a safety net
(:func:`wall_safety`, ``max_time_in_seconds``); a stage stopped by it says so among its
timings (``wall_stop``), never in the plan document.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from asp.errors import ScheduleError
from asp.game import rules
from asp.numbers import json_number

MAX_SCALE_DIGITS = 6


@dataclass(frozen=True)
class BaselineResult:
    """Outcome of a CP-SAT solve.

    Attributes
    ----------
    kind : str
        ``"path"`` or ``"schedule"``.
    status : str
        CP-SAT status name (``OPTIMAL``, ``FEASIBLE``, ``INFEASIBLE``, ``UNKNOWN``, ...).
    objective, bound : float or None
        Best objective found and the proven bound (original units).
    wall_s : float
        Wall time of the solve, seconds.
    detail : dict
        ``path`` (node ids) and ``edges`` for a path; ``schedule`` (one dict per task with
        ``task, agent, start, end``) and the lower bounds for a schedule.
    """

    kind: str
    name: str
    status: str
    objective: float | None
    bound: float | None
    wall_s: float
    detail: dict = field(default_factory=dict)
    credit: str = ""

    def to_dict(self) -> dict:
        out = {
            "kind": self.kind,
            "name": self.name,
            "status": self.status,
            "objective": json_number(_significant(self.objective)),
            "bound": json_number(_significant(self.bound)),
            "wall_s": round(self.wall_s, 3),
        }
        out.update(self.detail)
        if self.credit:
            out["credit"] = self.credit
        return out


def _significant(x, digits: int = 12):
    """``x`` to ``digits`` significant digits (a tiny cost stays visible, unlike round(x, 6))."""
    return None if x is None else float(f"{float(x):.{digits}g}")


EXACT_HEADROOM = 2**53
"""Scaled sums stay below this: integers there are exact in float64 and well inside CP-SAT's
int64."""


def exact_scale(values, n_terms: int) -> tuple[int, bool]:
    """The power of ten making every value an integer, as CP-SAT needs, and whether it is exact.

    The smallest ``10**k`` that makes every value integral (to the relative cost tolerance,
    :data:`asp.game.rules.COST_TOL`; a nonzero value never becomes 0) while
    ``n_terms`` of the largest value, scaled, stay within :data:`EXACT_HEADROOM`; if none
    does, the largest such scale and ``False``: the values are then rounded to ``1 / scale``.
    """
    arr = np.abs(np.asarray(values, dtype=np.float64))
    top = float(arr.max()) if arr.size else 0.0
    best = 1
    for k in range(19):
        scale = 10**k
        if k and top * scale * max(n_terms, 1) > EXACT_HEADROOM:
            break
        best = scale
        scaled = arr * scale
        if np.all(np.abs(scaled - np.round(scaled)) <= rules.COST_TOL * scaled):
            return scale, True
    return best, False


def integer_scale(values) -> int:
    """Smallest power of ten (<= 10**6) making every value integral (else 10**6, rounded)."""
    arr = np.asarray(list(values), dtype=np.float64)
    for k in range(MAX_SCALE_DIGITS + 1):
        scaled = arr * 10**k
        if np.all(
            np.abs(scaled - np.round(scaled)) <= rules.COST_TOL * np.maximum(1.0, np.abs(scaled))
        ):
            return 10**k
    return 10**MAX_SCALE_DIGITS


DETERMINISTIC_PER_SECOND = 0.15
"""Units of CP-SAT's deterministic time in a search second: measured on the makespan models
with one worker, 2.0 units took 15.5 s of CPU on KILBRID's assembly (297 operations) and
0.5 units 3.6 s on a random 40-task, 3-agent job (a unit is about 7 s of one core there)."""


def search_seconds(deterministic_time: float) -> float:
    """CP-SAT's deterministic time in search seconds (:data:`DETERMINISTIC_PER_SECOND`)."""
    return float(deterministic_time) / DETERMINISTIC_PER_SECOND


WALL_SAFETY_FACTOR, WALL_SAFETY_S = 3.0, 30.0
"""The wall-clock safety net of a CP-SAT stage of ``t`` seconds of deterministic time:
``WALL_SAFETY_FACTOR * t + WALL_SAFETY_S`` seconds (:func:`wall_safety`)."""


def wall_safety(time_limit: float) -> float:
    """Wall-clock seconds after which a stage given ``time_limit`` search seconds stops
    anyway (a machine so loaded, or replays so slow, that the deterministic clock is no
    guide); its result then depends on the load, and says so."""
    return WALL_SAFETY_FACTOR * float(time_limit) + WALL_SAFETY_S


def new_solver(time_limit: float, workers: int, seed: int, wall_limit: float | None = None):
    """A CP-SAT solver stopping after ``time_limit`` search seconds (deterministic), with
    ``workers`` workers (1: the same result on every run; CP-SAT's parallel search is not
    repeatable) and ``seed``; ``wall_limit`` (default :func:`wall_safety`) is the
    wall-clock safety net."""
    from ortools.sat.python import cp_model

    if workers < 1:
        raise ScheduleError(f"workers: expected a positive integer, got {workers}")
    if not time_limit > 0:
        raise ScheduleError(f"time_limit: expected a positive number of seconds, got {time_limit}")
    solver = cp_model.CpSolver()
    solver.parameters.max_deterministic_time = float(time_limit) * DETERMINISTIC_PER_SECOND
    solver.parameters.max_time_in_seconds = float(
        wall_safety(time_limit) if wall_limit is None else max(wall_limit, 1e-3)
    )
    solver.parameters.num_workers = int(workers)
    solver.parameters.random_seed = int(seed)
    return solver
