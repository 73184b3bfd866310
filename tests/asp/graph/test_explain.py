"""Any number of parts, and infeasible assemblies explained by their root cause."""

from __future__ import annotations

import numpy as np
import pytest

from asp.graph.checker import check_line
from asp.graph.feasibility import insertion_oracle
from asp.graph.state_graph import build_state_graph
from asp.spec import spec_from_dict
from tests.asp.helpers_assembly import LATERAL, relations


def tower(n, extra_contacts=(), extra_blocks=()):
    """``n`` parts stacked: part k rests on part k - 1 (free only upwards)."""
    parts = tuple(f"P{k}" for k in range(n))
    contacts = [(parts[k], parts[k - 1], "-z") for k in range(1, n)]
    blocks = [(parts[k], parts[k - 1], "-z") for k in range(1, n)]
    return parts, relations(parts, [*contacts, *extra_contacts], [*blocks, *extra_blocks])


def tower_spec(parts, after=None):
    ops = [
        {"id": p, "agents": {"R": 1}, "part": p, "after": (after or {}).get(p, [])}
        for p in parts[1:]
    ]
    data = {
        "parts": [{"id": p, "file": f"{p}.stl"} for p in parts],
        "agents": {"R": {"side": "robot"}},
        "base_part": parts[0],
        "operations": ops,
    }
    return spec_from_dict(data, source="tower.yaml")


@pytest.mark.parametrize("n", [65, 70, 130])
def test_more_than_64_parts(n):
    parts, rel = tower(n)
    oracle = insertion_oracle(tower_spec(parts), rel)
    assert oracle.n_words == -(-n // 64)
    graph = build_state_graph(tower_spec(parts), rel)
    assert graph.count_sequences() == 1
    assert graph.n_states == n
    assert graph.sequences() == [list(parts[1:])]
    check_line(graph.spec, rel, graph.sequences()[0])


def test_wide_part_sets_agree_with_python_ints():
    parts, rel = tower(70)
    oracle = insertion_oracle(tower_spec(parts), rel)
    sets = [sum(1 << k for k in range(m)) for m in (1, 40, 68, 69)]
    # part 69 needs part 68 below it; part 1 is blocked by part 2 above it once placed
    assert oracle.feasible(69, np.array(sets, dtype=object)).tolist() == [0, 0, 0, 1]
    assert oracle.feasible(1, np.array(sets[:1], dtype=object)).tolist() == [True]


def test_root_cause_not_knock_on():
    # P3 is blocked on every side by P1 and P2 (it had to go in before them, but rests on
    # P2); every part above P3 only fails because P3 never comes.
    parts = tuple(f"P{k}" for k in range(8))
    blocks = [("P3", q, d) for q in ("P1", "P2") for d in ("+z", *LATERAL)]
    _, rel = tower(8, extra_blocks=blocks)
    with pytest.raises(ValueError) as info:
        build_state_graph(tower_spec(parts), rel)
    text = str(info.value)
    assert "part P3 (operation P3) can never be inserted" in text
    assert "no free direction (blocked along +x by P1, P2" in text
    assert "part P4" not in text and "\n" not in text
    assert "4 more operation(s) never done, knock-on" in text
    assert "e.g. after placing P1, P2;" in text and "{" not in text  # parts, not op ids


def test_precedence_named_as_the_cause():
    parts = tuple(f"P{k}" for k in range(4))
    # P2 sits in a pocket of P1 and may only go in after P3 (spec), which closes the pocket.
    blocks = [("P2", "P3", "+z"), *(("P2", "P1", d) for d in LATERAL)]
    _, rel = tower(4, extra_blocks=blocks, extra_contacts=[("P3", "P1", "-z")])
    spec = tower_spec(parts, after={"P2": ["P3"]})
    with pytest.raises(
        ValueError, match=r"part P2 .*along \+z by P3.*precedence: P3 by operation P3"
    ):
        build_state_graph(spec, rel)


def test_dead_end_is_named_never_an_empty_list():
    # A and B both stand on the base; whichever comes first closes the other's only way in.
    parts = ("B", "A", "C")
    contacts = [("A", "B", "-z"), ("C", "B", "-z")]
    blocks = [(x, "B", "-z") for x in "AC"]
    blocks += [("A", "C", d) for d in ("+z", *LATERAL)] + [("C", "A", d) for d in ("+z", *LATERAL)]
    rel = relations(parts, contacts, blocks)
    with pytest.raises(ValueError) as info:
        build_state_graph(tower_spec(parts), rel)
    text = str(info.value)
    assert "every order ends in a dead end; the furthest, after placing A (" in text
    assert "cannot be inserted (" in text and "no free direction" in text
    assert not text.rstrip().endswith("operations")


def test_state_limit_names_the_multiplying_parts_and_the_key():
    parts = tuple(f"P{k}" for k in range(12))
    contacts = [(p, "P0", "-z") for p in parts[1:]]
    rel = relations(parts, contacts, [(p, "P0", "-z") for p in parts[1:]])
    spec = tower_spec(parts)
    with pytest.raises(ValueError, match="exceeds the limit of 500 states") as info:
        build_state_graph(spec, rel, max_states=500)
    text = str(info.value)
    assert "the free order of 11 parts or operations multiplies them (P" in text
    assert "--max-states N" in text and "max_states: N" in text
    data = {"max_states": 500, "parts": [{"id": p, "file": f"{p}.stl"} for p in parts]}
    limited = spec_from_dict({**data, **_rest(spec)}, source="tower.yaml")
    assert limited.max_states == 500
    with pytest.raises(ValueError, match="exceeds the limit of 500 states"):
        build_state_graph(limited, rel)


def _rest(spec):
    ops = [{"id": op.id, "agents": {"R": 1}, "part": op.parts[0]} for op in spec.operations]
    return {"agents": {"R": {"side": "robot"}}, "base_part": "P0", "operations": ops}
