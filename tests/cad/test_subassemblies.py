"""Subassemblies: a rod tower whose holders can only go in with their bearings."""

from __future__ import annotations

import re

import pytest

from asp.game.solve import solve
from asp.graph.checker import check_line
from asp.graph.game_dag import game_dag
from asp.graph.state_graph import build_state_graph
from asp.spec import spec_from_dict
from asp.subassemblies import build_with_units
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


@pytest.mark.parametrize("cap", [1, 10, None])
def test_a_proof_stands_for_a_graph_too_large_to_find_the_stuck_parts(tower, monkeypatch, cap):
    """With the reduction, the derived precedences prove that a holder can never go in alone
    (it touches only its own bearings, which come after it). The round's graph is built up
    to ``PROVED_ROUND_STATES`` states only (``None``: the default, the tower fits); beyond,
    the holder the proof names is grouped with its bearings without any graph of a spec
    that has no complete sequence. Every way finds the same units and plan."""
    import asp.graph.state_graph
    import asp.subassemblies

    if cap is not None:
        monkeypatch.setattr(asp.subassemblies, "PROVED_ROUND_STATES", cap)
    built = []
    real = asp.graph.state_graph.build_state_graph

    def spy(spec, *args, **kwargs):
        try:
            graph = real(spec, *args, **kwargs)
        except ValueError:
            built.append((spec.subassemblies, kwargs.get("check", True), "raised"))
            raise
        built.append((spec.subassemblies, kwargs.get("check", True), graph.n_states))
        return graph

    monkeypatch.setattr(asp.graph.state_graph, "build_state_graph", spy)
    lines = []
    graph = build_with_units(tower_spec(tower), tower, reduce=True, on_unit=lines.append)
    assert sorted(map(sorted, dict(graph.spec.subassemblies).values())) == [
        ["bearing_1a", "bearing_1b", "holder_1"],
        ["bearing_2a", "bearing_2b", "holder_2"],
    ]
    unchecked = [n for units, check, n in built if not check]
    if cap is None:
        assert unchecked and all(n != "raised" for n in unchecked)
    else:  # stopped at the cap: no whole graph without the check
        assert unchecked and all(n == "raised" for n in unchecked)
    assert any("trying subassemblies" in line for line in lines)
    plain = build_with_units(tower_spec(tower), tower)  # the rounds without a proof agree
    assert solve(game_dag(graph)).tct == solve(game_dag(plain)).tct


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
    from asp.graph.checker import plan_operations

    result = pipeline.plan(pipeline.Assembly(tower_spec(tower), tower), time_limit=5)
    doc = result.to_dict()
    assert sorted(map(sorted, doc["subassemblies"].values())) == [
        ["bearing_1a", "bearing_1b", "holder_1"],
        ["bearing_2a", "bearing_2b", "holder_2"],
    ]
    units = [s for s in doc["robust_plan"] if s["operation"] in doc["subassemblies"]]
    # a unit's insertion names the unit and places its real member parts
    assert [s["unit"] for s in units] == [s["operation"] for s in units] and len(units) == 2
    assert [sorted(s["parts"]) for s in units] == [
        sorted(doc["subassemblies"][s["unit"]]) for s in units
    ]
    members = [s for s in doc["robust_plan"] if s["workspace"] not in ("main", None)]
    assert {s["workspace"] for s in members} == set(doc["subassemblies"]) and len(members) == 6
    check_line(result.assembly.spec, tower, plan_operations(doc))


# --------------------------------------------------------------------------- gusseted box

GUSSET_Z = (40.0, 46.0)


def gusseted_box() -> dict:
    """The finger-jointed box with a gusset in each upper corner, as a real laser-cut box
    has: each gusset's two tabs sit in blind pockets of the two walls of its corner, so it
    leaves a wall only straight away from it, through the opposite wall and the gusset
    across; whichever gusset comes last, the other three and the walls hold it."""
    from tests.cad.real_shapes import BOX_L, BOX_W, PANEL, finger_box

    parts = finger_box()
    t, size = PANEL, 20.0
    z0, z1 = GUSSET_Z
    corners = {
        "fl": (t, t, 1, 1),
        "fr": (BOX_L - t, t, -1, 1),
        "bl": (t, BOX_W - t, 1, -1),
        "br": (BOX_L - t, BOX_W - t, -1, -1),
    }
    walls = {"f": "front", "b": "back", "l": "left", "r": "right"}
    pockets: dict[str, list] = {w: [] for w in walls.values()}

    def span(a, b):
        return min(a, b), max(a, b)

    for name, (x, y, sx, sy) in corners.items():
        (xa, xb), (ya, yb) = span(x, x + sx * size), span(y, y + sy * size)
        plate = box((xa, ya, z0), (xb, yb, z1))
        (xa, xb), (ya, yb) = span(x + sx * 6, x + sx * 14), span(y, y - sy * t / 2)
        tab_y = box((xa, ya, z0 + 1), (xb, yb, z1 - 1))  # into the front or back wall
        (xa, xb), (ya, yb) = span(x, x - sx * t / 2), span(y + sy * 6, y + sy * 14)
        tab_x = box((xa, ya, z0 + 1), (xb, yb, z1 - 1))  # into the left or right wall
        parts[f"gusset_{name}"] = union(plate, tab_y, tab_x)
        pockets[walls[name[0]]].append(tab_y)
        pockets[walls[name[1]]].append(tab_x)
    for wall, cut in pockets.items():
        parts[wall] = difference(parts[wall], *cut)
    return parts


