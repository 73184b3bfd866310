"""Synthetic assembly DAGs (paper, section 3.2; ``../shared/DESIGN.md``, "Synthetic DAGs").

The generator draws ``layers`` inner layers of 1..``max_nodes`` candidate nodes, then for
every node 1..``max_actions`` out-edges to later layers: early nodes draw more actions,
targets prefer the next layer. Only the nodes reachable from the start are kept, so every
node but the start has an in-edge; every node but the end has an out-edge because edges
only go forward and the last inner layer feeds the end (no skip lands on the end, so TCT is
at least 2). Ids are renumbered layer by layer:
node 0 is the start, the last node the end.

All randomness comes from one ``numpy.random.Generator(PCG64(seed))``, so the same
parameters give the same graph on every machine.
"""

from __future__ import annotations

import numpy as np

from asp.errors import GraphError
from asp.game.dag import GameDAG, from_arrays

NEXT_LAYER_PROBABILITY = 0.9
"""Chance that an edge goes to the adjacent layer rather than a later one."""
P_MORE_START = 0.95
P_MORE_DROP = 0.4
"""A node in layer l draws ``1 + Binomial(A - 1, P_MORE_START - P_MORE_DROP * l / (L + 1))``
actions: early nodes offer more alternatives. Tuned so that the sizes and path lengths come
close to the paper's (see the README)."""


def synthetic_dag(layers: int, max_nodes: int, max_actions: int, seed: int = 0) -> GameDAG:
    """Generate a layered random game DAG.

    Parameters
    ----------
    layers : int
        Number of inner layers L (>= 1). The start is layer 0, the end layer L + 1.
    max_nodes : int
        Maximum candidate nodes per inner layer M (>= 1).
    max_actions : int
        Maximum out-edges per node A (>= 1).
    seed : int
        Seed of the generator.

    Returns
    -------
    GameDAG
        All edges open to either player, cost 1; ``metadata`` holds the parameters and the
        layer of every node (``layer_of``).
    """
    for name, value in (("layers", layers), ("max_nodes", max_nodes), ("max_actions", max_actions)):
        if int(value) != value or value < 1:
            raise GraphError(f"{name}: expected a positive integer, got {value!r}")
    if int(seed) != seed or seed < 0:
        raise GraphError(f"seed: expected a non-negative integer, got {seed!r}")
    rng = np.random.Generator(np.random.PCG64(int(seed)))

    # Candidate nodes per layer: 1 start, 1..M per inner layer, 1 end.
    sizes = np.concatenate([[1], rng.integers(1, max_nodes + 1, size=layers), [1]])
    first = np.concatenate([[0], np.cumsum(sizes)])  # first candidate id of each layer
    layer_of = np.repeat(np.arange(layers + 2), sizes)
    n_candidates = int(first[-1])

    src_list: list[int] = []
    dst_list: list[int] = []
    for u in range(n_candidates - 1):
        layer = int(layer_of[u])
        # Early nodes are more likely to offer many actions.
        p_more = P_MORE_START - P_MORE_DROP * layer / (layers + 1)
        k = 1 + rng.binomial(max_actions - 1, p_more)
        chosen: list[int] = []
        for _ in range(k):
            # Skips land on a later inner layer; only the last inner layer feeds the end.
            if layer + 2 > layers or rng.random() < NEXT_LAYER_PROBABILITY:
                target_layer = layer + 1
            else:
                target_layer = int(rng.integers(layer + 2, layers + 1))
            v = int(first[target_layer] + rng.integers(sizes[target_layer]))
            if v not in chosen:
                chosen.append(v)
        chosen.sort()
        src_list.extend([u] * len(chosen))
        dst_list.extend(chosen)
    src = np.asarray(src_list, dtype=np.int64)
    dst = np.asarray(dst_list, dtype=np.int64)

    # Keep what the start reaches (candidate ids are already in topological order).
    alive = np.zeros(n_candidates, dtype=bool)
    alive[0] = True
    for u in range(n_candidates):
        if alive[u]:
            alive[dst[src == u]] = True
    keep = alive[src]
    new_id = np.cumsum(alive) - 1
    src, dst = new_id[src[keep]], new_id[dst[keep]]
    n = int(alive.sum())
    return from_arrays(
        list(range(n)),
        src,
        dst,
        start=0,
        end=n - 1,
        metadata={
            "generator": "asmplan.synth/1",
            "layers": int(layers),
            "max_nodes": int(max_nodes),
            "max_actions": int(max_actions),
            "seed": int(seed),
            "layer_of": layer_of[alive].tolist(),
        },
    )
