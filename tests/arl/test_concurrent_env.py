"""The concurrent game's Gymnasium environments, played on the fly from the rules."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env
from hypothesis import HealthCheck, given, settings
from stable_baselines3.common.env_checker import check_env as sb3_check_env

from arl.concurrent_env import (
    ConcurrentHumanEnv,
    ConcurrentRobotEnv,
    Encoder,
    Turn,
    robot_choose,
)
from asp.concurrent.certify import certify
from asp.concurrent.rules import commit_rows, concurrent_rules, reply_rows
from asp.concurrent.search import Search
from tests.asp.concurrent.test_rules import job, random_jobs

SETTINGS = settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])

TWO_PEOPLE = [
    {"id": "a", "agents": {"H1": [2, 4], "R1": 3}, "after": []},
    {"id": "b", "agents": {"H1": 2, "H2": [1, 3], "R1": 1}, "after": []},
    {"id": "c", "agents": {"H2": 2, "R1": 2}, "after": ["a"]},
    {"id": "d", "agents": {"H1": 1, "R1": 2}, "after": ["b", "c"]},
]
AGENTS = {"H1": {"side": "human"}, "H2": {"side": "human"}, "R1": {"side": "robot"}}


def small_rules():
    spec, graph = job(TWO_PEOPLE, agents=AGENTS)
    return concurrent_rules(spec, graph)


@pytest.mark.parametrize("cls", [ConcurrentRobotEnv, ConcurrentHumanEnv])
@pytest.mark.parametrize("budgets", [[0], [0, 1, None]])
def test_gymnasium_and_sb3_check_env_pass(cls, budgets):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        env = cls(small_rules(), budgets=budgets)
        gym_check_env(env, skip_render_check=True)
        sb3_check_env(env, warn=True)
    assert [str(w.message) for w in caught] == []


def sequences(turn_codes: np.ndarray) -> list[int]:
    """The joint move reached by every sequence of allowed actions."""
    out = []

    def walk(turn: Turn, path: list[int]) -> None:
        if turn.done:
            out.append(turn.index)
            return
        for a in turn.allowed():
            t = Turn(turn_codes)
            for b in [*path, int(a)]:
                t.choose(b)
            walk(t, [*path, int(a)])

    walk(Turn(turn_codes), [])
    return out


@SETTINGS
@given(random_jobs(humans=(1, 2), ranges=True))
def test_worker_by_worker_actions_reach_each_joint_move_once(data):
    ops, agents = data
    spec, graph = job(ops, agents=agents)
    rules = concurrent_rules(spec, graph)
    enc = Encoder(rules)
    rng = np.random.default_rng(0)
    for budget in (0, None):
        row = rules.start(budget).row()
        while row[0] >= 0:
            commits = commit_rows(rules.tables, row)
            assert sorted(sequences(enc.robot_codes(commits))) == list(range(len(commits)))
            commit = commits[rng.integers(len(commits))]
            r_ops, durs, _, _, rows = reply_rows(rules.tables, row, commit)
            codes = enc.human_codes(r_ops, durs)
            assert sorted(sequences(codes)) == list(range(len(rows)))
            row = rows[rng.integers(len(rows))]


def play(env, seed: int) -> tuple[list, float, float]:
    obs, _ = env.reset(seed=seed)
    trace, total, done, info = [obs], 0.0, False, {}
    rng = np.random.default_rng(seed)
    while not done:
        action = rng.choice(np.flatnonzero(env.action_masks()))
        obs, reward, done, _, info = env.step(action)
        trace.append(obs)
        total += reward
    return trace, total, info["makespan"]


@pytest.mark.parametrize("cls", [ConcurrentRobotEnv, ConcurrentHumanEnv])
def test_same_seed_same_episode_and_rewards_sum_to_the_makespan(cls):
    rules = small_rules()
    env = cls(rules, budgets=[0, 1, None])
    a, total, makespan = play(env, 3)
    b, _, _ = play(env, 3)
    assert all((x == y).all() for x, y in zip(a, b, strict=True))
    sign = -1 if cls is ConcurrentRobotEnv else 1
    assert sign * total * env.enc.horizon / rules.scale == pytest.approx(makespan)


def test_random_games_lie_between_the_value_and_the_robots_certified_worst_case():
    rules = small_rules()
    env = ConcurrentRobotEnv(rules, budgets=[None])
    # The robot env's learner replaced by a fixed policy: a seeded random choice per turn.
    choose = robot_choose(rules, None, seed=4)
    cert = certify(rules, choose, [0, None])
    w_inf = Search(rules).value(None) / rules.scale
    assert cert.worst[None] >= w_inf
    makespans = [play(env, s)[2] for s in range(10)]
    assert min(makespans) >= Search(rules).value(0) / rules.scale


def test_robot_choose_with_a_callable_takes_the_masked_action():
    rules = small_rules()
    first = robot_choose(rules, lambda obs, mask: int(np.flatnonzero(mask)[0]))
    last = robot_choose(rules, lambda obs, mask: int(np.flatnonzero(mask)[-1]))
    pos = rules.start(0)
    commits = rules.commits(pos)
    assert 0 <= first(pos, commits) < len(commits)
    assert first(pos, commits) != last(pos, commits) or len(commits) == 1


def test_bad_side_is_an_error():
    with pytest.raises(ValueError, match="side"):
        from arl.concurrent_env import ConcurrentEnv

        ConcurrentEnv(small_rules(), "cat")


def test_a_models_greedy_action_is_its_predict():
    from sb3_contrib import MaskablePPO

    from arl.concurrent_env import act

    rules = small_rules()
    env = ConcurrentHumanEnv(rules, budgets=[0, 1, None])
    model = MaskablePPO("MlpPolicy", env, seed=0, device="cpu", n_steps=32, batch_size=32)
    model.learn(32)  # a network that is not at its initial weights
    rng = np.random.default_rng(0)
    for seed in range(5):
        obs, _ = env.reset(seed=seed)
        done = False
        while not done:
            mask = env.action_masks()
            want, _ = model.predict(obs, action_masks=mask, deterministic=True)
            assert act(model, obs, mask, rng, True) == int(want)
            sampled = act(model, obs, mask, rng, False)
            assert mask[sampled]
            obs, _, done, _, _ = env.step(sampled)


FIXED_TIMES = [
    {"id": "a", "agents": {"H1": 2, "R1": 3}, "after": []},
    {"id": "b", "agents": {"H1": 2, "R1": 1}, "after": []},
    {"id": "c", "agents": {"H1": 1, "R1": 2}, "after": ["a", "b"]},
]


def test_a_budget_where_the_learner_never_decides_is_drawn_again():
    """Fixed durations, no deviation left: the person only follows the instructions, so at
    k = 0 the human side never decides. Training at budgets 0 and 1 still finds games
    (each restart draws its budget); at 0 alone the error says why, in one line."""
    spec, graph = job(FIXED_TIMES, agents={"H1": {"side": "human"}, "R1": {"side": "robot"}})
    rules = concurrent_rules(spec, graph)
    with pytest.raises(ValueError, match="the human side has no decision in 100 games"):
        ConcurrentHumanEnv(rules, budgets=[0]).reset(seed=0)
    env = ConcurrentHumanEnv(rules, budgets=[0, 1])
    for seed in range(5):  # some of these draw budget 0 first (fails on the old code)
        obs, _ = env.reset(seed=seed)
        assert env.action_masks().any() and obs.shape == env.observation_space.shape