@pytest.fixture(scope="module")
def gusset_box():
    return compute_relations(Assembly.from_meshes(gusseted_box()))


def box_spec(rel):
    ops = [{"id": p, "agents": {"H": 2, "R": 3}, "part": p} for p in rel.parts if p != "bottom"]
    return spec_from_dict(
        {
            "parts": [{"id": p, "file": f"{p}.stl"} for p in rel.parts],
            "agents": {"H": {"side": "human"}, "R": {"side": "robot"}},
            "base_part": "bottom",
            "operations": ops,
        },
        source="box.yaml",
    )


def test_the_last_gusset_is_always_held(gusset_box):
    free = {
        p: {d for d in range(6) if gusset_box.tt[k, :, d].sum() == len(gusset_box.parts) - 1}
        for k, p in enumerate(gusset_box.parts)
    }
    assert all(not free[p] for p in free if p.startswith("gusset"))
    with pytest.raises(ValueError, match="every order ends in a dead end"):
        build_state_graph(box_spec(gusset_box), gusset_box)


def test_walls_enter_with_their_gussets(gusset_box):
    lines = []
    graph = build_with_units(box_spec(gusset_box), gusset_box, on_unit=lines.append)
    units = sorted(map(sorted, dict(graph.spec.subassemblies).values()))
    # each gusset goes with one wall of its corner, and both units with parallel walls
    assert units in (
        [["back", "gusset_bl", "gusset_br"], ["front", "gusset_fl", "gusset_fr"]],
        [["gusset_bl", "gusset_fl", "left"], ["gusset_br", "gusset_fr", "right"]],
    )
    assert lines and "subassemblies" in lines[0]
    seqs = graph.sequences(limit=100)
    assert seqs
    for seq in seqs:
        check_line(graph.spec, gusset_box, seq)


def test_gusseted_box_plans_with_defaults(gusset_box):
    from asmplan import pipeline
    from asp.graph.checker import plan_operations

    result = pipeline.plan(pipeline.Assembly(box_spec(gusset_box), gusset_box), time_limit=5)
    doc = result.to_dict()
    assert len(doc["subassemblies"]) == 2
    check_line(result.assembly.spec, gusset_box, plan_operations(doc))


# ------------------------------------------------------------------ the CAD file's hierarchy


def write_glb(path, parts: dict, tree: dict) -> None:
    """A glTF in metres of ``parts`` (mm) under the product node ``Product``; ``tree`` maps
    a group node to its children (parts or groups), nested as a CAD product tree. Y-up,
    as glTF's specification has it (+z of the parts becomes +y)."""
    import numpy as np
    import trimesh

    y_up = trimesh.transformations.rotation_matrix(-np.pi / 2, (1, 0, 0))

    scene = trimesh.Scene()
    scene.graph.update(frame_from="world", frame_to="Product")

    def add(name, parent):
        if name in tree:
            scene.graph.update(frame_from=parent, frame_to=name)
            for child in tree[name]:
                add(child, name)
        else:
            scene.add_geometry(
                parts[name].copy().apply_transform(y_up).apply_scale(0.001),
                node_name=name,
                geom_name=f"mesh_{name}",
                parent_node_name=parent,
            )

    for name in tree["Product"]:
        add(name, "Product")
    scene.export(str(path))


TOWER_TREE = {
    "Product": ["Frame", "Level 1", "Level 2"],
    "Frame": ["base", "Rods"],
    "Rods": ["rod_1", "rod_2"],
    "Level 1": ["holder_1", "bearing_1a", "bearing_1b"],
    "Level 2": ["holder_2", "bearing_2a", "bearing_2b"],
}


