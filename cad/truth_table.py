"""The precedence truth table of the paper for a part p and a subassembly S."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from cad.directions import DIRECTIONS
from cad.relations import Relations, _indices


@dataclass(frozen=True, eq=False)
class TruthTable:
    """``TT_d(p, j)`` for each j in S (rows) and direction d (columns), AND row, OR result.

    Attributes
    ----------
    part : str
        The part p to insert.
    rows : tuple[str, ...]
        Ids of the parts j in S, in table order.
    values : np.ndarray
        Bool, shape ``(len(rows), 6)``: ``values[r, d] = TT_d(p, rows[r])``.
    and_row : np.ndarray
        Bool, shape ``(6,)``: ``TT_d(p, S)`` (eq. 4).
    result : bool
        ``RTT(p, S)`` (eq. 5), the OR of ``and_row``.
    """

    part: str
    rows: tuple[str, ...]
    values: np.ndarray
    and_row: np.ndarray
    result: bool
    directions: tuple[str, ...] = DIRECTIONS

    def _grid(self, yes: str = "1", no: str = "0") -> list[list[str]]:
        header = [f"TT({self.part}, j)", *self.directions]
        body = [
            [j, *(yes if v else no for v in row)]
            for j, row in zip(self.rows, self.values, strict=True)
        ]
        and_row = ["AND", *(yes if v else no for v in self.and_row)]
        result = ["OR", yes if self.result else no, *([""] * (len(self.directions) - 1))]
        return [header, *body, and_row, result]

    def to_text(self) -> str:
        """Aligned plain-text table."""
        grid = self._grid()
        widths = [max(len(row[c]) for row in grid) for c in range(len(grid[0]))]
        lines = [
            "  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)).rstrip()
            for row in grid
        ]
        lines.insert(1, "  ".join("-" * w for w in widths))
        lines.insert(len(lines) - 2, "  ".join("-" * w for w in widths))
        return "\n".join(lines) + "\n"

    def to_markdown(self) -> str:
        """GitHub-flavoured Markdown table."""
        grid = self._grid()
        lines = ["| " + " | ".join(grid[0]) + " |", "|" + "---|" * len(grid[0])]
        for row in grid[1:-2]:
            lines.append("| " + " | ".join(row) + " |")
        lines.append("| **" + grid[-2][0] + "** | " + " | ".join(grid[-2][1:]) + " |")
        lines.append(f"| **OR** | {grid[-1][1]} |" + " |" * (len(grid[0]) - 2))
        return "\n".join(lines) + "\n"

    def to_csv(self) -> str:
        """CSV: header ``j,+x,...,-z``, a row per j, then ``AND`` and ``OR`` rows."""
        grid = self._grid()
        grid[0][0] = "j"
        return "\n".join(",".join(row) for row in grid) + "\n"


def truth_table(relations: Relations, p: str | int, S: Iterable[str | int]) -> TruthTable:
    """The truth table of ``TT_d(p, j)`` for ``j`` in ``S`` (rows in table order)."""
    ip, members = _indices(relations, p, S)
    values = relations.tt[ip, members, :].copy()
    and_row = values.all(axis=0)
    return TruthTable(
        part=relations.parts[ip],
        rows=tuple(relations.parts[j] for j in members),
        values=values,
        and_row=and_row,
        result=bool(and_row.any()),
    )
