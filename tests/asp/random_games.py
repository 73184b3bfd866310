"""Seeded random game DAGs for consistency tests: sides any/robot/human, passes, fractional
costs."""

import numpy as np

from asp.game.dag import ANY, HUMAN, ROBOT, GameDAG, from_arrays

FRACTIONAL_COSTS = (0.1, 0.2, 0.5, 1.0, 1.25, 2.5, 3.0)


def random_game(seed: int, n: int = 9, *, fractional: bool = True, sided: bool = True) -> GameDAG:
    """A random game DAG on ``n`` nodes (0 the start, ``n - 1`` the end).

    Every node but the end has 1..3 out-edges to later nodes, every node but the start an
    in-edge. Sides are drawn from any/robot/human (so some players pass), costs from
    :data:`FRACTIONAL_COSTS` or 1.
    """
    rng = np.random.default_rng(seed)
    src, dst = [], []
    for v in range(n - 1):
        later = np.arange(v + 1, n)
        k = min(int(rng.integers(1, 4)), later.size)
        for t in rng.choice(later, size=k, replace=False):
            src.append(v)
            dst.append(int(t))
    heads = set(dst)
    for v in range(1, n):
        if v not in heads:
            src.append(int(rng.integers(0, v)))
            dst.append(v)
    m = len(src)
    costs = rng.choice(FRACTIONAL_COSTS, size=m) if fractional else np.ones(m)
    sides = (
        rng.choice([ANY, ROBOT, HUMAN], size=m, p=[0.5, 0.25, 0.25]).astype(np.int8)
        if sided
        else np.full(m, ANY, np.int8)
    )
    return from_arrays(list(range(n)), src, dst, costs, sides, start=0, end=n - 1)
