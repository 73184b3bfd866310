"""The schedule stage on a graph whose alike operations are in a fixed order.

The state graph of the alternating game is reduced by symmetry (:mod:`asp.graph.symmetry`): of a
class of interchangeable blocks of operations (a pin; a dowel with its roller), the
``i``-th operations of the blocks are chained in block order at every position ``i``
(:attr:`asp.graph.state_keys.OperationModel.fixed`). The graph holds one state of every orbit:
the *sorted* state, whose blocks are done in block order by prefix length (longest first).
TCT and W* stay exact, but a schedule replayed through it as it is could never run two
alike operations at once (both orders must be transitions) and would keep the chain as a
precedence. This module undoes the order for the CP-SAT schedule (:mod:`asp.schedule`):

- **Relabelling.** Every done set ``D`` of the full graph whose blocks are done in block
  order (each block a prefix of its operations: its derived precedences, which every
  schedule keeps and the replay checks first) is
  mapped by a symmetry onto its sorted state: the ``k``-th block of a class to have done
  its operation ``p`` becomes the class's ``k``-th block there. So, per position, the
  count of done operations is all that matters: ``D`` is completable iff its sorted state
  is in the graph, and operation ``o`` at position ``p`` of a class follows ``D`` iff the
  position's next operation in the chain follows the sorted state. In the graph at most
  one operation of a position's chain has a transition out of a state (the next one), so
  the replay looks up the transition of ``o`` by its *label*, the first operation of its
  chain (:attr:`FixedOrder.label`, :class:`asp.graph.together.LiveSteps`).
- **Precedences** (:meth:`FixedOrder.implied`): the chain is no precedence; ``a`` precedes
  ``b`` in the full graph iff it precedes the first operation of ``b``'s chain in the
  reduced one and is no alike operation, or the whole chain of ``a`` (its last operation)
  precedes it, or ``a`` is before ``b`` in its block.
- **Symmetry breaking** (:meth:`FixedOrder.start_order`): the blocks of a class may be
  renamed in any schedule, so the first operations of the blocks start in block order
  (``start[a] <= start[b]``, not ``end[a] <= start[b]``).
- **Short cuts** (:meth:`FixedOrder.canonical`, :meth:`FixedOrder.actual`): a cut is found
  on the sorted done set and the graph's states, then stated again with counts per
  position: it holds for every state of an orbit (:class:`asp.schedule.cuts.PlacementCuts`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class FixedOrder:
    """The fixed order of alike operations of a reduced state graph (module docstring).

    Attributes
    ----------
    n_ops : int
    classes : tuple of classes of blocks of operation indices
        :attr:`asp.graph.state_keys.OperationModel.fixed`.
    chains : tuple of tuple of int
        Per class and position, the chain of the blocks' operations there, in block order.
    label : (n_ops,) int64
        The first operation of an operation's chain (itself for an operation in no chain).
    chain_of : (n_ops,) int64
        An operation's chain (index into ``chains``), -1 for none.
    before : tuple of int
        Per operation, the operations before it in its block (bitset).
    """

    n_ops: int
    classes: tuple[tuple[tuple[int, ...], ...], ...]
    chains: tuple[tuple[int, ...], ...]
    label: np.ndarray
    chain_of: np.ndarray
    before: tuple[int, ...]

    @classmethod
    def of(cls, n_ops: int, classes) -> FixedOrder | None:
        """The fixed order of ``classes`` (None when there is none)."""
        classes = tuple(tuple(tuple(int(o) for o in b) for b in c) for c in classes if len(c) > 1)
        if not classes:
            return None
        chains = tuple(tuple(block[p] for block in c) for c in classes for p in range(len(c[0])))
        label = np.arange(n_ops, dtype=np.int64)
        chain_of = np.full(n_ops, -1, dtype=np.int64)
        for k, chain in enumerate(chains):
            label[list(chain)] = chain[0]
            chain_of[list(chain)] = k
        before = [0] * n_ops
        for c in classes:
            for block in c:
                for p, o in enumerate(block):
                    before[o] = sum(1 << a for a in block[:p])
        return cls(n_ops, classes, chains, label, chain_of, tuple(before))

    @classmethod
    def of_graph(cls, graph) -> FixedOrder | None:
        """The fixed order of a state graph's model (None when it has none)."""
        model = graph.model
        return cls.of(model.n_ops, model.fixed)

    def chain_pairs(self) -> set[tuple[int, int]]:
        """The precedences ``(a, b)`` the chains add to the spec (consecutive in a chain)."""
        return {(a, b) for chain in self.chains for a, b in zip(chain, chain[1:], strict=False)}

    def waiting(self, o: int, placed) -> bool:
        """Whether an operation of ``o``'s chain before it is not in ``placed`` (alike, so a
        schedule built one operation at a time takes the first of them)."""
        k = int(self.chain_of[o])
        if k < 0:
            return False
        chain = self.chains[k]
        return any(a not in placed for a in chain[: chain.index(o)])

    def block_before(self, o: int) -> list[int]:
        """The operations before ``o`` in its block (each must end before it starts)."""
        return [a for a in range(self.n_ops) if self.before[o] >> a & 1]

    def start_order(self) -> tuple[tuple[int, int], ...]:
        """``(a, b)``: ``start[a] <= start[b]`` breaks the symmetry of the blocks (the first
        operations of consecutive blocks of a class)."""
        return tuple((a[0], b[0]) for c in self.classes for a, b in zip(c, c[1:], strict=False))

    def implied(self, reduced: list[int]) -> list[int]:
        """The full graph's implied predecessors (bitsets, per operation) from the reduced
        graph's (:func:`asp.schedule.assembly.implied_predecessors`; module docstring)."""
        alike = 0
        for chain in self.chains:
            alike |= sum(1 << o for o in chain)
        out = []
        for b in range(self.n_ops):
            mask = reduced[int(self.label[b])]
            full = mask & ~alike
            for chain in self.chains:
                if mask >> chain[-1] & 1:
                    full |= sum(1 << o for o in chain)
            out.append((full | self.before[b]) & ~(1 << b))
        return out

    def canonical(self, done, b: int) -> tuple[set[int], int]:
        """The sorted done set of ``done`` (per chain, its first ``count`` operations) and the
        operation ``b`` is there (the next one of its chain)."""
        out = {o for o in done if self.chain_of[o] < 0}
        count = [0] * len(self.chains)
        for o in done:
            if self.chain_of[o] >= 0:
                count[self.chain_of[o]] += 1
        for k, chain in enumerate(self.chains):
            out.update(chain[: count[k]])
        k = int(self.chain_of[b])
        return out, (b if k < 0 else self.chains[k][count[k]])

    def actual(self, ys, xs, done, b: int) -> tuple[list[int], list[int]]:
        """A cut ``(Y, X)`` found on the sorted done set (:meth:`canonical`) in terms of the
        operations of ``done`` and ``b``.

        On sorted states, containing ``chain[i]`` means at least ``i + 1`` of the chain
        done, and missing ``chain[i]`` at most ``i``: so ``X`` takes as many of ``done`` in
        the chain as the highest position it holds there, plus one, and ``Y`` as many of the
        chain's operations outside ``done + {b}`` as the chain has after its lowest position
        there (less one when ``b`` is in the chain). The cut then says the same of every
        state of an orbit: counts per position are all a symmetry keeps of a chain.
        """
        y_out = [o for o in ys if self.chain_of[o] < 0]
        x_out = [o for o in xs if self.chain_of[o] < 0]
        for chain in self.chains:
            rank = {o: i for i, o in enumerate(chain)}
            xr = [rank[o] for o in xs if o in rank]
            yr = [rank[o] for o in ys if o in rank]
            if xr:
                x_out += [o for o in chain if o in done][: max(xr) + 1]
            if yr:
                n_y = len(chain) - min(yr) - (1 if b in rank else 0)
                outside = [o for o in chain if o not in done and o != b]
                y_out += outside[len(outside) - n_y :] if n_y > 0 else []
        return sorted(y_out), sorted(x_out)
