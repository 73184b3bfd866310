"""Graph files: asmplan-dag/1 JSON and GraphML, with clear errors on bad files."""

import json

import networkx as nx
import pytest

from asp.game.dag import HUMAN, from_edges
from asp.game.io import dag_to_dict, load_dag, save_dag
from asp.game.synth import synthetic_dag


def _same(a, b):
    assert [str(x) for x in a.node_ids] == [str(x) for x in b.node_ids]
    assert a.indptr.tolist() == b.indptr.tolist()
    assert a.targets.tolist() == b.targets.tolist()
    assert a.costs.tolist() == b.costs.tolist()
    assert a.sides.tolist() == b.sides.tolist()
    assert (a.start, a.end) == (b.start, b.end)


@pytest.mark.parametrize("suffix", [".json", ".graphml"])
def test_round_trip(tmp_path, suffix):
    dag = from_edges(
        ["s", "a", "t"],
        [("s", "a"), ("a", "t"), ("s", "t")],
        costs=[1.5, 2, 7],
        sides=[0, HUMAN, 2],
        operations=["1.1", "1.2", "2.1"],
        agents=["R1", "H", "R2"],
        cost_model="time",
    )
    path = save_dag(dag, tmp_path / f"g{suffix}")
    back = load_dag(path)
    _same(dag, back)
    assert back.operations == dag.operations and back.agents == dag.agents
    assert back.cost_model == "time"


def test_synthetic_json_keeps_metadata(tmp_path):
    dag = synthetic_dag(4, 10, 4, seed=1)
    back = load_dag(save_dag(dag, tmp_path / "g.json"))
    _same(dag, back)
    assert back.metadata["seed"] == 1


def test_plain_networkx_graphml(tmp_path):
    g = nx.DiGraph()
    g.add_edge(1, 2, cost=3)
    g.add_edge(1, 3)
    g.add_edge(2, 4)
    g.add_edge(3, 4)
    nx.write_graphml(g, tmp_path / "plain.graphml")
    dag = load_dag(tmp_path / "plain.graphml")
    assert dag.node_ids[dag.start] == "1" and dag.node_ids[dag.end] == "4"
    assert sorted(dag.costs.tolist()) == [1, 1, 1, 3]


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("{not json", "malformed JSON"),
        ('{"format": "other/1", "nodes": [], "edges": []}', "expected format"),
        ('{"nodes": [1, 2], "edges": [[1, 2]]}', "malformed graph"),
        ('{"nodes": [], "edges": []}', "empty graph"),
        ('{"nodes": [1, 2], "edges": [{"source": 1, "target": 3}]}', "unknown node 3"),
        ('{"nodes": [1, 2], "edges": [{"source": 1, "target": 2, "cost": -2}]}', "negative"),
        ("[1, 2]", "expected a JSON object"),
        ('{"nodes": [1, 2.0], "edges": [{"source": 1, "target": 2.0}]}', "node id 2.0: expected"),
        ('{"nodes": [1, true], "edges": [{"source": 1, "target": true}]}', "node id true"),
        ('{"nodes": [1, null], "edges": [{"source": 1, "target": null}]}', "node id null"),
        ('{"nodes": [1, 2], "edges": [{"source": 1.0, "target": 2}]}', "edge end 1.0"),
        ('{"nodes": [1, 2], "edges": [{"source": 1, "target": 2}], "start": 1.0}', "start/end 1.0"),
        # issue 26 (the reliability probe): a cost not written as a number names the edge
        ('{"nodes": [1, 2], "edges": [{"source": 1, "target": 2, "cost": "x"}]}', "edge 1 cost"),
        ('{"nodes": [1, 2], "edges": [{"source": 1, "target": 2, "cost": true}]}', "cost true"),
        ('{"nodes": [1, 2], "edges": [{"source": 1, "target": 2, "cost": [1]}]}', "cost \\[1\\]"),
        (
            '{"nodes": [1, 2], "edges": [{"source": 1, "target": 2}], "start": 1, "start": 2}',
            'duplicate key "start"',
        ),
        (
            '{"nodes": [1, 2], "edges": [{"source": 1, "target": 2, "cost": 1, "cost": 5}]}',
            'duplicate key "cost"',
        ),
    ],
)
def test_bad_json_names_the_file(tmp_path, content, message):
    path = tmp_path / "bad.json"
    path.write_text(content)
    with pytest.raises(ValueError, match=message) as info:
        load_dag(path)
    assert "bad.json" in str(info.value)


def test_missing_file_and_unknown_suffix(tmp_path):
    with pytest.raises(FileNotFoundError, match="nope.json"):
        load_dag(tmp_path / "nope.json")
    (tmp_path / "g.txt").write_text("x")
    with pytest.raises(ValueError, match="unknown graph format"):
        load_dag(tmp_path / "g.txt")


