"""The independent plan checker accepts feasible lines and names the first wrong step."""

from __future__ import annotations

import pytest

from asp.graph.checker import PlanCheckError, check_line
from tests.asp.helpers_assembly import relations, stack_relations, stack_spec


def test_accepts_the_stack_and_gives_the_way_in():
    steps = check_line(stack_spec(), stack_relations(), ["p", "s"])
    assert [(s.operation, s.parts, s.direction) for s in steps] == [
        ("p", ("P",), "+z"),
        ("s", ("S",), "+z"),
    ]


@pytest.mark.parametrize(
    ("line", "message"),
    [
        (["s", "p"], r"step 1 \(operation s\): S touches none of B"),
        (["p"], "ends with operation s not done"),
        (["p", "s", "s"], "done twice"),
    ],
)
def test_rejects_wrong_lines(line, message):
    with pytest.raises(PlanCheckError, match=message):
        check_line(stack_spec(), stack_relations(), line)


def test_rejects_blocked_and_unsupported_and_precedence():
    # P sits on B; S is blocked from above by P once P is there and hangs under nothing.
    rel = relations(
        ("B", "P", "S"),
        contacts=[("P", "B", "-z"), ("S", "B", "+x")],
        blocks=[("S", "P", d) for d in ("+x", "-x", "+y", "-y", "+z", "-z")],
    )
    spec = stack_spec(gripper_approach=["+z", "-z", "+x", "-x", "+y", "-y"])
    with pytest.raises(PlanCheckError, match="S has no free way in past B, P"):
        check_line(spec, rel, ["p", "s"])
    with pytest.raises(PlanCheckError, match="S is not supported"):
        check_line(spec, rel, ["s", "p"])
    ops = [
        {"id": "p", "agents": {"R": 1}, "part": "P", "after": ["s"]},
        {"id": "s", "agents": {"R": 1}, "part": "S", "held": True},
    ]
    later = stack_spec(operations=ops, agents={"R": {"side": "robot"}})
    with pytest.raises(PlanCheckError, match="predecessor s is not done"):
        check_line(later, rel, ["p", "s"])
    with pytest.raises(PlanCheckError, match=r"step 2 \(operation p\): P has no free way"):
        check_line(later, rel, ["s", "p"])  # held, S may come first; then P cannot go in


def test_a_unit_is_one_rigid_body():
    # P and S together: S alone would hang in the air, as a unit it stands on B through P.
    steps = check_line(stack_spec(), stack_relations(), ["p", "s"], units={"p": ("P", "S")})
    assert steps[0].parts == ("P", "S") and steps[0].direction == "+z"
