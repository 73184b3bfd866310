"""The state graph builder's memory bound (issue 26 item 3): estimated before each layer,
checked as it builds, one line naming --max-states, the estimate and the memory available."""

from __future__ import annotations

import pytest
import yaml

from asmplan.cli import main
from asp import heap
from asp.errors import StateLimit
from asp.graph.state_graph import build_state_graph, graph_bytes
from asp.subassemblies import build_with_units
from tests.asp.helpers_assembly import precedence_spec

MB = 2**20


def message_of(info) -> str:
    text = str(info.value)
    assert "\n" not in text
    for words in ("needs more memory than it may use", "GB available", "--max-states", "fit"):
        assert words in text, text
    return text


@pytest.mark.parametrize(
    ("n", "limit", "where"),
    [
        # 14 free operations: 16,384 states, 114,688 transitions, about 1.9 MB in all
        (14, MB // 2, "while building layer"),
        (14, MB, "while building layer"),
        # 40 free operations, the state limit out of reach: the projection after a few
        # layers is over long before those layers are built
        (40, 320 * MB, "projected from the"),
    ],
)
def test_a_build_over_its_memory_stops_with_the_estimate(n, limit, where):
    with pytest.raises(StateLimit) as info:
        build_state_graph(precedence_spec(n, []), max_states=10**12, max_memory=limit)
    text = message_of(info)
    assert where in text and "--max-states 1,000,000,000,000" in text, text


def test_enough_memory_builds_the_same_graph():
    spec = precedence_spec(12, [(0, 1)])
    full = build_state_graph(spec)
    need = graph_bytes(full.n_states, full.n_transitions)
    again = build_state_graph(spec, max_memory=2 * need)
    assert (again.n_states, again.n_transitions) == (full.n_states, full.n_transitions)
    with pytest.raises(StateLimit):
        build_state_graph(spec, max_memory=need // 4)


def test_the_estimate_grows_with_the_graph():
    assert graph_bytes(10, 10) < graph_bytes(10, 11) < graph_bytes(11, 11)
    assert graph_bytes(10, 10) < graph_bytes(10, 10, 1) and graph_bytes(10, 10, wide=True) > (
        graph_bytes(10, 10)
    )
    assert graph_bytes(10, 0, n_words=2) == 2 * graph_bytes(10, 0)


@pytest.fixture
def little_memory(monkeypatch):
    """A machine with 4 MB available (3 MB for a build)."""
    monkeypatch.setattr(heap, "available_memory", lambda: 4 * MB)


def test_the_default_limit_is_a_share_of_the_memory_available(little_memory):
    assert heap.memory_budget() == 3 * MB and heap.memory_budget(MB) == MB
    with pytest.raises(StateLimit) as info:
        build_state_graph(precedence_spec(18, []), max_states=10**9)
    assert "(0.00 GB available)" in message_of(info)
    # through the automatic subassemblies as well (every round builds with the bound)
    with pytest.raises(StateLimit):
        build_with_units(precedence_spec(18, []), None, max_states=10**9)


def test_plan_with_a_huge_max_states_stops_in_one_line(tmp_path, capsys, little_memory):
    # the real case: many free parts and --max-states 1e9 used to take all the memory
    ops = [{"id": f"o{k}", "agents": {"any": 1}} for k in range(22)]
    spec = tmp_path / "free.yaml"
    spec.write_text(yaml.safe_dump({"agents": {"any": {"side": "any"}}, "operations": ops}))
    out = tmp_path / "plan"
    for command in (["graph", str(spec)], ["plan", str(spec), "-o", str(out)]):
        with pytest.raises(SystemExit) as info:
            main([*command, "--max-states", "1000000000"])
        err = capsys.readouterr().err.strip().splitlines()
        assert info.value.code == 2, err
        assert err[-1].startswith("asmplan: error: ") and "--max-states 1,000,000,000" in err[-1]
        assert "needs more memory than it may use" in err[-1]
    assert not out.exists() or not any(out.iterdir())


@pytest.mark.parametrize(
    ("limit", "usage", "room"),
    [
        ("max", "100", None),
        ("1000", "300", 700),
        ("100", "300", 0),
        ("9223372036854771712", "5", None),
    ],
)
def test_the_control_group_limit_bounds_the_memory_available(tmp_path, limit, usage, room):
    (tmp_path / "max").write_text(limit + "\n")
    (tmp_path / "cur").write_text(usage + "\n")
    files = (
        (str(tmp_path / "none"), str(tmp_path / "none")),
        (str(tmp_path / "max"), str(tmp_path / "cur")),
    )
    assert heap.cgroup_room(files) == room