def test_the_files_sub_assemblies_become_units(tmp_path):
    from asmplan import pipeline
    from asp.graph.checker import plan_operations

    write_glb(tmp_path / "tower.glb", rod_tower(), TOWER_TREE)
    lines = []
    result = pipeline.plan(tmp_path / "tower.glb", time_limit=5, on_step=lines.append)
    doc = result.to_dict()
    units = {u["id"]: u for u in doc["units"]}
    assert {u: units[u]["used"] for u in units} == {
        "frame": False,
        "rods": False,
        "level_1": True,
        "level_2": True,
    }
    assert (
        units["frame"]["reason"] == "it holds the base part base, placed first in the main assembly"
    )
    assert units["rods"]["reason"].startswith("it cannot be built on its own: with rod_1 placed")
    assert all(u["source"] == "cad" for u in units.values())
    assert sorted(doc["subassemblies"]) == ["level_1", "level_2"]
    assert any("sub-assembly level_1 [bearing_1a, bearing_1b, holder_1]: built" in x for x in lines)
    check_line(result.assembly.spec, result.assembly.relations, plan_operations(doc))


def test_init_writes_the_units_it_uses(tmp_path):
    from typer.testing import CliRunner

    from asmplan.cli import app

    write_glb(tmp_path / "tower.glb", rod_tower(), TOWER_TREE)
    out = tmp_path / "work" / "assembly.yaml"
    result = CliRunner().invoke(app, ["init", str(tmp_path / "tower.glb"), "-o", str(out)])
    assert result.exit_code == 0, result.output
    text = out.read_text()
    assert "\nsubassemblies:\n" in text
    assert "\n  level_1: [bearing_1a, bearing_1b, holder_1]\n" in text
    assert "\n#   frame: [base, rod_1, rod_2]   # not used: it holds the base part" in text


def test_a_sub_assembly_that_leaves_no_sequence_is_given_up(tmp_path):
    """A corner of the gusseted box (two walls) can be built and goes in from above, but
    then the corner's gusset can go in with neither wall: the plan gives the corner up and
    finds the walls with their gussets instead."""
    from asmplan import pipeline
    from asp.graph.checker import plan_operations
    from asp.subassemblies import GIVEN_UP

    parts = gusseted_box()
    others = [p for p in parts if p not in ("front", "left")]
    write_glb(
        tmp_path / "box.glb", parts, {"Product": ["Corner", *others], "Corner": ["front", "left"]}
    )
    result = pipeline.plan(tmp_path / "box.glb", time_limit=5)
    doc = result.to_dict()
    units = {u["id"]: u for u in doc["units"]}
    assert units["corner"]["used"] is False and units["corner"]["reason"] == GIVEN_UP
    assert [u["source"] for u in units.values() if u["used"]] == ["automatic", "automatic"]
    check_line(result.assembly.spec, result.assembly.relations, plan_operations(doc))


def pairs_spec(n_units: int, generated: bool = False):
    """A base and ``n_units`` pairs of parts, each pair a unit (no geometry)."""
    parts = ["base"] + [f"p{k}{s}" for k in range(n_units) for s in "ab"]
    ops = [{"id": p, "agents": {"H": 1, "R": 1}, "part": p} for p in parts[1:]]
    data = {
        "parts": [{"id": p, "file": f"{p}.stl"} for p in parts],
        "agents": {"H": {"side": "human"}, "R": {"side": "robot"}},
        "base_part": "base",
        "operations": ops,
        "subassemblies": {f"u{k}": [f"p{k}a", f"p{k}b"] for k in range(n_units)},
    }
    spec = spec_from_dict(data, source="pairs.yaml")
    if generated:
        from dataclasses import replace

        spec = replace(spec, generated=True)
    return spec


def test_many_units_are_built_one_after_another():
    from asp.subassemblies import MAX_WORKSPACE_PRODUCT, built_in_turn

    few = pairs_spec(2)
    assert MAX_WORKSPACE_PRODUCT >= 3**2 and built_in_turn(few) is few
    many = pairs_spec(5)  # 3**5 = 243 partial builds at once: too many
    turned = built_in_turn(many)
    assert turned.operation("p1a").after == ("p0a", "p0b")
    assert turned.operation("p4b").after == ("p3a", "p3b")
    assert turned.operation("p0a").after == ()
    free, chained = build_state_graph(many), build_state_graph(turned)
    assert chained.n_states < free.n_states
    for seq in chained.sequences(limit=20):
        check_line(turned, None, seq)


