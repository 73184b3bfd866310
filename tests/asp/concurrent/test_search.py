"""The on-the-fly search: the compiled game's values, certified policies, intervals."""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from asp.concurrent.curve import solve_curve
from asp.concurrent.model import UNBOUNDED
from asp.concurrent.rules import commit_rows, concurrent_rules
from asp.concurrent.search import (
    GREEDY,
    HYBRID,
    SCHEDULE,
    Limits,
    Search,
)
from asp.errors import SpecError
from asp.game.solve import solve
from asp.graph.state_graph import build_state_graph
from asp.graph.symmetry import interchangeable_blocks, reduced_state_graph
from tests.asp.concurrent.test_rules import job, oracle_values, random_jobs
from tests.asp.graph.test_symmetry_workspaces import GROUPINGS, random_alike_spec

SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def top_budget(agents: dict, ops: list) -> int:
    return sum(1 for a in agents.values() if a["side"] == "human") * len(ops)


def start_values(game, budgets) -> list[float]:
    sol = solve(game.dag)
    return [float(sol.value[game.starts[b], 0]) for b in budgets]


@SETTINGS
@given(random_jobs(humans=(1, 2), ranges=True))
def test_search_gives_the_compiled_game_values(data):
    ops, agents = data
    spec, graph = job(ops, agents=agents)
    rules = concurrent_rules(spec, graph)
    top = top_budget(agents, ops)
    want = oracle_values(spec, graph, top)
    search = Search(rules)
    assert [search.value(k) for k in range(top + 1)] == want
    assert search.value(None) == want[-1]


@SETTINGS
@given(random_jobs(humans=(1, 2), ranges=True))
def test_curve_and_robust_policy_are_exact(data):
    ops, agents = data
    spec, graph = job(ops, agents=agents)
    rules = concurrent_rules(spec, graph)
    top = top_budget(agents, ops)
    want = [w / rules.scale for w in oracle_values(spec, graph, top)]
    curve = solve_curve(rules, max_k=top)
    assert curve.stopped is None and all(curve.exact) and curve.policy == "robust"
    assert list(curve.lower[:-1]) == want[: curve.k + 1]
    assert curve.lower[-1] == want[-1]
    # The plan's policy, certified by an exact best response in its own policy game,
    # guarantees W*(k) at every budget: it is robust-optimal.
    assert start_values(curve.game, range(curve.k + 1)) == want[: curve.k + 1]
    # ... and the policy is optimal at every state it reaches, not only at the start.
    search = Search(rules)
    sol = curve.solution
    game = curve.game
    for v in range(1, min(game.dag.n_nodes, 60)):
        kind, state, running, budget, _ = game.nodes[v]
        if kind != "R":
            continue
        from asp.concurrent.rules import Position

        exact = search.value_at(Position(state, budget, running))
        assert round(sol.value[v, 0] * rules.scale) == exact


@SETTINGS
@given(random_jobs(humans=(1, 2)))
def test_fixed_policies_never_fall_as_k_grows(data):
    ops, agents = data
    spec, graph = job(ops, agents=agents)
    rules = concurrent_rules(spec, graph)
    top = top_budget(agents, ops)
    search = Search(rules)
    search.value(top)  # the hybrid policy reads the table's moves
    budgets = [UNBOUNDED, *range(top + 1)]
    rows = [
        {"task": op["id"], "agent": next(iter(op["agents"])), "start": i}
        for i, op in enumerate(ops)
    ]
    for kind in (GREEDY, HYBRID, SCHEDULE):
        game = search.policy_game([None, *range(top + 1)], kind, rows)
        values = start_values(game, budgets)
        finite, inf = values[1:], values[0]
        assert all(a <= b for a, b in zip(finite, finite[1:], strict=False)), (kind, values)
        assert finite[-1] == inf  # k = inf is the budget at its cap


