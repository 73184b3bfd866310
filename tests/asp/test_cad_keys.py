"""``flex:``: a snap fit's locking pair named first, and planned once the part flexes."""

from __future__ import annotations

import numpy as np
import pytest

from asp.cad_keys import parse_flex, with_flex
from asp.graph.state_graph import build_state_graph
from asp.spec import spec_from_dict
from cad.freedom import locking_pairs
from tests.asp.graph.test_explain import tower
from tests.asp.helpers_assembly import LATERAL


def snap_fit():
    """A tower of three whose top part P2 and P1 block each other along every direction
    (P2 a housing that snaps over P1)."""
    everywhere = ("+z", "-z", *LATERAL)
    blocks = [("P2", "P1", d) for d in everywhere] + [("P1", "P2", d) for d in everywhere]
    return tower(3, extra_blocks=blocks)


def spec(parts, **more):
    data = {
        "parts": [{"id": p, "file": f"{p}.stl"} for p in parts],
        "agents": {"R": {"side": "robot"}},
        "base_part": parts[0],
        "operations": [{"id": f"op{p}", "agents": {"R": 1}, "part": p} for p in parts[1:]],
        **more,
    }
    return spec_from_dict(data, source="spool.yaml")


def test_the_locking_pair_is_named_first_with_the_line_that_fixes_it():
    parts, rel = snap_fit()
    assert locking_pairs(rel.tt, rel.parts) == [("P1", "P2")]
    with pytest.raises(ValueError) as info:
        build_state_graph(spec(parts), rel)
    text = str(info.value)
    assert text.startswith(
        "spool.yaml: infeasible assembly, no complete sequence: P1 and P2 block each other "
        "along every direction"
    )
    assert "`flex: [P2]` lets it in after P1" in text


def test_a_flexing_part_is_inserted_after_the_part_it_locks_with():
    parts, rel = snap_fit()
    flexed = with_flex(rel, ("P2",))
    ids = list(rel.parts)
    assert flexed.tt[ids.index("P2"), ids.index("P1")].all()
    assert not flexed.tt[ids.index("P1"), ids.index("P2")].any()  # P1 still goes first
    assert np.array_equal(
        np.delete(flexed.tt, ids.index("P2"), 0), np.delete(rel.tt, ids.index("P2"), 0)
    )
    planned = spec(parts, flex=["P2"])
    assert planned.flex == ("P2",)
    assert build_state_graph(planned, flexed).sequences() == [["opP1", "opP2"]]


@pytest.mark.parametrize(
    ("value", "message"),
    [({"a": 1}, "flex: expected a list of part ids"), (["P9"], "flex: unknown part 'P9'")],
)
def test_a_bad_flex_line_is_one_error_naming_the_key(value, message):
    with pytest.raises(ValueError, match=message):
        parse_flex(value, {"P0", "P1"}, "spool.yaml")