def test_a_generated_spec_holds_a_unit_nothing_outside_holds_up():
    from types import SimpleNamespace

    import numpy as np

    from asp.subassemblies import hold_unsupported_units

    spec = pairs_spec(2, generated=True)
    parts = list(spec.part_ids)
    sp = np.zeros((5, 5, 6), dtype=bool)
    k = {p: i for i, p in enumerate(parts)}
    sp[k["p0a"], k["base"], 5] = True  # unit u0 rests on the base; u1 only on itself
    sp[k["p1b"], k["p1a"], 5] = True
    rel = SimpleNamespace(parts=parts, sp=sp)
    held = hold_unsupported_units(spec, rel)
    assert not held.operation("u0").held and held.operation("u1").held
    user = pairs_spec(2)
    assert hold_unsupported_units(user, rel) is user  # a user's spec is never changed


def capped_shaft() -> dict:
    """A base, a stepped shaft standing on it, a ring resting on the shaft's shoulder and a
    cap on the shaft's top above the ring: the ring goes in after the shaft, before the cap."""
    return {
        "base": box((-20, -20, 0), (20, 20, 5)),
        "shaft": union(cylinder(3, 5, 10, 32), cylinder(1.5, 10, 22, 24)),
        "ring": annulus(1.5, 8, 10, 12, 24, 48),
        "cap": cylinder(4, 22, 24, 32),
    }


def test_a_unit_the_derived_precedences_refute_is_given_up_before_building(tmp_path):
    """The file groups the shaft with its cap: built and inserted as one body, the cap would
    shut the ring out, which can rest on nothing but the shaft. The derived precedences
    prove it without a state graph; the unit is given up, with the proof on stderr."""
    from asmplan import pipeline
    from asp.graph.checker import plan_operations
    from asp.subassemblies import GIVEN_UP, refuted_units

    write_glb(
        tmp_path / "shaft.glb",
        capped_shaft(),
        {"Product": ["base", "Stack", "ring"], "Stack": ["shaft", "cap"]},
    )
    assembly = pipeline.load(tmp_path / "shaft.glb")
    lines = []
    assert refuted_units(assembly.spec, assembly.relations, on_unit=lines.append) == {"stack"}
    assert len(lines) == 1
    assert lines[0].startswith("the file's sub-assembly stack: no complete sequence with it")
    assert re.search(r"as one unit \((unit stack|part ring) .+\); planned without it$", lines[0])
    result = pipeline.plan(tmp_path / "shaft.glb", time_limit=5)
    doc = result.to_dict()
    units = {u["id"]: u for u in doc["units"]}
    assert units["stack"]["used"] is False and units["stack"]["reason"] == GIVEN_UP
    assert doc["subassemblies"] == {}
    check_line(result.assembly.spec, result.assembly.relations, plan_operations(doc))


def capped_block():
    """A block with two pockets and a lid (mm, z up) into which two flanged pegs are pressed
    from below, their flanges under the lid standing in the block's pockets: built on its
    own right side up, the lid's unit needs a peg held (one stands on the bench, the lid on
    its flange, nothing under the other), upside down (lid on the bench) both pegs rest on
    the lid."""
    from tests.cad.real_shapes import box, cylinder, difference, union

    xys = [(-15.0, 0.0), (15.0, 0.0)]
    parts = {
        "block": difference(
            box((-30, -20, 0), (30, 20, 20)), *(cylinder(5.5, 12, 21, 40, xy) for xy in xys)
        ),
        "lid": difference(
            box((-30, -20, 20), (30, 20, 30)), *(cylinder(3, 19, 31, 32, xy) for xy in xys)
        ),
    }
    for k, xy in enumerate(xys, 1):
        parts[f"peg_{k}"] = union(cylinder(3, 20, 30, 32, xy), cylinder(5, 12, 20, 40, xy))
    return parts


def test_a_files_sub_assembly_built_upside_down_passes_both_checkers(tmp_path):
    """The file's sub-assembly [lid, peg_1, peg_2] is built upside down in its workspace
    (:mod:`asp.fromcad.orientation`), turned over and put on the block; the relations checker and
    the mesh replay both follow the workspace's gravity from ``plan.json``."""
    from tests.asmplan.checked import plan_and_check

    write_glb(
        tmp_path / "capped.glb",
        capped_block(),
        {"Product": ["block", "Cap"], "Cap": ["lid", "peg_1", "peg_2"]},
    )
    plan = plan_and_check(tmp_path / "capped.glb", tmp_path / "out", "--time-limit", "5")
    assert plan["subassemblies"] == {"cap": ["lid", "peg_1", "peg_2"]}
    spaces = {w["id"]: w for w in plan["workspaces"]}
    assert (spaces["main"]["gravity"], spaces["cap"]["gravity"]) == ("-y", "+y")
    assert spaces["cap"]["parts"][0] == "lid"
    steps = [i for s in plan["robust_plan"] for i in s["insertions"]]
    assert not any(i["held"] for i in steps)  # the lid rests on the block
    into = next(i for i in steps if i["unit"] == "cap")
    assert into["insert_along"] == "-y"
