"""The concurrent game move by move: the same game as the compiled one (the oracle)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from asp.concurrent.build import build_game
from asp.concurrent.model import WAIT, concurrent_model
from asp.concurrent.robustness import value
from asp.concurrent.rules import END_STATE, Position, concurrent_rules
from asp.errors import SpecError
from asp.game.solve import solve
from asp.graph.fixed_order import FixedOrder
from asp.graph.state_graph import build_state_graph
from asp.graph.symmetry import interchangeable_blocks, reduced_state_graph
from asp.spec import spec_from_dict, with_subassemblies
from tests.asp.concurrent.test_concurrent import job as concurrent_job
from tests.asp.graph.test_symmetry_workspaces import GROUPINGS, random_alike_spec


def job(ops: list[dict], agents: dict | None = None, tools: dict | None = None):
    """A spec without geometry and its state graph."""
    model = concurrent_job(ops, agents=agents, tools=tools)
    return model.spec, model.graph


def minimax(rules, pos, memo=None) -> int:
    """The value of ``pos`` (scaled) by plain recursion over the rules, memoised on keys."""
    memo = {} if memo is None else memo
    if rules.is_end(pos):
        return 0
    key = rules.key(pos)
    if key not in memo:
        memo[key] = min(
            max(reply.delta + minimax(rules, nxt, memo) for reply, nxt in rules.replies(pos, c))
            for c in rules.commits(pos)
        )
    return memo[key]


@st.composite
def random_jobs(draw, humans=(1, 1), ranges=False):
    n = draw(st.integers(2, 5))
    robots = draw(st.integers(1, 2))
    n_h = draw(st.integers(*humans))
    names = [f"H{i + 1}" for i in range(n_h)] + [f"R{i + 1}" for i in range(robots)]
    ops = []
    for i in range(n):
        allowed = draw(st.lists(st.sampled_from(names), min_size=1, max_size=2, unique=True))
        after = [f"o{j}" for j in range(i) if draw(st.booleans()) and draw(st.booleans())]
        agents = {}
        for a in allowed:
            d = draw(st.integers(1, 6))
            if ranges and a.startswith("H") and draw(st.booleans()):
                agents[a] = [d, d + draw(st.integers(1, 2))]
            else:
                agents[a] = d
        ops.append({"id": f"o{i}", "agents": agents, "after": after})
    used = {a for op in ops for a in op["agents"]}
    agents = {a: {"side": "human" if a.startswith("H") else "robot"} for a in names if a in used}
    return ops, agents


def oracle_values(spec, graph, top: int) -> list[int]:
    """W*(0..top) (scaled) of the compiled game."""
    model = concurrent_model(spec, graph)
    game = build_game(model, top)
    sol = solve(game.dag)
    return [round(value(game, sol, k) * model.scale) for k in range(top + 1)]


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(random_jobs(humans=(1, 2), ranges=True))
def test_walking_the_rules_gives_the_compiled_game_values(data):
    ops, agents = data
    spec, graph = job(ops, agents=agents)
    rules = concurrent_rules(spec, graph)
    n_humans = sum(1 for a in agents.values() if a["side"] == "human")
    top = n_humans * len(ops)  # budgets past this are never binding: k = inf
    want = oracle_values(spec, graph, top)
    memo: dict = {}
    got = [minimax(rules, rules.start(k), memo) for k in range(top + 1)]
    assert got == want
    assert minimax(rules, rules.start(None), memo) == want[-1]


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(random_jobs())
def test_one_person_unbounded_is_the_adversary_game(data):
    # With one person the robot can always tell it an operation it may start, so the
    # budget without limit is the uninstructed adversary of the compiled game.
    ops, agents = data
    spec, graph = job(ops, agents=agents)
    rules = concurrent_rules(spec, graph)
    model = concurrent_model(spec, graph)
    adversary = build_game(model, None)
    top = value(adversary, solve(adversary.dag), -1)
    assert minimax(rules, rules.start(None)) == round(top * model.scale)


def test_lower_bound_is_admissible_everywhere_on_random_jobs():
    rng = np.random.default_rng(0)
    for trial in range(12):
        n = int(rng.integers(3, 7))
        ops = []
        for i in range(n):
            agents = {"H": int(rng.integers(1, 7))}
            if rng.random() < 0.7 or i == 0:
                agents["R"] = int(rng.integers(1, 7))
            after = [f"o{j}" for j in range(i) if rng.random() < 0.3]
            ops.append({"id": f"o{i}", "agents": agents, "after": after})
        spec, graph = job(ops)
        rules = concurrent_rules(spec, graph)
        memo: dict = {}
        seen = [rules.start(2)]
        checked = 0
        while seen and checked < 400:
            pos = seen.pop()
            if rules.is_end(pos):
                continue
            exact = minimax(rules, pos, memo)
            assert rules.lower_bound(pos) * rules.scale <= exact, (trial, pos)
            checked += 1
            for c in rules.commits(pos):
                seen.extend(nxt for _, nxt in rules.replies(pos, c))


def p_q_r_rules():
    """The person's p (1 s) or q (5 s), then the robot's r after p."""
    spec, graph = job(
        [
            {"id": "p", "agents": {"H": 1}},
            {"id": "q", "agents": {"H": 5}},
            {"id": "r", "agents": {"R": 5}, "after": ["p"]},
        ]
    )
    return concurrent_rules(spec, graph)


def test_hand_checked_job_moves_and_positions():
    # The person should do p (1 s) so the robot can start r; q first costs 5 s of idle.
    rules = p_q_r_rules()
    start = rules.start(1)
    assert start == Position(0, 1, ((WAIT, 0), (WAIT, 0)))
    assert rules.budget_cap(start) == 2 and rules.start(None).budget == 2
    commits = rules.commits(start)
    # The robot has nothing to start: it waits and tells the person p or q.
    assert [c.ops for c in commits] == [(WAIT, 0), (WAIT, 1)]
    replies = rules.replies(start, commits[0])
    assert [(r.ops, r.durations, r.deviations, r.delta) for r, _ in replies] == [
        ((None, 0), (None, 1), 0, 1),
        ((None, 1), (None, 5), 1, 5),
    ]
    after_p = replies[0][1]
    assert after_p.budget == 1 and after_p.running == ((WAIT, 0), (WAIT, 0))
    assert minimax(rules, rules.start(0)) == 6 and minimax(rules, start) == 11
    assert rules.lower_bound(start) == 6  # p then r: the critical path
    features = rules.features(after_p)
    assert features.shape == (2 * 3 + 2 + 1,) and features[0] == 1 and features[-1] == 1
    assert rules.key(after_p) != rules.key(start)


def test_tables_are_one_structure_with_every_array_by_name_and_pickle():
    # The rules' arrays are one numba structure (one reference per kernel call); in Python
    # each is an attribute, a pickled copy plays the same moves, and a missing array is
    # refused by name.
    import pickle

    from asp.concurrent.rules import TABLE_FIELDS, Rules, Tables

    rules = p_q_r_rules()
    t = rules.tables
    assert all(isinstance(getattr(t, f), np.ndarray) for f in TABLE_FIELDS)
    copy = Rules(model=rules.model, tables=pickle.loads(pickle.dumps(t)), fixed=rules.fixed)
    for f in TABLE_FIELDS:
        assert np.array_equal(getattr(copy.tables, f), getattr(t, f))
    assert minimax(copy, copy.start(1)) == minimax(rules, rules.start(1)) == 11
    assert copy.lower_bound(copy.start(1)) == rules.lower_bound(rules.start(1))
    arrays = {f: getattr(t, f) for f in TABLE_FIELDS if f != "flex"}
    with pytest.raises(TypeError, match="flex"):
        Tables(**arrays)


def test_end_position_and_budget_errors():
    spec, graph = job([{"id": "a", "agents": {"R": 2}}], agents={"R": {"side": "robot"}})
    rules = concurrent_rules(spec, graph)
    (commit,) = rules.commits(rules.start(0))
    ((reply, end),) = rules.replies(rules.start(0), commit)
    assert reply.delta == 2 and rules.is_end(end) and end.state == END_STATE
    assert rules.commits(end) == []
    with pytest.raises(ValueError, match="deviation budget"):
        rules.start(-1)


def test_tool_changes_are_in_the_durations():
    spec, graph = job(
        [
            {"id": "a", "agents": {"R": 3}, "requires": {"R.bit": "x"}},
            {"id": "b", "agents": {"H": 2}, "sets": {"R.bit": "x"}},
        ],
        tools={"R.bit": {"initial": "y", "change_time": 1}},
    )
    rules = concurrent_rules(spec, graph)
    assert minimax(rules, rules.start(0)) == round(oracle_values(spec, graph, 0)[0])


def alike_values(graph, top: int = 2) -> list[int]:
    """W*(0..top) and W*(inf) (scaled) walked through the rules of ``graph``."""
    rules = concurrent_rules(graph.spec, graph)
    memo: dict = {}
    return [minimax(rules, rules.start(k), memo) for k in [*range(top + 1), None]]


def test_undone_fixed_order_of_alike_parts_gives_the_full_game():
    """The pinned disc: on the alternating game's graph (pins and screws in a fixed order)
    the rules run alike operations at once, and the curve is the full graph's."""
    from tests.asp.graph.test_symmetry import pinned_disc

    spec, rel = pinned_disc(3, 2)
    full = build_state_graph(spec, rel)
    fixed = reduced_state_graph(spec, rel)
    assert fixed.n_states < full.n_states
    want = oracle_values(spec, full, 2)
    model = concurrent_model(spec, full)
    adversary = build_game(model, None)
    top = round(value(adversary, solve(adversary.dag), -1) * model.scale)
    assert alike_values(fixed) == [*want, top]


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    data=st.data(),
    copies=st.integers(2, 3),
    singles=st.integers(0, 2),
    grouping=st.sampled_from([None, *sorted(GROUPINGS)]),
)
def test_random_alike_tables_fixed_order_undone_gives_the_full_game(
    data, copies, singles, grouping
):
    spec, rel = random_alike_spec(data.draw, copies, singles, grouping)
    try:
        full = build_state_graph(spec, rel)
    except SpecError:
        return  # no complete sequence
    fixed = reduced_state_graph(spec, rel)
    if fixed is None or FixedOrder.of_graph(fixed) is None:
        return
    if interchangeable_blocks(spec, rel, chains_only=False) != interchangeable_blocks(spec, rel):
        return  # blocks that are not chains (first of equals): the alternating game's only
    assert alike_values(fixed) == alike_values(full)


