"""Typed failures: each is raised where it happens, caught by its type, and keeps its parent
(so the command line still answers with one line and exit code 2)."""

from __future__ import annotations

import pytest

import asp.subassemblies as subassemblies
from asp.concurrent.build import build_game
from asp.concurrent.model import concurrent_model
from asp.concurrent.robustness import robustness
from asp.errors import (
    AsmplanError,
    GameError,
    GameLimit,
    GeometryError,
    InfeasibleAssembly,
    Interpenetration,
    SpecError,
    StateLimit,
)
from asp.graph.state_graph import build_state_graph
from asp.spec import spec_from_dict
from tests.asp.helpers_assembly import precedence_spec, relations


def _lonely_part():
    """Part K touches nothing: no complete sequence."""
    data = {
        "parts": [{"id": "B", "file": "b"}, {"id": "K", "file": "k"}],
        "agents": {"R": {"side": "robot"}},
        "base_part": "B",
        "operations": [{"id": "k", "agents": {"R": 1}, "part": "K"}],
    }
    return spec_from_dict(data, source="k.yaml"), relations(("B", "K"))


def _two_jobs():
    data = {
        "name": "job",
        "agents": {"H": {"side": "human"}, "R": {"side": "robot"}},
        "operations": [
            {"id": "a", "agents": {"H": 2, "R": 3}},
            {"id": "b", "agents": {"H": 2, "R": 3}},
        ],
    }
    spec = spec_from_dict(data)
    return concurrent_model(spec, build_state_graph(spec))


@pytest.mark.parametrize(
    ("kind", "parent"),
    [
        (InfeasibleAssembly, SpecError),
        (StateLimit, SpecError),
        (GameLimit, GameError),
        (Interpenetration, GeometryError),
    ],
)
def test_each_kind_keeps_its_family(kind, parent):
    assert issubclass(kind, parent) and issubclass(kind, AsmplanError)
    assert issubclass(kind, ValueError)


def test_interpenetration_carries_its_pairs_through_a_pickle():
    import pickle

    error = Interpenetration("parts 'a' and 'b' interpenetrate", [("a", "b")])
    again = pickle.loads(pickle.dumps(error))
    assert type(again) is Interpenetration and again.pairs == (("a", "b"),)
    assert str(again) == str(error)


def test_no_complete_sequence_is_infeasible_assembly():
    spec, rel = _lonely_part()
    with pytest.raises(InfeasibleAssembly) as info:
        build_state_graph(spec, rel)
    assert "part K" in str(info.value) and "\n" not in str(info.value)


def test_too_many_states_is_state_limit():
    with pytest.raises(StateLimit) as info:
        build_state_graph(precedence_spec(10, []), max_states=100)
    assert "raise max_states" in str(info.value)


def test_too_many_nodes_is_game_limit():
    with pytest.raises(GameLimit, match="--max-k"):
        build_game(_two_jobs(), None, max_nodes=2)
    with pytest.raises(GameLimit):  # the curve has nothing to show: the limit stands
        robustness(_two_jobs(), max_k=2, max_nodes=2)


def test_units_decide_by_type_not_by_text(monkeypatch):
    """An infeasible assembly whose message says nothing known still starts the rounds of
    subassemblies; a plain SpecError with the old words does not."""
    spec, rel = _lonely_part()
    calls = []

    def failing(message, kind):
        def build(*args, **kwargs):
            calls.append(kind)
            raise kind(message)

        return build

    monkeypatch.setattr(
        "asp.graph.symmetry.reduced_state_graph", failing("no words", InfeasibleAssembly)
    )
    monkeypatch.setattr("asp.graph.precedences.refutation", lambda *a: None)
    with pytest.raises(InfeasibleAssembly):
        subassemblies.build_with_units(spec, rel, reduce=True)
    assert calls == [InfeasibleAssembly]  # given up after the rounds, the first error raised
    monkeypatch.setattr(
        "asp.graph.symmetry.reduced_state_graph",
        failing("infeasible assembly, raise max_states", SpecError),
    )
    with pytest.raises(SpecError) as info:
        subassemblies.build_with_units(spec, rel, reduce=True)
    assert type(info.value) is SpecError


def test_a_state_limit_says_the_proof_that_no_limit_gives_a_plan():
    """Eight free parts on a base and one touching nothing: the graph goes over a limit of
    20 states long before the dead end shows, and the derived precedences prove there is
    no complete sequence; the error says so with the proof (raising the limit would
    only build a larger graph to fail). A feasible spec's error says no such thing."""
    free = [f"F{k}" for k in range(8)]
    data = {
        "parts": [{"id": p, "file": p.lower()} for p in ("B", *free, "K")],
        "agents": {"R": {"side": "robot"}},
        "base_part": "B",
        "constraints": {"stability": False},
        "operations": [{"id": p, "agents": {"R": 1}, "part": p} for p in (*free, "K")],
    }
    rel = relations(("B", *free, "K"), contacts=[(p, "B", "+z") for p in free])
    with pytest.raises(StateLimit) as info:
        build_state_graph(spec_from_dict(data, source="k.yaml"), rel, max_states=20)
    said = str(info.value)
    assert "raise max_states" in said and "no complete sequence exists" in said
    assert "K" in said.rpartition("as the derived precedences prove")[2]
    data["parts"] = data["parts"][:-1]
    data["operations"] = data["operations"][:-1]
    rel = relations(("B", *free), contacts=[(p, "B", "+z") for p in free])
    with pytest.raises(StateLimit) as info:
        build_state_graph(spec_from_dict(data, source="f.yaml"), rel, max_states=20)
    assert "no complete sequence" not in str(info.value)
