"""The two-player game as a PettingZoo AEC environment (agents ``robot`` and ``human``).

Each agent observes ``{"observation": node obs, "action_mask": int8 (max_moves,)}``; the
mask is all zeros for the agent not on turn. Passes are automatic: ``agent_selection`` is
always an agent that has a move (the robot first, as in the game), until the end node
terminates both agents.

Reward attribution: the reward of a step belongs to the agent that moved, not to the agent
whose turn comes next (the known trap of turn-based AEC code). With ``reward="paper"`` a
robot move gives ``rewards == {"robot": -cost, "human": 0}``, a human move
``{"robot": 0, "human": +cost}``, and reaching the end adds ``+n`` to the robot whoever moved.
With ``reward="zero_sum"`` every move gives ``{"robot": -cost, "human": +cost}``.
"""

from __future__ import annotations

import numpy as np
from gymnasium import spaces
from pettingzoo import AECEnv

from arl.envs import Observer
from arl.moves import AGENTS, REWARDS, Game, GameTables, check_choice, move_rewards
from asp.game.dag import GameDAG


class GameAEC(AECEnv):
    """Alternate-turn AEC environment of the robot-vs-human game on ``dag``.

    Parameters
    ----------
    dag : GameDAG
    obs : "node" or "features"
    features : (n, d) array, optional
    reward : "paper" or "zero_sum"
    render_mode : "ansi" or None
    """

    metadata = {"render_modes": ["ansi"], "name": "asmplan_game_v0", "is_parallelizable": False}

    def __init__(
        self,
        dag: GameDAG,
        *,
        obs: str = "node",
        features: np.ndarray | None = None,
        reward: str = "paper",
        render_mode: str | None = None,
    ) -> None:
        super().__init__()
        self.tables = GameTables.from_dag(dag)
        self.reward_kind = check_choice("reward", reward, REWARDS)
        self.observer = Observer(dag, obs, features)
        self.render_mode = render_mode
        self.possible_agents = list(AGENTS)
        k = self.tables.max_moves
        self.observation_spaces = {
            a: spaces.Dict(
                {
                    "observation": self.observer.space,
                    "action_mask": spaces.Box(0, 1, shape=(k,), dtype=np.int8),
                }
            )
            for a in self.possible_agents
        }
        self.action_spaces = {a: spaces.Discrete(k) for a in self.possible_agents}
        self.game = Game(self.tables)

    def observation_space(self, agent: str) -> spaces.Space:
        return self.observation_spaces[agent]

    def action_space(self, agent: str) -> spaces.Space:
        return self.action_spaces[agent]

    def observe(self, agent: str) -> dict:
        mask = np.zeros(self.tables.max_moves, dtype=np.int8)
        if not self.game.done and AGENTS[self.game.player] == agent:
            mask[: self.tables.n_moves[self.game.player, self.game.node]] = 1
        return {"observation": np.asarray(self.observer(self.game.node)), "action_mask": mask}

    def reset(self, seed: int | None = None, options: dict | None = None) -> None:
        # The game has no randomness; ``seed`` is accepted for the API.
        self.agents = list(self.possible_agents)
        self.game.reset()
        self.rewards = {a: 0.0 for a in self.agents}
        self._cumulative_rewards = {a: 0.0 for a in self.agents}
        self.terminations = {a: False for a in self.agents}
        self.truncations = {a: False for a in self.agents}
        self.infos = {a: {} for a in self.agents}
        self.agent_selection = AGENTS[self.game.player]

    def step(self, action) -> None:
        agent = self.agent_selection
        if self.terminations[agent] or self.truncations[agent]:
            self._was_dead_step(action)
            return
        mover = self.game.player
        self._cumulative_rewards[agent] = 0.0
        _, cost = self.game.play(int(action))
        robot_r, human_r = move_rewards(mover, cost, self.reward_kind)
        # The rewards of this step are the mover's move (and the end bonus), never the
        # next agent's.
        self.rewards = {"robot": robot_r, "human": human_r}
        if self.game.done:
            bonus = self.tables.end_bonus(self.reward_kind)
            self.rewards = {"robot": robot_r + bonus[0], "human": human_r + bonus[1]}
            self.terminations = {a: True for a in self.agents}
        for a in self.agents:
            self.infos[a] = {"node": int(self.game.node), "cost": float(self.game.cost)}
        # After a pass the same agent moves again; at the end the selection stays put.
        self.agent_selection = AGENTS[self.game.player]
        self._accumulate_rewards()

    def render(self) -> str | None:
        if self.render_mode != "ansi":
            return None
        node_id = self.tables.dag.node_ids[self.game.node]
        turn = "game over" if self.game.done else f"{AGENTS[self.game.player]} on turn"
        return f"node {node_id!r}, {turn}, cost {self.game.cost:g}"

    def close(self) -> None:
        pass


def env(dag: GameDAG, **kwargs) -> GameAEC:
    """PettingZoo-style constructor of :class:`GameAEC`."""
    return GameAEC(dag, **kwargs)