def test_save_is_atomic_and_readable_json(tmp_path):
    dag = synthetic_dag(3, 3, 2, seed=0)
    path = save_dag(dag, tmp_path / "sub" / "g.json")
    data = json.loads(path.read_text())
    assert data == dag_to_dict(dag) | {"metadata": data["metadata"]}
    assert [p.name for p in path.parent.iterdir()] == ["g.json"]


def test_large_graph_is_written_compactly_and_round_trips(tmp_path):
    import numpy as np

    from asp.game.dag import from_arrays
    from asp.game.io import READABLE_EDGES

    n = READABLE_EDGES // 2 + 2
    src = np.concatenate([np.arange(n - 1), np.arange(n - 2)])
    dst = np.concatenate([np.arange(1, n), np.arange(2, n)])
    dag = from_arrays(list(range(n)), src, dst, start=0, end=n - 1)
    assert dag.n_edges > READABLE_EDGES
    path = save_dag(dag, tmp_path / "big.json")
    assert path.read_text().count("\n") == 1  # one line: compact
    _same(dag, load_dag(path))


def test_graphml_parallel_edges_are_moves_not_the_last_one(tmp_path):
    """Issue 14, item 8: costs 1 and 9 between the same nodes gave TCT 9 (the last kept)."""
    from asp.game.solve import solve

    g = nx.MultiDiGraph()
    g.add_edge("s", "t", cost=1)
    g.add_edge("s", "t", cost=9)
    nx.write_graphml(g, tmp_path / "parallel.graphml")
    dag = load_dag(tmp_path / "parallel.graphml")
    assert sorted(dag.costs.tolist()) == [1, 9]
    assert solve(dag).tct == 1


def test_parallel_edges_round_trip_through_graphml(tmp_path):
    dag = from_edges(
        ["s", "t"],
        [("s", "t"), ("s", "t")],
        costs=[2, 5],
        sides=[0, HUMAN],
        operations=["1", "1"],
        agents=["R1", "H"],
    )
    back = load_dag(save_dag(dag, tmp_path / "g.graphml"))
    assert back.n_edges == 2
    assert sorted(zip(back.agents, back.costs.tolist(), strict=True)) == [("H", 5), ("R1", 2)]


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ('{"nodes": [1, 2], "edges": [{"source": 1, "target": 2, "cost": 1e400}]}', "1e\\+12"),
        ('{"nodes": [1, 2], "edges": [{"source": 1, "target": 2, "cost": NaN}]}', "non-finite"),
        ('{"nodes": [1, 2], "edges": [{"source": 1, "target": 2, "cost": 1e13}]}', "too large"),
        ('{"nodes": [1, 2], "edges": [{"source": 1, "target": 2, "cost": 1' + "0" * 400 + "}]}",
         "too large"),
        ("[" * 200_000 + "]" * 200_000, "nested too deeply"),
    ],
)  # fmt: skip
def test_numbers_past_the_limit_and_deep_nesting_are_refused(tmp_path, content, message):
    """Issue 14, items 5 and 6: overflowing costs, NaN and deep JSON name the file."""
    path = tmp_path / "bad.json"
    path.write_text(content)
    with pytest.raises(ValueError, match=message) as info:
        load_dag(path)
    assert "bad.json" in str(info.value)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda d: d["nodes"].__setitem__(0, {"id": "s" * 201}), "node id 1: 201 characters"),
        (lambda d: d["edges"][0].__setitem__("operation", "o" * 201), "edge operation 1: 201"),
        (lambda d: d["edges"][0].__setitem__("agent", "a" * 201), "edge agent 1: 201"),
    ],
)
def test_texts_of_a_dag_file_are_bounded(tmp_path, change, message):
    """Issue 26 item 13: every id and label at most a name long (cad.texts.bounded)."""
    data = {
        "format": "asmplan-dag/1",
        "nodes": ["s", "t"],
        "edges": [{"source": "s", "target": "t", "cost": 1, "side": "robot"}],
        "start": "s",
        "end": "t",
    }
    change(data)
    path = tmp_path / "g.json"
    path.write_text(json.dumps(data))
    with pytest.raises(ValueError, match="over the limit of 200") as info:
        load_dag(path)
    assert message in str(info.value) and "\n" not in str(info.value)
    assert str(info.value).count(str(path)) == 1  # the file named once


def test_texts_of_a_graphml_file_are_bounded(tmp_path):
    g = nx.DiGraph()
    g.add_edge("s", "t" * 201, cost=1.0)
    path = tmp_path / "g.graphml"
    nx.write_graphml(g, path)
    with pytest.raises(ValueError, match="node id 2: 201 characters, over the limit of 200") as e:
        load_dag(path)
    assert str(e.value).count(str(path)) == 1
