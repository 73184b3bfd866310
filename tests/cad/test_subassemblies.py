"""Subassemblies: a rod tower whose holders can only go in with their bearings."""

from __future__ import annotations

import pytest

from asp.checker import check_line
from asp.game import game_dag
from asp.solve import solve
from asp.spec import spec_from_dict
from asp.state_graph import build_state_graph
from asp.units import build_with_units
from cad import Assembly, compute_relations
from tests.cad.real_shapes import annulus, box, cylinder, difference, union

RODS = (-15.0, 15.0)
LEVELS = {"1": 20.0, "2": 50.0}


def rod_tower() -> dict:
    """A base, two rods standing on it and two levels, each a holder plate with two
    flanged bearings pressed in from above; each holder touches only its own bearings."""
    parts = {"base": box((-30, -15, 0), (30, 15, 5))}
    for k, x in enumerate(RODS, start=1):
        parts[f"rod_{k}"] = cylinder(4, 5, 85, 32, (x, 0))
    for level, z in LEVELS.items():
        holes = [cylinder(7, z - 1, z + 7, 48, (x, 0)) for x in RODS]
        parts[f"holder_{level}"] = difference(box((-25, -10, z), (25, 10, z + 6)), *holes)
        for side, x in zip("ab", RODS, strict=True):
            body = annulus(4, 7, z, z + 6, 40, 48, (x, 0))
            flange = annulus(4, 10, z + 6, z + 8, 40, 60, (x, 0))
            parts[f"bearing_{level}{side}"] = union(body, flange)
    return parts


@pytest.fixture(scope="module")
def tower():
    return compute_relations(Assembly.from_meshes(rod_tower()))


def tower_spec(rel, subassemblies=None):
    ops = [{"id": p, "agents": {"H": 2, "R": 3}, "part": p} for p in rel.parts if p != "base"]
    data = {
        "parts": [{"id": p, "file": f"{p}.stl"} for p in rel.parts],
        "agents": {"H": {"side": "human"}, "R": {"side": "robot"}},
        "base_part": "base",
        "operations": ops,
    }
    if subassemblies:
        data["subassemblies"] = subassemblies
    return spec_from_dict(data, source="tower.yaml")


def test_holders_alone_never_go_in(tower):
    with pytest.raises(ValueError, match=r"part holder_1 .*can never be inserted"):
        build_state_graph(tower_spec(tower), tower)


def test_automatic_subassemblies_plan_the_tower(tower):
    graph = build_with_units(tower_spec(tower), tower)
    units = dict(graph.spec.subassemblies)
    assert sorted(map(sorted, units.values())) == [
        ["bearing_1a", "bearing_1b", "holder_1"],
        ["bearing_2a", "bearing_2b", "holder_2"],
    ]
    seqs = graph.sequences(limit=50)
    assert seqs
    for seq in seqs:
        steps = check_line(graph.spec, tower, seq)
        inserted = [s.parts for s in steps if len(s.parts) == 3]
        assert [min(p) for p in inserted] == ["bearing_1a", "bearing_2a"]  # lower level first
    solution = solve(game_dag(graph))
    assert solution.tct == len(graph.spec.operations)


def test_spec_subassemblies_and_workspaces(tower):
    units = {
        "level_1": ["holder_1", "bearing_1a", "bearing_1b"],
        "level_2": ["holder_2", "bearing_2a", "bearing_2b"],
    }
    spec = tower_spec(tower, units)
    op = spec.operation("level_2")
    assert op.unit == "level_2" and set(op.after) == set(units["level_2"])
    assert dict(op.durations) == {"H": 2, "R": 3}
    graph = build_state_graph(spec, tower)
    for seq in graph.sequences(limit=50):
        check_line(spec, tower, seq)
    # a unit can be built before the rods stand: its workspace is its own
    done = graph.model.done_matrix(graph.keys)
    ids = spec.op_ids
    assert (done[:, ids.index("bearing_2a")] & ~done[:, ids.index("rod_1")]).any()


@pytest.mark.parametrize(
    ("units", "message"),
    [
        ({"u": ["holder_1"]}, "at least two parts"),
        ({"u": ["holder_1", "nope"]}, "unknown part 'nope'"),
        ({"u": ["holder_1", "base"]}, "base part"),
        ({"rod_1": ["holder_1", "bearing_1a"]}, "already used"),
    ],
)
def test_bad_subassemblies_are_one_line_errors(tower, units, message):
    with pytest.raises(ValueError, match=message):
        tower_spec(tower, units)


def test_plan_file_shows_the_hierarchy(tower):
    from asmplan import pipeline
    from asp.checker import plan_operations

    result = pipeline.plan(pipeline.Assembly(tower_spec(tower), tower), time_limit=5)
    doc = result.to_dict()
    assert sorted(map(sorted, doc["subassemblies"].values())) == [
        ["bearing_1a", "bearing_1b", "holder_1"],
        ["bearing_2a", "bearing_2b", "holder_2"],
    ]
    units = [s for s in doc["robust_plan"] if s["operation"] in doc["subassemblies"]]
    assert [s["parts"] for s in units] == [[s["operation"]] for s in units] and len(units) == 2
    check_line(result.assembly.spec, tower, plan_operations(doc))
