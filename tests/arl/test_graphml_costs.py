"""A GraphML with ``cost`` edges (a ``steps`` graph) trains and certifies on the same costs.

Issue 10: the learners once charged 1 per move on every ``steps`` graph while the solver
and the certification used the edge costs, so costs 1, 5, 1 became 1, 1, 1 for PPO.
"""

import networkx as nx
import numpy as np
import pytest
import torch

from arl import train
from arl.envs import RobotEnv
from arl.moves import GameTables
from asp.game.io import load_dag
from asp.game.solve import solve


def _graphml(tmp_path):
    """Two lines from s to e. Line A costs 1, 5, 1 (the 5 is the robot's own move: the human
    passes at x), 7 in all, in two robot moves; line B costs 1 six times, 6 in all, in three
    robot moves. Counting 1 per move the robot prefers A; counting costs, B (W* = 6)."""
    g = nx.DiGraph()
    g.add_edge("s", "x", cost=1, side="any")
    g.add_edge("x", "y", cost=5, side="robot")
    g.add_edge("y", "e", cost=1, side="any")
    line_b = ["s", "b1", "b2", "b3", "b4", "b5", "e"]
    for u, v in zip(line_b, line_b[1:], strict=False):
        g.add_edge(u, v, cost=1, side="any")
    path = tmp_path / "costs.graphml"
    nx.write_graphml(g, path)
    return load_dag(path)


def test_graphml_costs_are_the_move_costs(tmp_path):
    dag = _graphml(tmp_path)
    assert dag.cost_model == "steps"
    tables = GameTables.from_dag(dag)
    assert np.array_equal(tables.move_cost, dag.costs)
    line_a = [dag.index_of(x) for x in ("s", "x", "y")]
    assert [tables.move_cost[dag.out_edges(v)[0]] for v in line_a] == [1, 5, 1]
    # Playing line A in the robot's environment charges what the solver charges.
    env = RobotEnv(dag, reward="zero_sum")
    env.reset(seed=0)
    a_first = dag.moves(dag.start, 0).index(dag.out_edges(dag.start)[0])
    total, done, info = 0.0, False, {}
    action = a_first
    while not done:
        _, reward, done, _, info = env.step(action)
        total += reward
        action = 0
    assert info["cost"] == -total == 7.0
    assert solve(dag).minimax == 6.0


@pytest.mark.parametrize("seed", [0])
def test_graphml_costs_train_and_certify_alike(tmp_path, seed):
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        result = train(_graphml(tmp_path), "fast", seed=seed)
    finally:
        torch.set_num_threads(threads)
    assert result.minimax == 6.0
    assert result.certified_wcpl == result.wcpl == 6.0
    assert result.robust_optimal