@SETTINGS
@given(random_jobs(humans=(1, 2), ranges=True), st.integers(1, 40))
def test_a_stopped_search_gives_intervals_around_the_exact_values(data, nodes):
    ops, agents = data
    spec, graph = job(ops, agents=agents)
    rules = concurrent_rules(spec, graph)
    top = top_budget(agents, ops)
    want = [w / rules.scale for w in oracle_values(spec, graph, top)]
    curve = solve_curve(rules, max_k=top, limits=Limits(max_nodes=nodes))
    for k, (lo, hi) in enumerate(zip(curve.lower[:-1], curve.upper[:-1], strict=True)):
        assert lo <= want[k] <= hi, (k, lo, want[k], hi)
    assert curve.lower[-1] <= want[-1] <= curve.upper[-1]
    assert list(curve.lower) == sorted(curve.lower)
    assert list(curve.upper) == sorted(curve.upper)
    # The policy handed over is certified at U: its own worst case at the plan's budget.
    certified = start_values(curve.game, [curve.k])[0]
    assert certified == curve.upper[curve.k]


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    data=st.data(),
    copies=st.integers(2, 3),
    singles=st.integers(0, 2),
    grouping=st.sampled_from([None, *sorted(GROUPINGS)]),
)
def test_alike_parts_on_the_fixed_order_graph_give_the_full_game(data, copies, singles, grouping):
    spec, rel = random_alike_spec(data.draw, copies, singles, grouping)
    try:
        full = build_state_graph(spec, rel)
    except SpecError:
        return
    fixed = reduced_state_graph(spec, rel)
    if fixed is None:
        return
    if interchangeable_blocks(spec, rel, chains_only=False) != interchangeable_blocks(spec, rel):
        return
    a = solve_curve(concurrent_rules(spec, full), max_k=3)
    b = solve_curve(concurrent_rules(fixed.spec, fixed), max_k=3)
    assert a.lower == b.lower and a.upper == b.upper


def test_hand_checked_curve_and_progress(capsys):
    spec, graph = job(
        [
            {"id": "p", "agents": {"H": 1}},
            {"id": "q", "agents": {"H": 5}},
            {"id": "r", "agents": {"R": 5}, "after": ["p"]},
        ]
    )
    curve = solve_curve(concurrent_rules(spec, graph), progress=True)
    assert curve.lower == curve.upper == (6, 11, 11, 11)
    assert curve.flat and curve.k == 2
    rows = curve.to_list()
    assert rows[0] == {"k": 0, "bound": 6, "lower": 6, "upper": 6, "exact": True}
    assert rows[-1]["k"] is None
    assert "W*(0) = 6" in capsys.readouterr().err


def test_limits_are_checked():
    spec, graph = job([{"id": "a", "agents": {"R": 2, "H": 3}}, {"id": "b", "agents": {"H": 1}}])
    rules = concurrent_rules(spec, graph)
    search = Search(rules, Limits(max_nodes=1))
    assert search.value(0) is None and search.stopped == "node limit"
    with pytest.raises(ValueError, match="memory"):
        Search(rules, Limits(memory=10))


@SETTINGS
@given(
    random_jobs(humans=(1, 2), ranges=True), st.randoms(use_true_random=False), st.integers(0, 3)
)
def test_schedule_hints_and_proven_floors_keep_the_values(data, rnd, below):
    """Rules 6 and 7: a schedule's commitments tried first (any schedule, even a poor one)
    and a search from a proven floor (the value one budget lower, or any bound below it)
    give the compiled game's values."""
    ops, agents = data
    spec, graph = job(ops, agents=agents)
    rules = concurrent_rules(spec, graph)
    top = top_budget(agents, ops)
    want = oracle_values(spec, graph, top)
    order = list(ops)
    rnd.shuffle(order)
    rows = [
        {"task": op["id"], "agent": rnd.choice(sorted(op["agents"])), "start": i}
        for i, op in enumerate(order)
    ]
    search = Search(rules, schedule=rows)
    for k in range(top + 1):
        floor = max(0, (want[k - 1] if k else want[0]) - below)
        assert search.value(k, floor, want[-1] + 1) == want[k], k
    assert search.value(None, want[0]) == want[-1]
    curve = solve_curve(rules, max_k=top, schedule=rows, lower=want[0] / rules.scale)
    assert curve.stopped is None and all(curve.exact) and curve.policy == "robust"
    assert [round(x * rules.scale) for x in curve.lower[:-1]] == want[: curve.k + 1]
    assert (
        start_values(curve.game, range(curve.k + 1))
        == [w / rules.scale for w in want][: curve.k + 1]
    )


