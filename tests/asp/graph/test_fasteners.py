"""Joining parts (screws, pins) in one order after the parts they join: sound, complete."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from asp.errors import StateLimit
from asp.graph import state_graph
from asp.graph.checker import PlanCheckError, check_line
from asp.graph.fasteners import fastener_order, joining_parts, joining_states
from asp.graph.state_graph import build_state_graph
from asp.graph.symmetry import reduced_state_graph, symmetry_reduction
from asp.subassemblies import build_with_units
from tests.asp.helpers_assembly import LATERAL, parts_spec, relations


def screwed_brackets(n_brackets=3, screws=2):
    """A base, brackets standing on it, each fixed by screws through it into the base
    (a screw touches its bracket and the base, goes in along -z, and once in keeps its
    bracket from leaving upwards)."""
    brackets = [f"bracket{k}" for k in range(n_brackets)]
    fixing = {b: [f"{b}_screw{s}" for s in range(screws)] for b in brackets}
    parts = ("base", *brackets, *(s for ss in fixing.values() for s in ss))
    contacts = [(b, "base", "-z") for b in brackets]
    blocks = [(b, "base", "-z") for b in brackets]
    for b, ss in fixing.items():
        contacts += [c for s in ss for c in ((s, b, "-z"), (s, "base", "-z"))]
        blocks += [(s, q, d) for s in ss for q in (b, "base") for d in ("-z", *LATERAL)]
    rel = relations(parts, contacts, blocks)
    return parts_spec(parts, "brackets.yaml", lambda k, _: {"H": 2 + k % 3, "R": 3}), rel


def done_sets(graph) -> set[frozenset[str]]:
    """Every state of ``graph`` as the set of operations done on some path to it."""
    out = set()
    for seq in graph.sequences(limit=10_000):
        for k in range(len(seq) + 1):
            out.add(frozenset(seq[:k]))
    return out


def test_the_screws_are_the_joining_parts_and_wait_for_what_they_join():
    spec, rel = screwed_brackets()
    found = joining_parts(spec, rel)
    assert sorted(j.part for j in found) == sorted(p for p in rel.parts if "screw" in p)
    assert all(set(j.joins) == {"base", j.part.split("_")[0]} for j in found)
    ordered, chain = fastener_order(spec, rel)
    for before, j in zip(chain, chain[1:], strict=False):  # one chain, after both joined
        assert set(ordered.operation(j.operation).after) == {j.joins[1], before.operation}
    assert not any(op.held for op in ordered.operations)  # the brackets rest on the base


def test_the_order_keeps_only_sound_sequences_and_a_complete_one():
    spec, rel = screwed_brackets()
    full = build_state_graph(spec, rel)
    ordered, _ = fastener_order(spec, rel)
    reduced = build_state_graph(ordered, rel)
    assert reduced.n_states < full.n_states // 10
    assert done_sets(reduced) <= done_sets(full)  # a sub-graph of the full graph
    sequences = reduced.sequences(limit=50)
    assert sequences
    for seq in sequences:
        check_line(spec, rel, seq)  # the original spec's rules, replayed independently


@pytest.mark.parametrize(
    "change",
    [
        "screw blocked by a cover along its only way",  # (2): does not go in whatever is there
        "screw touches another screw",  # (1): not both
        "screw has a predecessor",
    ],
)
def test_a_part_that_is_no_joining_part_is_left_alone(change):
    spec, rel = screwed_brackets(n_brackets=2, screws=1)
    screw = "bracket0_screw0"
    s = rel.parts.index(screw)
    tc, tt = rel.tc.copy(), rel.tt.copy()
    if change.startswith("screw blocked"):
        other = rel.parts.index("bracket1")
        tt[s, other, 4] = tt[other, s, 5] = False
    elif change.startswith("screw touches"):
        other = rel.parts.index("bracket1_screw0")
        tc[s, other, 0] = tc[other, s, 1] = True
        screw = "bracket1_screw0"  # the later of the two in spec order touches the first
    else:
        ops = [
            op.__class__(**{**op.__dict__, "after": ("bracket1",)}) if op.id == screw else op
            for op in spec.operations
        ]
        spec = spec.__class__(**{**spec.__dict__, "operations": tuple(ops)})
    rel = type(rel)(rel.parts, tc, tt)
    assert screw not in {j.part for j in joining_parts(spec, rel)}


def test_a_part_resting_only_on_its_screws_is_held_while_they_go_in():
    spec, rel = screwed_brackets(n_brackets=2, screws=2)
    sp = rel.tc.copy()
    b = rel.parts.index("bracket0")
    sp[b, :, :] = False  # bracket0 touches the base but rests only on its screws
    for s in ("bracket0_screw0", "bracket0_screw1"):
        sp[b, rel.parts.index(s), 5] = True
    with_support = SimpleNamespace(parts=rel.parts, tc=rel.tc, tt=rel.tt, sp=sp)
    ordered, _ = fastener_order(spec, with_support)
    assert [op.id for op in ordered.operations if op.held] == ["bracket0"]
    graph = build_state_graph(ordered, with_support)
    for seq in graph.sequences(limit=20):
        check_line(ordered, with_support, seq)  # replayed with the plan's held flags
        with pytest.raises(PlanCheckError):  # loose, it has nothing to rest on
            check_line(spec, with_support, seq)


def test_the_state_limit_builds_the_graph_again_with_the_order_and_says_so():
    spec, rel = screwed_brackets()
    full = build_state_graph(spec, rel).n_states
    ordered = build_state_graph(fastener_order(spec, rel)[0], rel).n_states
    limit = (full + ordered) // 2
    said: list[str] = []
    graph = build_with_units(spec, rel, max_states=limit, on_unit=said.append)
    assert graph.n_states == ordered
    assert any("joining parts" in line and "one order" in line for line in said)
    with pytest.raises(StateLimit):  # below what the order needs: the limit stands
        build_with_units(spec, rel, max_states=ordered - 1)


def _stopped_after(exc: StateLimit) -> tuple[int, bool]:
    """The layer after which a state-limit error stopped, and whether by projection."""
    text = str(exc)
    layer = int(text.split("after layer ")[1].split()[0])
    return layer, "projected" in text


def test_a_margin_of_one_gives_up_a_graph_sure_to_go_over_a_layer_sooner():
    """Six brackets of two screws (262,144 states) under a limit of a fifth of that: the
    cautious projection stops the build after layer 6 at margin 1, after layer 7 at the
    default margin 2 (which first builds a layer it does not need)."""
    spec, rel = screwed_brackets(n_brackets=6, screws=2)
    limit = 52_428
    stopped = {}
    for margin in (1, 2):
        with pytest.raises(StateLimit) as info:
            build_state_graph(spec, rel, max_states=limit, projection_margin=margin)
        stopped[margin] = _stopped_after(info.value)
    assert stopped[1] == (6, True)
    assert stopped[2][0] == 7


@pytest.mark.parametrize(
    ("brackets", "screws", "margin"),
    [(3, 2, 1), (1, 1, 2)],  # joining parts: the fallback stands behind; one screw: none
)
def test_the_full_graph_is_tried_at_margin_one_only_with_joining_parts_to_fall_back_on(
    monkeypatch, brackets, screws, margin
):
    """The APLAN toy truck: its full graph was built to 11.9 M states (2.2 GB, 54 s) before
    the joining parts were put in order; with them known first, it stops a layer sooner."""
    import asp.graph.state_graph as state_graph

    spec, rel = screwed_brackets(n_brackets=brackets, screws=screws)
    real = state_graph.build_state_graph
    margins = []

    def recording(*args, **kwargs):
        margins.append(kwargs.get("projection_margin", state_graph.PROJECTION_MARGIN))
        return real(*args, **kwargs)

    monkeypatch.setattr(state_graph, "build_state_graph", recording)
    build_with_units(spec, rel, reduce=False)
    assert margins[0] == margin


def test_no_joining_parts_no_change():
    spec, rel = screwed_brackets(n_brackets=1, screws=1)
    assert fastener_order(spec, rel) == (spec, [])
    rel = type(rel)(rel.parts, np.zeros_like(rel.tc), rel.tt)
    assert joining_parts(spec, rel) == []


@pytest.mark.parametrize("brackets, screws", [(1, 2), (2, 2), (3, 2), (2, 3), (4, 1)])
def test_the_joining_states_are_at_most_the_full_graphs(brackets, screws):
    spec, rel = screwed_brackets(n_brackets=brackets, screws=screws)
    found = joining_parts(spec, rel)
    classes = symmetry_reduction(spec, rel)[3]
    states = joining_states(found, classes)
    assert states >= 2 ** len(found) // 2 ** len(classes)  # counts every joining part
    assert states <= build_state_graph(spec, rel).n_states
    assert states <= reduced_state_graph(spec, rel).n_states  # the graph the build makes


def test_over_the_projection_the_full_graph_is_never_built(monkeypatch):
    spec, rel = screwed_brackets(n_brackets=3, screws=2)
    found = joining_parts(spec, rel)
    assert joining_states(found, symmetry_reduction(spec, rel)[3]) == 64
    built: list = []
    real = state_graph.build_state_graph

    def counting(spec_built, *args, **kwargs):
        built.append(spec_built)
        return real(spec_built, *args, **kwargs)

    monkeypatch.setattr(state_graph, "build_state_graph", counting)
    said: list[str] = []
    graph = build_with_units(spec, rel, reduce=True, max_states=40, on_unit=said.append)
    ordered, chain = fastener_order(spec, rel)
    assert built  # and each time with the screws in their chain, never the full graph
    for s in built:
        for j in chain:
            assert set(ordered.operation(j.operation).after) <= set(s.operation(j.operation).after)
    assert any("the full graph is not built" in line for line in said)
    sequences = graph.sequences(limit=20)
    assert sequences
    for seq in sequences:
        check_line(spec, rel, seq)


def test_under_the_projection_the_full_graph_is_built_first():
    spec, rel = screwed_brackets(n_brackets=3, screws=2)  # 64 joining states, 125 in all
    full = reduced_state_graph(spec, rel).n_states
    assert build_with_units(spec, rel, reduce=True, max_states=full).n_states == full
    said: list[str] = []
    graph = build_with_units(spec, rel, reduce=True, max_states=100, on_unit=said.append)
    assert graph.n_states < 64  # the full graph went over: then the order
    assert any("the full graph exceeds the limit" in line for line in said)


def stacked_links(n_links):
    """``n_links`` links stacked on a base, a cap on the top one (each link rests on the
    one below and touches the one above; nothing but the one below stops it): merged coil
    links or a chain standing up."""
    links = [f"link{k}" for k in range(n_links)]
    parts = ("base", *links, "cap")
    column = ["base", *links, "cap"]
    pairs = list(zip(column[1:], column[:-1], strict=True))  # (upper, lower)
    rel = relations(parts, [(u, lo, "-z") for u, lo in pairs], [(u, lo, "-z") for u, lo in pairs])
    return parts_spec(parts, "links.yaml"), rel


@pytest.mark.parametrize("n_links", [1, 2, 3, 6])
def test_links_in_a_chain_are_no_joining_parts(n_links):
    """Links in a chain touch each other, and the cap touches the top link only: each
    would join a part that qualifies itself (condition 1), so none is one and none is put
    in an order (with one link the cap and the link join each other)."""
    spec, rel = stacked_links(n_links)
    assert joining_parts(spec, rel) == []
    assert fastener_order(spec, rel) == (spec, [])


def test_a_part_on_one_host_or_three_is_a_joining_part():
    """A cover touching only the block it sits on, and a bolt through three plates, are
    joining parts of one and of three parts (the rule once took exactly two: the engine's
    and the satellite's free modules were none); ordered, the graph keeps a complete
    sequence and each of its sequences is sound by the original spec's rules."""
    parts = ("base", "plate1", "plate2", "cover", "bolt", "module")
    contacts = [
        ("plate1", "base", "-z"),
        ("plate2", "plate1", "-z"),
        ("cover", "plate2", "-z"),
        ("bolt", "base", "-z"),
        ("bolt", "plate1", "+x"),
        ("bolt", "plate2", "+x"),
        ("module", "base", "-z"),
    ]
    blocks = [
        *(("plate1", "base", d) for d in ("-z", *LATERAL)),
        *(("plate2", "plate1", d) for d in ("-z", *LATERAL)),
        ("cover", "plate2", "-z"),
        ("bolt", "base", "-z"),
        ("module", "base", "-z"),
    ]
    rel = relations(parts, contacts, blocks)
    spec = parts_spec(parts, "hosts.yaml")
    found = {j.part: set(j.joins) for j in joining_parts(spec, rel)}
    assert found == {
        "cover": {"plate2"},
        "bolt": {"base", "plate1", "plate2"},
        "module": {"base"},
    }
    ordered, chain = fastener_order(spec, rel)
    assert [j.part for j in chain] == ["module", "cover", "bolt"]
    full, reduced = build_state_graph(spec, rel), build_state_graph(ordered, rel)
    assert reduced.n_states < full.n_states
    assert done_sets(reduced) <= done_sets(full)
    sequences = reduced.sequences(limit=50)
    assert sequences
    for seq in sequences:
        check_line(spec, rel, seq)
