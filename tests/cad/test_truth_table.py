"""The precedence truth table of (p, S)."""

from __future__ import annotations

import numpy as np
import pytest

from cad import compute_relations, truth_table
from tests.cad import shapes


@pytest.fixture(scope="module")
def relations():
    return compute_relations(shapes.boxed_container())


@pytest.mark.parametrize(
    ("subset", "and_row", "result"),
    [
        ({"tray", "lid"}, [0, 0, 0, 0, 0, 0], False),
        ({"tray"}, [0, 0, 0, 0, 1, 0], True),
        ({"lid"}, [1, 1, 1, 1, 0, 1], True),
    ],
)
def test_and_row_and_result(relations, subset, and_row, result):
    table = truth_table(relations, "item", subset)
    assert table.part == "item"
    assert set(table.rows) == subset
    assert table.values.shape == (len(subset), 6)
    assert np.array_equal(table.and_row, np.array(and_row, dtype=bool))
    assert table.result is result


def test_renderings(relations):
    table = truth_table(relations, "item", ["tray", "lid"])
    text = table.to_text()
    assert "+x" in text and "AND" in text and "OR" in text
    assert table.to_csv().splitlines() == [
        "j,+x,-x,+y,-y,+z,-z",
        "tray,0,0,0,0,1,0",
        "lid,1,1,1,1,0,1",
        "AND,0,0,0,0,0,0",
        "OR,0,,,,,",
    ]
    markdown = table.to_markdown().splitlines()
    assert markdown[0] == "| TT(item, j) | +x | -x | +y | -y | +z | -z |"
    assert markdown[-1].startswith("| **OR** | 0 |")
    assert all(line.count("|") == 8 for line in markdown)
