"""Every consumer of the rules charges the same costs and reaches the same states.

The same seeded random games (random DAGs with sides any/robot/human, so passes happen, and
fractional costs; random fixed robot and human lines) are played through the exact solver
and evaluator, the random-human distribution and simulation, the play session, the readable
plan, the Gymnasium environments, the vectorised environment and the PettingZoo
environment, and compared with a reference written here from the edge sides directly.
"""

from __future__ import annotations

import numpy as np
import pytest

from arl.envs import GameVecEnv, HumanEnv, RobotEnv
from arl.moves import GameTables
from arl.pettingzoo_env import GameAEC
from asp.game.dag import HUMAN, ROBOT
from asp.game.metrics import probability_within, random_cost_distribution, simulate_random_human
from asp.game.plan import play_steps
from asp.game.play import GameSession
from asp.game.solve import evaluate_policy, play, solve
from tests.asp.random_games import random_game

SEEDS = range(16)


def _random_lines(dag, seed):
    """A random fixed move for each player at each node (-1 where it has none)."""
    rng = np.random.default_rng(1000 + seed)
    lines = np.full((2, dag.n_nodes), -1, dtype=np.int64)
    for v in range(dag.n_nodes):
        for p in (ROBOT, HUMAN):
            lo, hi = int(dag.indptr[v]), int(dag.indptr[v + 1])
            own = [e for e in range(lo, hi) if int(dag.sides[e]) in (2, p)]
            if own:
                lines[p, v] = own[int(rng.integers(len(own)))]
    return lines[ROBOT], lines[HUMAN]


def _reference(dag, robot, human):
    """States ``(node, player)`` before each turn (passes included), moves and total cost."""
    v, p, cost = dag.start, ROBOT, 0.0
    states, edges = [], []
    while v != dag.end:
        states.append((v, p))
        lo, hi = int(dag.indptr[v]), int(dag.indptr[v + 1])
        if any(int(dag.sides[e]) in (2, p) for e in range(lo, hi)):
            e = int((robot if p == ROBOT else human)[v])
            edges.append(e)
            cost += float(dag.costs[e])
            v = int(dag.targets[e])
        p = 1 - p
    return states, edges, cost


def _game(seed):
    dag = random_game(seed, n=10)
    robot, human = _random_lines(dag, seed)
    return dag, robot, human, _reference(dag, robot, human)


@pytest.mark.parametrize("seed", SEEDS)
def test_solver_evaluator_and_random_human_agree(seed):
    dag, robot, human, (states, edges, cost) = _game(seed)
    path, played = play(dag, robot, human)
    assert played == pytest.approx(cost, abs=1e-12)
    assert path == [dag.start] + [int(dag.targets[e]) for e in edges]
    ev = evaluate_policy(dag, robot)
    # The best response's line costs the certified worst case; any line lies in between.
    _, worst = play(dag, robot, ev.human_best_response)
    assert worst == pytest.approx(ev.worst[dag.start, ROBOT], abs=1e-9)
    assert ev.best[dag.start, ROBOT] - 1e-9 <= cost <= worst + 1e-9
    dist = random_cost_distribution(dag, robot)
    assert any(abs(c - cost) <= 1e-9 for c in dist)  # the line is a possible random game
    mean = sum(c * q for c, q in dist.items())
    assert mean == pytest.approx(ev.expected[dag.start, ROBOT], abs=1e-9)
    assert max(dist) == pytest.approx(worst) and min(dist) == pytest.approx(ev.best[0, ROBOT])
    within = sum(q for c, q in dist.items() if c <= cost + 1e-9)
    assert probability_within(dag, robot, cost) == pytest.approx(within, abs=1e-12)
    sampled = simulate_random_human(dag, robot, n_games=200, seed=seed)
    assert all(any(abs(s - c) <= 1e-9 for c in dist) for s in np.unique(sampled))
    sol = solve(dag)
    assert sol.value[dag.start, ROBOT] <= worst + 1e-9
    assert sol.coop[dag.start, ROBOT] <= cost + 1e-9


@pytest.mark.parametrize("seed", SEEDS)
def test_play_session_and_plan_agree(seed):
    dag, robot, human, (states, edges, cost) = _game(seed)
    session = GameSession(dag, robot=robot)
    seen = []
    while not session.finished:
        seen.append((session.node, session.player))
        if session.persons_turn:
            e = int(human[session.node])
            session.play(next(m.number for m in session.moves() if m.edge == e))
        else:
            session.step()
    assert seen == states
    assert [t.move.edge for t in session.history if t.move is not None] == edges
    assert session.cost == pytest.approx(cost, abs=1e-12)
    steps = play_steps(dag, robot, human)
    assert [(dag.index_of(s.node), 0 if s.player == "robot" else 1) for s in steps] == states
    assert sum(s.cost for s in steps) == pytest.approx(cost, abs=1e-12)


