"""The PettingZoo AEC environment: API test and reward attribution."""

import warnings

import numpy as np
from pettingzoo.test import api_test

from arl.pettingzoo_env import GameAEC
from asp.game.synth import synthetic_dag
from tests.arl.graphs import figure4, sided_time_dag


def test_api_test_passes():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # advisory naming/observation-type hints
        api_test(GameAEC(figure4()), num_cycles=50)
        api_test(GameAEC(sided_time_dag()), num_cycles=50)
        api_test(GameAEC(synthetic_dag(5, 4, 3, seed=2), obs="features"), num_cycles=50)


def test_reward_goes_to_the_agent_that_moved():
    dag = figure4()
    env = GameAEC(dag)
    env.reset()
    assert env.agent_selection == "robot"
    env.step(0)  # robot 1->2
    assert env.rewards == {"robot": -1.0, "human": 0.0}
    # The human is on turn: what it sees is its own (zero) reward, not the robot's move.
    _, reward, terminated, _, _ = env.last()
    assert env.agent_selection == "human" and reward == 0.0 and not terminated
    env.step(1)  # human 2->6
    assert env.rewards == {"robot": 0.0, "human": 1.0}
    _, reward, _, _, _ = env.last()
    assert env.agent_selection == "robot" and reward == -1.0  # its own move, not the human's
    env.step(0)  # robot 6->7
    env.step(0)  # human 7->8
    env.step(0)  # robot 8->9: the end, the bonus goes to the robot
    assert env.rewards == {"robot": -1.0 + dag.n_nodes, "human": 0.0}
    assert all(env.terminations.values())


def test_passes_are_skipped_and_masks_follow_the_turn():
    dag = sided_time_dag()
    env = GameAEC(dag)
    env.reset()
    totals = {"robot": 0.0, "human": 0.0}
    for agent in env.agent_iter():
        obs, _, terminated, truncated, _ = env.last()
        if terminated or truncated:
            env.step(None)
            continue
        mask = obs["action_mask"]
        assert mask.any()
        other = "human" if agent == "robot" else "robot"
        assert not env.observe(other)["action_mask"].any()
        env.step(int(np.flatnonzero(mask)[0]))
        for a in totals:
            totals[a] += env.rewards[a]
    # Robot s->a (2.0), the human passes at a, robot a->c (3.0), human c->e (0.5).
    assert totals == {"robot": -5.0 + dag.n_nodes, "human": 0.5}
