"""``held`` of a generated spec for a part that rests only on what must come after it."""

from __future__ import annotations

import numpy as np

from asp.fromcad.generate import hold_refuted
from asp.graph.precedences import refutation
from asp.graph.state_graph import build_state_graph
from asp.spec import spec_from_dict
from cad.relations import Relations

PX, MX, PY, MY, PZ, MZ = range(6)
OPPOSITE = [MX, PX, MY, PY, MZ, PZ]


def bracket_on_wall():
    """A wall W on a floor B, a bracket K against the wall's face (+x side), and a screw S
    through K into W along x, its head outside K. K rests only on S (its hole on the
    shaft); S blocks K along every way but towards the wall, which W blocks: K goes in
    before S, with nothing under it yet."""
    parts = ("B", "W", "K", "S")
    k = {p: i for i, p in enumerate(parts)}
    n = len(parts)
    tc = np.zeros((n, n, 6), dtype=bool)
    tt = np.ones((n, n, 6), dtype=bool)
    sp = np.zeros((n, n, 6), dtype=bool)
    for i in range(n):
        tt[i, i] = False
    touching = [("W", "B", [MZ]), ("K", "W", [MX]), ("S", "K", [MY, PY, MZ, PZ]), ("S", "W", [MX])]
    for a, b, dirs in touching:
        for d in dirs:
            tc[k[a], k[b], d] = tc[k[b], k[a], OPPOSITE[d]] = True
    blocked = [
        ("W", "B", [MZ]),
        ("K", "W", [MX]),
        ("K", "S", [PX, PY, MY, PZ, MZ]),
        ("S", "W", [MX, PY, MY, PZ, MZ]),
    ]
    for a, b, dirs in blocked:
        for d in dirs:
            tt[k[a], k[b], d] = tt[k[b], k[a], OPPOSITE[d]] = False
    for a, b in (("W", "B"), ("K", "S"), ("S", "K"), ("S", "W")):
        sp[k[a], k[b], MZ] = True
    relations = Relations(
        parts=parts, tc=tc, tt=tt, contact_tol=0.1, penetration_tol=0.1, sp=sp, units="mm"
    )
    data = {
        "parts": [{"id": p, "file": f"{p}.stl"} for p in parts],
        "agents": {"R": {"side": "robot"}},
        "base_part": "B",
        "gravity": "-z",
        "operations": [{"id": f"op{p}", "agents": {"R": 1}, "part": p} for p in parts[1:]],
    }
    return spec_from_dict(data, source="bracket.yaml"), relations


def test_a_part_resting_only_on_its_later_screw_is_held():
    spec, relations = bracket_on_wall()
    assert refutation(spec, relations) is not None
    held, solved = hold_refuted(spec, relations)
    assert solved and [op.id for op in held.operations if op.held] == ["opK"]
    assert build_state_graph(held, relations).sequences() == [["opW", "opK", "opS"]]


def test_a_spec_not_refuted_is_unchanged_and_a_locked_part_gets_no_mark():
    spec, relations = bracket_on_wall()
    held, _ = hold_refuted(spec, relations)
    assert hold_refuted(held, relations) == (held, True)
    tt = np.array(relations.tt)
    tt[2, 1, :] = tt[1, 2, :] = False  # K and W lock each other: holding K cannot help
    from dataclasses import replace

    locked = replace(relations, tt=tt)
    again, solved = hold_refuted(spec, locked)
    assert not solved and not any(op.held for op in again.operations)
