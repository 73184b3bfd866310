"""Gymnasium environments: checkers, determinism, masks, rewards, the vectorised env."""

import warnings

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env
from hypothesis import given, settings
from hypothesis import strategies as st
from stable_baselines3.common.env_checker import check_env as sb3_check_env

from arl.envs import GameVecEnv, HumanEnv, RobotEnv, probability_table
from arl.moves import GameTables
from asp.game.dag import HUMAN, ROBOT, from_arrays
from asp.game.solve import solve
from asp.game.synth import synthetic_dag
from tests.arl.graphs import figure4, sided_time_dag

GRAPHS = {"figure4": figure4, "sided": sided_time_dag, "synth": lambda: synthetic_dag(4, 3, 3, 1)}


@pytest.mark.parametrize("graph", sorted(GRAPHS))
@pytest.mark.parametrize("cls", [RobotEnv, HumanEnv])
@pytest.mark.parametrize("obs", ["node", "features"])
def test_env_checkers_pass_without_warnings(graph, cls, obs):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        env = cls(GRAPHS[graph](), obs=obs)
        gym_check_env(env, skip_render_check=True)
        sb3_check_env(env, warn=True)
    assert [str(w.message) for w in caught] == []


def test_same_seed_same_episode():
    def rollout(seed):
        env = RobotEnv(synthetic_dag(6, 4, 3, seed=3))
        obs, _ = env.reset(seed=seed)
        trace, rng, done = [obs], np.random.default_rng(0), False
        while not done:
            action = rng.choice(np.flatnonzero(env.action_masks()))
            obs, reward, done, _, _ = env.step(action)
            trace += [obs, reward]
        return trace

    assert rollout(5) == rollout(5)


def test_robot_rewards_paper_figure4():
    dag = figure4()
    # Robot takes 1->2, the frozen human replies 2->6, robot 6->7, human 7->8, robot 8->9.
    human = np.full(dag.n_nodes, -1)
    human[dag.index_of(2)] = 3  # edge (2, 6)
    human[dag.index_of(7)] = 9  # edge (7, 8)
    env = RobotEnv(dag, opponent=human)
    obs, _ = env.reset(seed=0)
    assert obs == dag.index_of(1)
    obs, r, done, _, _ = env.step(0)
    assert (obs, r, done) == (dag.index_of(6), -1.0, False)
    obs, r, done, _, _ = env.step(0)
    assert (obs, r, done) == (dag.index_of(8), -1.0, False)
    obs, r, done, _, info = env.step(0)
    assert (obs, r, done) == (dag.index_of(9), -1.0 + dag.n_nodes, True)
    assert info["cost"] == 5.0 and info["episode"]["r"] == -3.0 + dag.n_nodes


def test_human_rewards_and_invalid_action_modulo():
    dag = figure4()
    robot = solve(dag).robot_policy  # the robust move 1->3 first
    env = HumanEnv(dag, opponent=robot)
    obs, _ = env.reset(seed=0)
    assert obs == dag.index_of(3)
    # Two moves at node 3: action 3 is invalid and maps to 3 % 2 = 1 (edge 3->5).
    obs, r, done, _, info = env.step(3)
    assert (obs, r, done) == (dag.index_of(9), 1.0, True)
    assert info["cost"] == 3.0
    with pytest.raises(ValueError, match="invalid action"):
        strict = HumanEnv(dag, opponent=robot, invalid="raise")
        strict.reset(seed=0)
        strict.step(3)


def test_time_costs_and_passes():
    dag = sided_time_dag()
    env = RobotEnv(dag, opponent=lambda node: dag.moves(node, HUMAN)[0])
    env.reset(seed=0)
    # Robot s->a (2.0); the human has no move at a and passes; robot a->c (3.0); human
    # c->e (0.5). The robot pays its own durations.
    obs, r, done, _, _ = env.step(0)
    assert (obs, r, done) == (dag.index_of("a"), -2.0, False)
    _, r, done, _, info = env.step(0)
    assert done and r == -3.0 + dag.n_nodes and info["cost"] == 5.5
    zero_sum = RobotEnv(dag, opponent=lambda node: dag.moves(node, HUMAN)[0], reward="zero_sum")
    zero_sum.reset(seed=0)
    _, r, _, _, _ = zero_sum.step(0)
    assert r == -2.0
    _, r, _, _, _ = zero_sum.step(0)
    assert r == -3.5  # its own 3.0 and the human's 0.5


