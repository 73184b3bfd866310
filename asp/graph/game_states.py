"""The states of the game DAG of a state graph, named (turn model ``alternate``).

:func:`alternate_states` maps each node of :func:`asp.graph.game_dag.game_dag`'s game back to
the state graph state it is, and :class:`AlternateStates` names its done operations and
tools (an :data:`asp.game.policy.StateDescriber`), one node or many at once.
"""

from __future__ import annotations

import numpy as np

from asp.game.dag import GameDAG

__all__ = ["AlternateStates", "alternate_states"]


def alternate_states(graph, dag: GameDAG) -> AlternateStates:
    """The structured state of each node of ``game_dag(graph)`` (turn model ``alternate``).

    Node ``i < n - 1`` is the ``i``-th state that can still be completed and is not
    complete (the numbering of :func:`asp.graph.game_dag.game_dag`); the last node is the complete
    assembly. No operation runs between turns, so ``running`` is always empty.
    """
    alive = graph.coreachable()
    complete = graph.complete
    ends = np.flatnonzero(alive & complete)
    alive &= ~complete  # the inner states
    del complete
    n_inner = int(np.count_nonzero(alive))
    if n_inner + 1 != dag.n_nodes:
        raise ValueError(
            f"state names: the game has {dag.n_nodes} nodes, the state graph "
            f"{n_inner + 1} (was the game built from this graph?)"
        )
    # Complete states come after every inner one (they are the last layer): the inner
    # states and the first complete one, in order, without a second copy of the array.
    alive[ends[:1]] = True
    state_of = np.flatnonzero(alive)
    if ends.size and state_of[-1] != ends[0]:  # pragma: no cover - another layout
        alive[ends[:1]] = False
        state_of = np.append(np.flatnonzero(alive), ends[:1])
    return AlternateStates(graph, state_of)


class AlternateStates:
    """A :data:`StateDescriber` of the nodes of an ``alternate`` game of a state graph, that
    also names the done operations of many nodes at once (:meth:`done_matrix`).

    Attributes
    ----------
    graph : asp.graph.state_graph.StateGraph
    state_of : (n,) int64
        The state graph state of each game node (of each of ``nodes``, when given).
    nodes : (k,) int64 or None
        The game nodes named, sorted (:meth:`only`); None: every node.
    """

    def __init__(self, graph, state_of: np.ndarray, nodes: np.ndarray | None = None):
        self.graph = graph
        self.state_of = state_of
        self.nodes = nodes

    def states(self, nodes) -> np.ndarray:
        """The state graph states of the game nodes ``nodes`` (an int or an index array)."""
        if self.nodes is None:
            return self.state_of[nodes]
        at = np.searchsorted(self.nodes, nodes)
        if not np.all(self.nodes[np.minimum(at, self.nodes.size - 1)] == nodes):
            raise KeyError(f"state names: game node(s) {nodes} not among those kept")
        return self.state_of[at]

    def only(self, nodes: np.ndarray) -> AlternateStates:
        """The same names for the game nodes ``nodes`` alone: a table of their size, not
        the game's."""
        nodes = np.unique(np.asarray(nodes, dtype=np.int64))
        return AlternateStates(self.graph, self.states(nodes), nodes)

    def __call__(self, v: int) -> dict:
        model = self.graph.model
        key = self.graph.keys[int(self.states(v))]
        return {"done": model.done_ops(key), "tools": model.tool_state(key), "running": []}

    @property
    def op_ids(self) -> tuple[str, ...]:
        """The operation ids, in the order of :meth:`done_matrix`'s columns."""
        return self.graph.spec.op_ids

    @property
    def has_tools(self) -> bool:
        return bool(self.graph.model.tool_names)

    def done_matrix(self, nodes: np.ndarray) -> np.ndarray:
        """(k, n_ops) bool: the operations done at each of the game nodes ``nodes``."""
        return self.graph.model.done_matrix(self.graph.keys[self.states(nodes)])
