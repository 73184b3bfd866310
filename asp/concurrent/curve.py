"""The curve ``W*(k)`` of the concurrent game: searched, then certified (:func:`solve_curve`).

:func:`solve_curve` runs the on-the-fly search (:mod:`asp.concurrent.search`) for
``W*(0)``, ``W*(inf)`` and ``W*(1), W*(2), ...`` until the curve is flat, ``max_k`` or a
limit; :func:`certified_curve` then turns what it found into a :class:`Curve`: exact values
where the search finished, else a certified interval ``[L(k), U(k)]``, ``U`` the least
certified worst case of the policies it has (an exact best response of the human side,
values only: :func:`asp.concurrent.certify.best_response_values`), and the policy game of
the policy handed to the cell.
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass

import numpy as np

from asp.concurrent.build import ConcurrentGame
from asp.concurrent.certify import best_response_values
from asp.concurrent.model import UNBOUNDED
from asp.concurrent.rules import Rules, lower_bound_of
from asp.concurrent.search import (
    GREEDY,
    HYBRID,
    INF,
    POSITIONS_PER_SECOND,
    ROBUST,
    SCHEDULE,
    Limits,
    Search,
    work_positions,
)


@dataclass(frozen=True, eq=False)
class Curve:
    """``W*(k)`` for ``k = 0..K`` and ``k = inf``, each exact or as a certified interval.

    Attributes
    ----------
    lower, upper : tuple of float
        ``L(k)`` and ``U(k)`` for ``k = 0..K`` then ``k = inf`` (spec units):
        ``L(k) <= W*(k) <= U(k)``, equal where exact; both never fall as ``k`` grows.
    bounds : tuple of float
        The certified worst case of the plan's policy for the same budgets (``upper`` at
        ``K``; ``W*(k)`` where exact). At ``inf``: the policy's own when its game has that
        start, else ``upper``.
    flat : bool
        ``W*(K) = W*(inf)`` is proven (the curve stops there), else ``max_k`` or a limit
        stopped it.
    game : asp.concurrent.build.ConcurrentGame
        The policy game of the plan's policy (its starts: budgets ``0..K``, and ``inf``
        unless the policy is the exact one; the plan's ``K`` is the DAG's start), and
        ``solution`` its exact solution: each state's bound is the policy's certified worst
        case from it.
    policy : str
        ``"robust"`` (exact), ``"hybrid"``, ``"greedy"`` or ``"schedule"``: the certified
        policy of least worst case at ``K``.
    schedule_worst : list of {"k", "bound"}
        The CP-SAT schedule's certified worst case per ``k`` (``None`` for ``inf``), empty
        without a schedule or when its policy game was over the limits.
    stopped : str or None
        The limit that stopped the search (``"time limit"``: its search seconds, ...), None
        when exact.
    nodes, positions : int
        Positions the search expanded, and the table's entries.
    seconds : float
    wall_stop : float or None
        The seconds of the wall clock's safety net that stopped the search or a certificate
        (:mod:`asp.concurrent.search`), when one did: the curve then depends on the load
        (``timings.json`` says so, never ``plan.json``).
    """

    lower: tuple[float, ...]
    upper: tuple[float, ...]
    bounds: tuple[float, ...]
    flat: bool
    game: ConcurrentGame
    solution: object
    policy: str
    schedule_worst: list
    stopped: str | None
    nodes: int
    positions: int
    seconds: float
    wall_stop: float | None = None

    @property
    def k(self) -> int:
        """The plan's budget ``K``."""
        return len(self.lower) - 2

    @property
    def exact(self) -> tuple[bool, ...]:
        return tuple(lo == hi for lo, hi in zip(self.lower, self.upper, strict=True))

    def gap(self, i: int) -> float:
        """The gap of entry ``i`` in per cent of the upper bound."""
        lo, hi = self.lower[i], self.upper[i]
        if not np.isfinite(hi):  # no policy certified there (k = inf past its time)
            return 100.0
        return 0.0 if hi <= lo or hi <= 0 else 100.0 * (hi - lo) / hi

    @property
    def largest_gap(self) -> float:
        """The largest gap (per cent) of the certified entries."""
        return max((self.gap(i) for i in range(len(self.lower)) if self.certified(i)), default=0)

    def certified(self, i: int) -> bool:
        """Some policy is certified at entry ``i`` (always, but ``k = inf`` when its best
        responses were over the time allowed)."""
        return bool(np.isfinite(self.upper[i]))

    def to_list(self) -> list[dict]:
        """``[{"k", "bound", "lower", "upper", "exact"}, ..., {"k": None, ...}]``: ``bound``
        is the certified worst case of the plan's policy (``W*(k)`` where exact). The row
        of ``k = inf`` is left out when no policy is certified there (:meth:`certified`)."""
        out = []
        n = len(self.lower)
        for i in range(n):
            if not self.certified(i):
                continue
            out.append(
                {
                    "k": None if i == n - 1 else i,
                    "bound": _number(self.bounds[i]),
                    "lower": _number(self.lower[i]),
                    "upper": _number(self.upper[i]),
                    "exact": self.lower[i] == self.upper[i],
                }
            )
        return out


