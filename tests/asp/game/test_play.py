"""Game sessions (asp.game.play): the person against the robust robot or a best-response human."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from asp.game.dag import HUMAN, ROBOT, from_edges
from asp.game.play import GameSession, fast_greedy_policy
from asp.game.solve import solve
from asp.game.synth import synthetic_dag
from tests.asp.figures import figure4


def _play_out(session: GameSession, choose) -> GameSession:
    """Play to the end; ``choose(session) -> move number`` picks the person's moves."""
    session.advance()
    while not session.finished:
        session.play(choose(session))
        session.advance()
    return session


def _all_games(dag, person=HUMAN, robot="robust"):
    """Every finished session the person's choices can lead to (small graphs only)."""
    out = []

    def explore(prefix):
        session = GameSession(dag, person=person, robot=robot)
        session.advance()
        for k in prefix:
            session.play(k)
            session.advance()
        if session.finished:
            out.append(session)
            return
        for m in session.moves():
            explore([*prefix, m.number])

    explore([])
    return out


def test_robust_robot_chooses_node_3_on_figure4():
    session = GameSession(figure4())
    turns = session.advance()
    assert len(turns) == 1 and turns[0].player == ROBOT and turns[0].by == "computer"
    assert turns[0].move.target_id == 3
    assert "keeps the worst case at 3" in turns[0].reason
    assert "would allow up to 5" in turns[0].reason
    assert session.persons_turn and session.player == HUMAN
    assert session.cost == 1 and session.worst_remaining == 2 and session.coop_remaining == 2
    assert [m.target_id for m in session.moves()] == [4, 5]
    assert [m.worst_remaining for m in session.moves()] == [2, 2]


def test_whatever_the_human_does_the_cost_is_at_most_3():
    games = _all_games(figure4())
    assert len(games) == 2
    for session in games:
        s = session.summary()
        assert s.finished and s.cost <= 3 and s.held is True
        assert (s.tct, s.minimax, s.robot_worst) == (2, 3, 3)


def test_as_robot_choosing_node_2_the_best_response_human_takes_it_to_5():
    session = GameSession(figure4(), person=ROBOT)
    assert session.persons_turn
    moves = session.moves()
    assert [(m.target_id, m.worst_remaining) for m in moves] == [(2, 5), (3, 3)]
    turn = session.play(1)  # to node 2
    assert (turn.worst_before, turn.worst_after) == (3, 5)
    reply = session.advance()
    assert reply[0].player == HUMAN and reply[0].move.target_id == 6
    _play_out(session, lambda s: 1)
    s = session.summary()
    assert s.cost == 5 and s.minimax == 3 and s.held is None
    assert [step for step, _, loss in s.person_slips] == [1]
    assert "your choices cost 2 more" in "\n".join(s.lines())


def test_as_robot_playing_robust_matches_w_star():
    for session in _all_games(figure4(), person=ROBOT):
        assert session.cost >= 3  # the maximising human holds any robot to at least W*
    best = _play_out(
        GameSession(figure4(), person=ROBOT),
        lambda s: min(s.moves(), key=lambda m: m.worst_remaining).number,
    )
    assert best.cost == 3 and not best.summary().person_slips


def test_passes_are_announced_on_a_sided_dag():
    # a -(human)-> b -(robot)-> c -(robot)-> d: the robot passes first, then the human.
    dag = from_edges(
        ["a", "b", "c", "d"],
        [("a", "b"), ("b", "c"), ("c", "d")],
        sides=[HUMAN, ROBOT, ROBOT],
        operations=["o1", "o2", "o3"],
        agents=["H", "R1", "R1"],
    )
    session = GameSession(dag, descriptions={"o1": "place the base"})
    turns = session.advance()
    assert [t.passed for t in turns] == [True]
    assert turns[0].player == ROBOT and "passes at zero cost" in turns[0].reason
    (move,) = session.moves()
    assert move.label == "o1 H place the base"
    session.play(1)
    turns = session.advance()
    assert [(t.player, t.passed) for t in turns] == [(ROBOT, False), (HUMAN, True), (ROBOT, False)]
    assert session.finished and session.cost == 3
    assert session.summary().held is True
    assert [t.step for t in session.history] == [1, 2, 3, 4, 5]


def test_fast_greedy_robot_and_a_given_policy():
    dag = figure4()
    sol = solve(dag)
    fast = fast_greedy_policy(dag, sol)
    assert dag.node_ids[int(dag.targets[fast[dag.index_of(1)]])] == 2
    session = GameSession(dag, robot="fast-greedy")
    (turn,) = session.advance()
    assert turn.move.target_id == 2 and "cooperative fastest path" in turn.reason
    assert session.summary().robot_worst == 5
    _play_out(session, lambda s: max(s.moves(), key=lambda m: m.worst_remaining).number)
    s = session.summary()
    assert s.cost == 5 and s.held is True  # its own (weak) guarantee holds, W* does not
    given = GameSession(dag, robot=sol.robot_policy, robot_name="trained (run)")
    assert given.robot_name == "trained (run)" and given.summary().robot_worst == 3


def test_bad_calls_raise_value_error():
    session = GameSession(figure4())
    with pytest.raises(ValueError, match="not the person's turn"):
        session.play(1)
    session.advance()
    with pytest.raises(ValueError, match="from 1 to 2"):
        session.play(3)
    with pytest.raises(ValueError, match="person's turn"):
        session.step()
    with pytest.raises(ValueError, match="robot"):
        GameSession(figure4(), robot="clever")
    with pytest.raises(ValueError, match="person"):
        GameSession(figure4(), person=5)


def test_quitting_early_summarises_without_a_verdict():
    session = GameSession(figure4())
    session.advance()
    s = session.summary()
    assert not s.finished and s.held is None and s.cost == 1
    assert "not finished" in s.lines()[0]


def test_seeded_human_breaks_ties_and_still_maximises():
    dag = synthetic_dag(4, 4, 3, seed=2)
    value = solve(dag).minimax
    costs = set()
    for seed in range(5):
        session = GameSession(dag, person=ROBOT, seed=seed)
        _play_out(session, lambda s: min(s.moves(), key=lambda m: m.worst_remaining).number)
        costs.add(session.cost)
    assert costs == {value}


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    layers=st.integers(1, 6),
    picks=st.lists(st.integers(0, 10), min_size=30, max_size=30),
)
def test_robust_guarantee_holds_against_any_human(seed, layers, picks):
    dag = synthetic_dag(layers, 4, 3, seed=seed)
    sol = solve(dag)
    it = iter(picks * 10)
    session = _play_out(GameSession(dag, solution=sol), lambda s: next(it) % len(s.moves()) + 1)
    assert session.cost <= sol.minimax + 1e-9
    assert session.summary().held is True
    # The worst case never rises under the robust robot; it is W* at the start.
    worsts = [t.worst_before for t in session.history]
    assert worsts[0] == pytest.approx(sol.minimax)
    assert all(b <= a + 1e-9 for a, b in zip(worsts, worsts[1:], strict=False))
    assert np.isclose(session.cost, sum(t.move.cost for t in session.history if t.move))
