"""Interchangeable parts: the reduced graph has the full graph's TCT and W*."""

from __future__ import annotations

import pytest

from asp.game.solve import solve
from asp.graph.checker import check_line
from asp.graph.game_dag import game_dag
from asp.graph.state_graph import build_state_graph
from asp.graph.symmetry import interchangeable_classes, reduce_interchangeable
from asp.spec import spec_from_dict
from tests.asp.helpers_assembly import LATERAL, relations


def pinned_disc(n_pins=5, n_screws=3):
    """A base, a disc on it, pins standing in the disc, a cover on the pins held by
    screws through it into the base (pins alike, screws alike, one screw needs a tool)."""
    pins = [f"pin{k}" for k in range(n_pins)]
    screws = [f"screw{k}" for k in range(n_screws)]
    parts = ("base", "disc", *pins, "cover", *screws)
    contacts = [("disc", "base", "-z"), *((p, "disc", "-z") for p in pins)]
    contacts += [("cover", p, "-z") for p in pins] + [(s, "cover", "-z") for s in screws]
    blocks = [("disc", "base", "-z")]
    blocks += [(p, "disc", d) for p in pins for d in ("-z", *LATERAL)]
    blocks += [("cover", p, "-z") for p in pins] + [(p, "cover", "+z") for p in pins]
    blocks += [(s, q, d) for s in screws for q in ("cover", "base") for d in ("-z", *LATERAL)]
    rel = relations(parts, contacts, blocks)
    ops = [{"id": "disc", "agents": {"H": 3, "R": 2}, "part": "disc"}]
    ops += [{"id": p, "agents": {"H": 2, "R": 4}, "part": p} for p in pins]
    ops += [{"id": "cover", "agents": {"H": 3, "R": 3}, "part": "cover"}]
    ops += [{"id": s, "agents": {"R": 2, "H": 5}, "part": s} for s in screws]
    data = {
        "parts": [{"id": p, "file": f"{p}.stl"} for p in parts],
        "agents": {"H": {"side": "human"}, "R": {"side": "robot"}},
        "base_part": "base",
        "operations": ops,
    }
    return spec_from_dict(data, source="disc.yaml"), rel


def test_classes_are_the_alike_parts_only():
    spec, rel = pinned_disc()
    assert interchangeable_classes(spec, rel) == [
        [f"pin{k}" for k in range(5)],
        [f"screw{k}" for k in range(3)],
    ]
    # a pin the cover does not stop (it can still go in after the cover) is not like the
    # others; a pin that also touches the base is (it comes after the disc all the same)
    pin0, cover = rel.parts.index("pin0"), rel.parts.index("cover")
    assert not rel.tt[pin0, cover, 4]
    loose = rel.tt.copy()
    loose[pin0, cover, 4] = loose[cover, pin0, 5] = True  # pin0 free along +z past the cover
    odd = type(rel)(rel.parts, rel.tc, loose)
    assert [c for c in interchangeable_classes(spec, odd) if "pin1" in c] == [
        [f"pin{k}" for k in range(1, 5)]
    ]
    other = relations(rel.parts, [("pin0", "base", "-z")])
    touching = type(rel)(rel.parts, rel.tc | other.tc, rel.tt)
    assert [c for c in interchangeable_classes(spec, touching) if "pin1" in c] == [
        [f"pin{k}" for k in range(5)]
    ]


@pytest.mark.parametrize("cost", ["steps", "time"])
def test_reduced_graph_has_the_same_tct_and_w_star(cost):
    spec, rel = pinned_disc()
    full = build_state_graph(spec, rel)
    reduced_spec = reduce_interchangeable(spec, rel)
    reduced = build_state_graph(reduced_spec, rel)
    assert reduced.n_states < full.n_states // 4
    a, b = solve(game_dag(full, cost=cost)), solve(game_dag(reduced, cost=cost))
    assert (a.tct, a.minimax) == (b.tct, b.minimax)
    for seq in reduced.sequences(limit=20):
        check_line(spec, rel, seq)