def _number(x: float):
    from asp.numbers import json_number

    return json_number(x, 6)


def solve_curve(
    rules: Rules,
    *,
    max_k: int = 12,
    min_k: int = 2,
    limits: Limits | None = None,
    schedule: list[dict] | None = None,
    lower: float | None = None,
    progress: bool = False,
) -> Curve:
    """``W*(k)`` for ``k = 0, 1, ...`` until it reaches ``W*(inf)`` (module docstring).

    Parameters
    ----------
    max_k : int
        The largest finite budget of the curve.
    min_k : int
        The curve goes at least this far (while ``<= max_k``), flat or not.
    limits : Limits, optional
        Memory, positions and search seconds for the search (default :class:`Limits`);
        every share of the search seconds below is counted in positions, so the curve is
        the same on every run.
    schedule : list of dict, optional
        A CP-SAT schedule (``{"task", "agent", "start"}`` rows), run as a plan: certified for
        every ``k``, and one more policy for ``U`` when the search stops.
    lower : float, optional
        A proven lower bound of ``W*(0)`` (the CP-SAT bound), spec units.
    progress : bool
        A line on stderr per value found and every second of search.

    Raises
    ------
    asp.errors.GameError
        The memory allowed holds no search table, or no policy could be certified in it.
    """

    t0 = time.perf_counter()
    search = Search(rules, limits, progress=progress, schedule=schedule)
    scale = rules.scale
    floor = int(np.ceil((lower or 0) * scale - 1e-9))
    floor = max(floor, int(lower_bound_of(rules.tables, rules.start(0).row())))

    def say(text: str) -> None:
        if progress:
            print(f"  {text} ({time.perf_counter() - t0:.1f} s)", file=sys.stderr, flush=True)

    exact: dict = {}  # budget (None: inf) -> W* (scaled)
    end = search.budget  # positions expanded the search seconds allow (None: no limit)
    v0 = search.value(0, floor)
    if v0 is not None:
        exact[0] = v0
        say(f"W*(0) = {v0 / scale:g}")
        # W*(inf) next, in half the search seconds left when there is a limit: past it,
        # the finite budgets (the person's few deviations: far smaller games) go on in the
        # rest.
        if end is not None:
            search.resume(search.nodes + max(0, end - search.nodes) // 2)
        top = search.value(None, v0)
        search.resume(end)
        if top is not None:
            exact[None] = top
            say(f"W*(inf) = {top / scale:g}")
        else:
            say("W*(inf) not found in half the time: the finite budgets first")
    k = 0
    while 0 in exact and k < max_k:
        if None in exact and exact[k] == exact[None]:
            if k >= min_k:
                break
            v = exact[None]  # flat from k on (the curve never falls, never passes W*(inf))
        else:
            v = search.value(k + 1, exact[k], exact[None] + 1 if None in exact else INF)
            if v is None:
                break
            say(f"W*({k + 1}) = {v / scale:g}")
        exact[k + 1] = v
        k += 1
    if 0 in exact and None not in exact and not search.stopped:  # in the time still left
        top = search.value(None, exact[k])
        if top is not None:
            exact[None] = top
            say(f"W*(inf) = {top / scale:g}")
    finished = None in exact and (k == max_k or exact[k] == exact[None])
    flat = None in exact and exact.get(k) == exact[None]
    K = k if finished or k == max_k else min(max_k, max(min_k, k))  # stopped: as reached
    budgets = list(range(K + 1))
    return certified_curve(
        search,
        exact,
        budgets,
        finished=all(b in exact for b in range(K + 1)),
        flat=flat,
        floor=floor,
        schedule=schedule,
        t0=t0,
        say=say,
        progress=progress,
    )


def certified_curve(
    search,
    exact: dict,
    budgets: list[int],
    *,
    finished: bool,
    flat: bool,
    floor: int,
    schedule: list[dict] | None,
    t0: float,
    say,
    progress: bool = False,
):
    """The :class:`Curve` of a search that has found the values
    ``exact`` (budget, None for ``k = inf`` -> scaled ``W*``) for the plan's ``budgets``
    (``0..K``).

    ``U(k)`` is the least certified worst case, at ``k`` or at a larger budget (``W*`` never
    falls), of the policies certified here: the robust policy when every value is known
    (its policy game, which the plan file needs anyway), else the hybrid and greedy policies,
    and the CP-SAT schedule run as a plan, each by :func:`best_response_values` (values only:
    a policy whose game is over the memory allowed is still certified; with a time limit,
    half the search's seconds, shared out among them in turn). ``L(k)`` is the exact
    value, else the best bound the search proved (never below ``floor``, the CP-SAT bound,
    nor below ``L(k - 1)``). Only the policy handed to the cell, the one certified at
    ``U(K)``, gets its policy game: with every budget's start, else with ``0..K`` only (its
    bound at ``inf`` is then its certified value); if neither fits, the next policy in order
    of certified worst case whose game fits.

    Raises
    ------
    asp.errors.GameError
        No policy could be certified, or none of those certified has a policy game that fits
        the memory allowed (the message names ``--max-memory``).
    """
    from asp.errors import GameError
    from asp.game.solve import solve

    rules = search.rules
    scale = rules.scale
    K = budgets[-1]
    ks: list = [*budgets, None]
    everything = [None, *budgets]
    kinds = {"hybrid": HYBRID, "greedy": GREEDY, "schedule": SCHEDULE}
    certified: dict[str, dict] = {}  # name -> budget -> certified worst case (spec units)
    games: dict[str, tuple] = {}  # name -> (policy game, its solution)
    stopped = search.stopped
    limit = search.limits.time_limit  # half the search seconds for the certificates, in turn
    seconds = None if limit is None else limit / 2
    if finished:
        # W*(0..K) are known: the robust policy's positions are searched to their values
        # again (on the search's table, past its budget: small games at budgets <= K).
        if seconds is None:
            search.resume(None)
        else:
            search.resume(search.nodes + work_positions(seconds))
            search.safety_net(seconds)
        game = search.policy_game(budgets, ROBUST)
        if game is not None:
            sol = solve(game.dag)
            games["robust"] = (game, sol)
            certified["robust"] = _start_values(game, sol)
    robust_inf = "robust" in certified and None in exact
    names = ["schedule"] if robust_inf else ["hybrid", "greedy", "schedule"]
    names = [n for n in names if n != "schedule" or schedule]
    valued = search.valued  # positions the certificates valued before these

    def share(left: int) -> float | None:  # search seconds, counted in positions valued
        if seconds is None:
            return None
        return max(1.0, (seconds - (search.valued - valued) / POSITIONS_PER_SECOND) / left)

    found: dict[str, dict] = {}
    # The finite budgets first (the person's deviations are few: small best responses),
    # then k = inf (the budget at its cap: every order of the person's operations), the
    # policies of least worst case at K first.
    for i, name in enumerate(names):
        values = best_response_values(
            search, kinds[name], budgets, schedule=schedule, time_limit=share(2 * len(names) - i),
            progress=progress,
        )  # fmt: skip
        if values is None:
            say(f"the {name} policy: its best response is over the memory or time allowed")
            continue
        found[name] = values
    ranked = sorted(found, key=lambda n: (found[n][K], names.index(n)))
    for i, name in enumerate(ranked):
        top = best_response_values(
            search, kinds[name], [None], schedule=schedule, time_limit=share(len(ranked) - i),
            progress=progress,
        )  # fmt: skip
        if top is not None:
            found[name][None] = top[None]
        say(f"the {name} policy certified at {_fmt_values(found[name], budgets)}")
    schedule_worst = [
        {"k": b, "bound": found["schedule"][b]} for b in ks if b in found.get("schedule", {})
    ]
    if not robust_inf:
        certified.update(found)
    if not certified:
        raise GameError(
            f"--max-memory: {search.limits.memory:,} bytes certify no policy of this game "
            "(each best response was over the limit); allow more memory"
        )
    # U(k): the least certified worst case at k or at a larger budget (W* never falls);
    # L(k): exact, else the best proven bound, never below L(k - 1).
    upper, lows = [], []
    for i, b in enumerate(ks):
        later = ks[i:]
        u = min(
            (vals[c] for vals in certified.values() for c in later if c in vals), default=np.inf
        )
        if b in exact:
            u = min(u, exact[b] / scale)
        upper.append(u)
        lo = exact[b] if b in exact else max(search.proven(b)[0], floor)
        lows.append(lo / scale)
    lower_k = list(np.maximum.accumulate(lows))
    upper_k = list(np.minimum.accumulate(upper[::-1])[::-1])
    # The policy handed over: least certified worst case at K (the robust one on ties).
    order = sorted(certified, key=lambda n: (certified[n][K], n != "robust"))
    name = None
    for name in order:
        if name in games:
            break
        kind = kinds[name]
        sched = schedule if name == "schedule" else None
        game = None
        if None in certified[name]:  # (else its game at the cap is too large to walk)
            game = search.policy_game(everything, kind, sched)
        game = game or search.policy_game(budgets, kind, sched)
        if game is not None:
            games[name] = (game, solve(game.dag))
            break
        say(f"the {name} policy's game is over the memory allowed")
    if name not in games:
        raise GameError(
            f"--max-memory: {search.limits.memory:,} bytes hold the policy game of no "
            f"certified policy ({', '.join(order)}); allow more memory"
        )
    game, solution = games[name]
    values = certified[name]
    bounds = [values.get(b, upper_k[i]) for i, b in enumerate(ks)]
    if stopped:
        finite = [i for i in range(len(ks)) if np.isfinite(upper_k[i]) and upper_k[i] > 0]
        gap = max((100 * (upper_k[i] - lower_k[i]) / upper_k[i] for i in finite), default=0)
        say(
            f"{stopped} reached: W*({K}) in [{lower_k[K]:g}, {upper_k[K]:g}], "
            f"the largest gap {gap:.1f} %"
        )
    return Curve(
        lower=tuple(float(x) for x in lower_k),
        upper=tuple(float(x) for x in upper_k),
        bounds=tuple(float(x) for x in bounds),
        flat=bool(flat),
        game=game,
        solution=solution,
        policy=name,
        schedule_worst=schedule_worst,
        stopped=stopped,
        nodes=search.nodes,
        positions=search.positions,
        seconds=time.perf_counter() - t0,
        wall_stop=search.wall_stop,
    )


def _start_values(game: ConcurrentGame, solution) -> dict:
    """Budget (None: ``k = inf``) -> the solved value at that budget's start."""
    return {
        (None if b == UNBOUNDED else b): float(solution.value[v, 0]) for b, v in game.starts.items()
    }


def _fmt_values(values: dict, budgets: list[int]) -> str:
    finite = " ".join(f"{values[b]:g}" for b in budgets)
    top = f"{values[None]:g}" if None in values else "not certified (over the time allowed)"
    return f"k = 0..{budgets[-1]}: {finite}, k = inf: {top}"