@SETTINGS
@given(random_jobs(humans=(1, 2), ranges=True))
def test_a_table_that_grows_gives_the_same_values(data):
    """A search table that starts at 16 entries and grows four-fold when full (the entries
    rehashed, the search run again where it stopped): the compiled game's values and the
    robust policy's certificate."""
    import asp.concurrent.search as search_module

    ops, agents = data
    spec, graph = job(ops, agents=agents)
    rules = concurrent_rules(spec, graph)
    top = top_budget(agents, ops)
    want = oracle_values(spec, graph, top)
    first = search_module.FIRST_ENTRIES
    search_module.FIRST_ENTRIES = 16
    try:
        search = Search(rules)
        assert [search.value(k) for k in range(top + 1)] == want
        curve = solve_curve(rules, max_k=top)
    finally:
        search_module.FIRST_ENTRIES = first
    assert search.stopped is None and all(curve.exact) and curve.policy == "robust"
    assert (
        start_values(curve.game, range(curve.k + 1))
        == [w / rules.scale for w in want][: curve.k + 1]
    )


def every_position(rules, pos, out: dict) -> int:
    """The exact value (scaled) of ``pos`` by plain recursion over the rules; ``out`` gets
    every position reached, by key, with its value."""
    if rules.is_end(pos):
        return 0
    key = rules.key(pos)
    if key not in out:
        out[key] = (
            pos,
            min(
                max(r.delta + every_position(rules, nxt, out) for r, nxt in rules.replies(pos, c))
                for c in rules.commits(pos)
            ),
        )
    return out[key][1]


@SETTINGS
@given(
    random_jobs(humans=(1, 2), ranges=True), st.randoms(use_true_random=False), st.integers(0, 3)
)
def test_deviation_aware_bounds_hold_every_exact_value(data, rnd, slack):
    """Rule 9: after searches of the budgets in any order and from any proven floor, every
    position of the game (each budget's) has its exact value inside the interval the table
    proves for it, or inside the interval a new entry would start with (its lower budgets'
    proven floors, its higher budgets' ceilings); the values are the compiled game's."""
    ops, agents = data
    spec, graph = job(ops, agents=agents)
    rules = concurrent_rules(spec, graph)
    top = top_budget(agents, ops)
    want = oracle_values(spec, graph, top)
    exact: dict = {}
    assert [every_position(rules, rules.start(k), exact) for k in range(top + 1)] == want
    search = Search(rules)
    budgets = list(range(top + 1))
    rnd.shuffle(budgets)
    for k in budgets:
        floor = max(0, want[k] - rnd.randint(0, slack))
        assert search.value(k, floor, want[-1] + 1 + rnd.randint(0, slack)) == want[k], k
        for pos, w in exact.values():
            lo, hi = search.interval(pos)
            assert lo <= w <= hi, (pos, lo, w, hi)


@SETTINGS
@given(random_jobs(humans=(1, 2), ranges=True), st.randoms(use_true_random=False))
def test_the_robust_move_is_optimal_at_every_position(data, rnd):
    """Rule 10: after searches of the budgets in any order, the robust policy's move at
    every position of the game (a higher budget's move where the table proves it, else the
    search's) achieves the position's exact value against every reply."""
    from asp.concurrent.search import ROBUST, policy_choice

    ops, agents = data
    spec, graph = job(ops, agents=agents)
    rules = concurrent_rules(spec, graph)
    top = top_budget(agents, ops)
    exact: dict = {}
    want = [every_position(rules, rules.start(k), exact) for k in range(top + 1)]
    search = Search(rules)
    budgets = list(range(top + 1))
    rnd.shuffle(budgets)
    for k in budgets:
        assert search.value(k) == want[k]
    items = list(exact.values())
    rnd.shuffle(items)
    t = rules.tables
    for pos, w in items:
        commits = rules.commits(pos)
        rows = commit_rows(t, pos.row())
        i = policy_choice(
            t, search.table, pos.row(), rows, ROBUST, search.prefs, search.n_prefs, search.stats
        )
        got = max(
            r.delta + (0 if rules.is_end(nxt) else exact[rules.key(nxt)][1])
            for r, nxt in rules.replies(pos, commits[i])
        )
        assert got == w, (pos, i, got, w)