def unit_job():
    """A spec of three parts (the pin held) and its state graph with the plate and the pin
    as a subassembly added while building (as :func:`asmplan.pipeline.state_graph` adds
    units automatically): the graph's spec has one operation more than the spec."""
    data = {
        "parts": [{"id": p, "file": f"{p}.stl"} for p in ("base", "plate", "pin", "cap")],
        "agents": {"H": {"side": "human"}, "R": {"side": "robot"}},
        "base_part": "base",
        "operations": [
            {"id": "plate", "part": "plate", "agents": {"H": [2, 3], "R": 3}},
            {"id": "pin", "part": "pin", "agents": {"H": 1, "R": 2}, "held": True,
             "after": ["plate"]},
            {"id": "cap", "part": "cap", "agents": {"H": 2}},
        ],
    }  # fmt: skip
    spec = spec_from_dict(data, source="unit.yaml")
    return spec, build_state_graph(with_subassemblies(spec, [("unit", ["plate", "pin"])]))


def test_a_graph_with_units_added_plays_its_own_operations():
    """Issue 23 item 0 (the APLAN shear mold: 17 operations in the spec, 19 in the graph
    with its two units): the game is the graph's spec's, whichever spec is given."""
    spec, graph = unit_job()
    assert len(spec.operations) == 3 and len(graph.spec.operations) == 4
    rules = concurrent_rules(spec, graph)
    assert rules.model.spec is graph.spec
    own = concurrent_rules(graph.spec, graph)
    for b in (0, 1, None):
        assert minimax(rules, rules.start(b)) == minimax(own, own.start(b))
    adversary = build_game(concurrent_model(spec, graph), None)
    assert solve(adversary.dag).value is not None
    fewer = build_state_graph(replace(spec, operations=spec.operations[:2]))
    with pytest.raises(SpecError, match=r"unit.yaml: the state graph is of other operations"):
        concurrent_rules(spec, fewer)  # (not a graph of the spec's operations and more)