def _random_graph(layers, nodes, actions, seed, sided):
    dag = synthetic_dag(layers, nodes, actions, seed=seed)
    if not sided:
        return dag
    sides = np.random.default_rng(seed).integers(0, 3, dag.n_edges).astype(np.int8)
    return from_arrays(dag.node_ids, dag.sources, dag.targets, dag.costs, sides)


@settings(max_examples=25, deadline=None)
@given(
    layers=st.integers(1, 5),
    nodes=st.integers(1, 4),
    actions=st.integers(1, 4),
    seed=st.integers(0, 10_000),
    sided=st.booleans(),
    walk=st.integers(0, 2**31),
)
def test_masks_never_allow_an_invalid_move(layers, nodes, actions, seed, sided, walk):
    dag = _random_graph(layers, nodes, actions, seed, sided)
    tables = GameTables.from_dag(dag)
    rng = np.random.default_rng(walk)
    for player, cls in ((ROBOT, RobotEnv), (HUMAN, HumanEnv)):
        if not tables.can_move_somewhere(player):
            continue
        env = cls(dag, explore_starts=0.3)
        vec = GameVecEnv(dag, "robot" if player == ROBOT else "human", 4, seed=walk)
        vec.reset()
        for _ in range(3):
            env.reset(seed=int(rng.integers(1000)))
            done = False
            while not done:
                node, mask = env.game.node, env.action_masks()
                allowed = set(dag.moves(node, player))
                assert mask.sum() == len(allowed) > 0
                assert {tables.moves[player, node, a] for a in np.flatnonzero(mask)} == allowed
                _, _, done, _, _ = env.step(rng.choice(np.flatnonzero(mask)))
            for _ in range(5):
                masks = vec.action_masks()
                for node, mask in zip(vec.node, masks, strict=True):
                    edges = {tables.moves[player, node, a] for a in np.flatnonzero(mask)}
                    assert edges == set(dag.moves(node, player)) and edges
                vec.step(np.array([rng.choice(np.flatnonzero(m)) for m in masks]))


def test_vec_env_matches_single_env_against_a_fixed_opponent():
    dag = synthetic_dag(6, 4, 3, seed=7)
    tables = GameTables.from_dag(dag)
    human = tables.to_edges(HUMAN, np.zeros(dag.n_nodes, dtype=np.int64))
    single = RobotEnv(dag, opponent=human)
    vec = GameVecEnv(dag, "robot", 1, seed=0)
    vec.set_opponent(human)
    obs_v = vec.reset()
    obs_s, _ = single.reset(seed=0)
    rng = np.random.default_rng(1)
    for _ in range(40):
        assert obs_s == obs_v[0]
        action = rng.integers(tables.max_moves)
        obs_s, r_s, done_s, _, info_s = single.step(action)
        obs_v, r_v, done_v, infos = vec.step(np.array([action]))
        assert (r_s, done_s) == (float(r_v[0]), bool(done_v[0]))
        if done_s:
            assert infos[0]["episode"]["r"] == info_s["episode"]["r"]
            obs_s, _ = single.reset()


def test_probability_table_masks_and_mixes():
    tables = GameTables.from_dag(figure4())
    probs = probability_table(tables, HUMAN, np.ones((tables.n, tables.max_moves)), 0.1)
    assert np.allclose(probs.sum(axis=1)[tables.n_moves[HUMAN] > 0], 1.0)
    assert np.all(probs[~tables.masks(HUMAN)] == 0.0)
