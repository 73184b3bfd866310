"""Alike operations at run time: a physical observation mapped onto the policy's canonical one.

The state graph is reduced by symmetry (:mod:`asp.graph.symmetry`): of a class of interchangeable
blocks of operations (the pins of a ring; a dowel with the roller it carries, around a
drive) it keeps one canonical order, so the policy knows only the canonical states. Any
transposition of two blocks of a class, position by position, is a symmetry of the game. A
person who places the fifth pin before the first does something equivalent; the runtime
follows her with a permutation ``pi`` of each class's blocks (physical block -> canonical
block), the identity at the start:

- an observed operation ``x`` (block ``b``, position ``p``) stands for the operation at
  ``p`` of a canonical block ``c`` in the same *pattern* as ``pi(b)`` (the same positions
  done, nothing of either running; ``pi(b)`` itself among them): the instruction's if it is
  one, else the first of them in class order the game can take (the class's next canonical
  operation). Swapping ``pi(b)`` and ``c`` is a symmetry that fixes the canonical state, so
  the physical state still maps onto it, and the whole block moves with it (the roller
  follows its dowel);
- ``pi`` changes only when an observation is taken, so the finish of an operation maps as
  its start did (a running operation's block is never swapped);
- advice names physical operations (``pi`` inverted), with every alike operation that is
  equally acceptable (the same position of every block in the same pattern).

:class:`AlikeMap` holds ``pi``; the advisor (``asmplan/advisor.py``) says which canonical
operations are done or running (the pattern) and which candidate the game takes.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence

Pattern = Callable[[str], object]
"""Canonical operation id -> a hashable summary of it in the current state (done or not, in
every state the runtime follows), or None while it runs (its block is then fixed)."""


class AlikeMap:
    """The permutation of interchangeable blocks between a cell and its policy.

    Parameters
    ----------
    classes : sequence of classes of blocks of operation ids
        ``plan.json``'s ``interchangeable``: each class a list of blocks, each block the
        operation ids in position order; blocks of a class have the same length and
        classes are disjoint.
    """

    def __init__(self, classes: Sequence[Sequence[Sequence[str]]] = ()):
        self.classes = tuple(tuple(tuple(str(o) for o in b) for b in cls) for cls in classes)
        self._where: dict[str, tuple[int, int, int]] = {}
        for k, cls in enumerate(self.classes):
            sizes = {len(b) for b in cls}
            if len(sizes) != 1:
                raise ValueError(f"interchangeable class {k}: blocks of different lengths")
            for b, block in enumerate(cls):
                for p, op in enumerate(block):
                    if op in self._where:
                        raise ValueError(f"interchangeable: operation {op} in two blocks")
                    self._where[op] = (k, b, p)
        self._perm = [list(range(len(cls))) for cls in self.classes]

    def __bool__(self) -> bool:
        return bool(self.classes)

    @property
    def permutation(self) -> tuple[tuple[int, ...], ...]:
        """Per class, the canonical block of each physical block."""
        return tuple(tuple(p) for p in self._perm)

    def canonical(self, op: str) -> str:
        """The canonical operation a physical operation stands for now."""
        if op not in self._where:
            return op
        k, b, p = self._where[op]
        return self.classes[k][self._perm[k][b]][p]

    def physical(self, op: str) -> str:
        """The physical operation a canonical operation stands for now."""
        if op not in self._where:
            return op
        k, c, p = self._where[op]
        return self.classes[k][self._perm[k].index(c)][p]

    def _block_pattern(self, k: int, c: int, pattern: Pattern):
        """The pattern of canonical block ``c`` of class ``k`` (None: something runs)."""
        out = tuple(pattern(op) for op in self.classes[k][c])
        return None if any(x is None for x in out) else out

    def _twins(self, k: int, c: int, pattern: Pattern) -> list[int]:
        """Canonical blocks of class ``k`` a symmetry fixing the state swaps with ``c``
        (``c`` first; only ``c`` while one of its operations runs)."""
        mine = self._block_pattern(k, c, pattern)
        if mine is None:
            return [c]
        others = (
            d
            for d in range(len(self.classes[k]))
            if d != c and self._block_pattern(k, d, pattern) == mine
        )
        return [c, *others]

    def alike(self, canonical_op: str, pattern: Pattern) -> list[str]:
        """The physical operations as good as ``canonical_op`` now (its own first)."""
        if canonical_op not in self._where:
            return [canonical_op]
        k, c, p = self._where[canonical_op]
        inverse = {v: b for b, v in enumerate(self._perm[k])}
        return [self.classes[k][inverse[d]][p] for d in self._twins(k, c, pattern)]

    def candidates(
        self, op: str, pattern: Pattern, prefer: Iterable[str] = ()
    ) -> list[tuple[str, tuple[tuple[int, ...], ...]]]:
        """The canonical operations physical ``op`` may stand for, each with the
        permutation that maps it so: those in ``prefer`` (the instructions) first, then the
        twins of its block in class order (the class's next canonical operation first).

        Every candidate is as good as another (a symmetry fixing the state swaps them), so
        the canonical line a cell follows does not depend on which alike part it picks."""
        if op not in self._where:
            return [(op, self.permutation)]
        k, b, p = self._where[op]
        c = self._perm[k][b]
        out = []
        for d in self._twins(k, c, pattern):
            perm = [list(x) for x in self._perm]
            if d != c:
                other = perm[k].index(d)
                perm[k][b], perm[k][other] = d, c
            out.append((self.classes[k][d][p], tuple(tuple(x) for x in perm)))
        wanted = set(prefer)
        return sorted(out, key=lambda item: (item[0] not in wanted, self._where[item[0]][1]))

    def adopt(self, permutation: Sequence[Sequence[int]]) -> None:
        """Take a permutation of :meth:`candidates` (the observation it maps was taken)."""
        self._perm = [list(p) for p in permutation]