def _own_moves(states, player):
    return [v for v, p in states if p == player]


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("learner", [ROBOT, HUMAN])
def test_gymnasium_envs_agree(seed, learner):
    dag, robot, human, (states, edges, cost) = _game(seed)
    tables = GameTables.from_dag(dag)
    mine = [v for v, p in states if p == learner and tables.can_move[p, v]]
    if not mine:
        pytest.skip("the learner never moves on this line (the env restarts elsewhere)")
    line = robot if learner == ROBOT else human
    actions = tables.to_actions(learner, line)
    # The episode's rewards start at the learner's first move (earlier ones happen in reset).
    movers = [(v, p) for v, p in states if tables.can_move[p, v]]
    first = next(k for k, (_, p) in enumerate(movers) if p == learner)
    charged = sum(float(dag.costs[e]) for e in edges[first:])
    cls = RobotEnv if learner == ROBOT else HumanEnv
    env = cls(dag, opponent=human if learner == ROBOT else robot, reward="zero_sum")
    obs, info = env.reset(seed=seed)
    visited, total, done = [], 0.0, False
    while not done:
        visited.append(int(obs))
        obs, reward, done, _, info = env.step(int(actions[int(obs)]))
        total += reward
    assert visited == mine
    assert info["cost"] == pytest.approx(cost, abs=1e-12)
    sign = -1.0 if learner == ROBOT else 1.0
    assert sign * total == pytest.approx(charged, abs=1e-12)

    vec = GameVecEnv(dag, "robot" if learner == ROBOT else "human", 1, reward="zero_sum", seed=0)
    vec.set_opponent(human if learner == ROBOT else robot)
    nodes = vec.reset()
    visited, total = [], 0.0
    for _ in range(2 * dag.n_nodes):
        visited.append(int(nodes[0]))
        nodes, rewards, dones, infos = vec.step(np.array([actions[int(nodes[0])]]))
        total += float(rewards[0])
        if dones[0]:
            break
    assert dones[0] and "episode" in infos[0]
    assert visited == mine
    assert sign * total == pytest.approx(charged, rel=1e-6)  # float32 rewards


@pytest.mark.parametrize("seed", SEEDS)
def test_pettingzoo_env_agrees(seed):
    dag, robot, human, (states, edges, cost) = _game(seed)
    tables = GameTables.from_dag(dag)
    actions = {"robot": tables.to_actions(ROBOT, robot), "human": tables.to_actions(HUMAN, human)}
    env = GameAEC(dag, reward="zero_sum")
    env.reset(seed=seed)
    visited, returns = [], {"robot": 0.0, "human": 0.0}
    while not all(env.terminations.values()):
        agent = env.agent_selection
        node = env.game.node
        visited.append((node, 0 if agent == "robot" else 1))
        env.step(int(actions[agent][node]))
        for a in returns:
            returns[a] += env.rewards[a]
    movers = [(v, p) for v, p in states if tables.can_move[p, v]]
    assert visited == movers
    assert env.game.cost == pytest.approx(cost, abs=1e-12)
    assert -returns["robot"] == pytest.approx(cost) and returns["human"] == pytest.approx(cost)


@pytest.mark.parametrize("seed", range(4))
def test_cp_sat_path_agrees_with_the_solver(seed):
    from asp.schedule.path import min_cost_path

    dag = random_game(seed, n=10)
    result = min_cost_path(dag, time_limit=10.0)
    assert result.status == "OPTIMAL"
    assert result.objective == pytest.approx(solve(dag).tct, abs=1e-6)
    # The path it reports is a line of the game: replay it by the reference's turn rules.
    v, p, cost = dag.start, ROBOT, 0.0
    for e in result.detail["edges"]:
        while int(dag.sides[e]) not in (2, p):  # p has no move here: it passes
            lo, hi = int(dag.indptr[v]), int(dag.indptr[v + 1])
            assert not any(int(dag.sides[f]) in (2, p) for f in range(lo, hi))
            p = 1 - p
        assert dag.out_edges(v).start <= e < dag.out_edges(v).stop
        v, p, cost = int(dag.targets[e]), 1 - p, cost + float(dag.costs[e])
    assert v == dag.end and cost == pytest.approx(result.objective, abs=1e-6)
