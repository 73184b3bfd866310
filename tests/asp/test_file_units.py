"""The CAD file's groups that the derived precedences prove can never be one unit are not
written or kept as units (asp/subassemblies.py: file_units, refuted_reasons)."""

from __future__ import annotations

import numpy as np
import trimesh

from tests.cad.real_shapes import box, cylinder, difference
from tests.cad.test_subassemblies import write_glb


def pin_along_x(radius: float, x0: float, x1: float, z: float) -> trimesh.Trimesh:
    """A pin along x from ``x0`` to ``x1`` at height ``z`` (mm)."""
    turn = trimesh.transformations.rotation_matrix(np.pi / 2, (0, 1, 0))  # z -> x
    pin = cylinder(radius, -x1, -x0, 24).apply_transform(turn)
    return pin.apply_translation((0, 0, z))


def piston_on_rod() -> dict:
    """A crankcase, a connecting rod standing on it, a piston whose slot takes the rod's
    top (it rests on the rod) and a pin through the piston's cheeks and the rod's eye."""

    def eye():
        return pin_along_x(2.0, -20, 20, 34)

    return {
        "crankcase": box((-30, -30, 0), (30, 30, 5)),
        "rod": difference(box((-4, -4, 5), (4, 4, 40)), eye()),
        "piston": difference(
            box((-10, -10, 28), (10, 10, 50)), box((-4, -4, 27), (4, 4, 40)), eye()
        ),
        "pin": pin_along_x(2.0, -10, 10, 34),
    }


PISTON_TREE = {"Product": ["crankcase", "rod", "Piston group"], "Piston group": ["piston", "pin"]}


def test_the_scene_is_a_pin_through_the_rod():
    parts = piston_on_rod()
    assert all(m.is_watertight for m in parts.values())
    assert parts["pin"].bounds.tolist() == [[-10, -2, 32], [10, 2, 36]]


def test_init_writes_no_unit_that_can_never_go_in(tmp_path):
    """The file groups the piston with its pin but not the rod the pin passes through: the
    group can be built (pin into piston) and touches the rod, so it passes the unit checks,
    but inserted as one body it is blocked along every direction by the rod, on which alone
    it rests (so the rod is there first). ``init`` writes it commented with the proof and
    says so on stderr; the spec it writes plans, the pin going in after piston and rod."""
    from typer.testing import CliRunner

    from asmplan import pipeline
    from asmplan.cli import app
    from asp.graph.checker import check_line, plan_operations

    write_glb(tmp_path / "engine.glb", piston_on_rod(), PISTON_TREE)
    out = tmp_path / "work" / "assembly.yaml"
    result = CliRunner().invoke(app, ["init", str(tmp_path / "engine.glb"), "-o", str(out)])
    assert result.exit_code == 0, result.output
    text = out.read_text()
    assert "\nsubassemblies:" not in text
    proof = "unit piston_group is blocked along every direction by parts that must be there"
    assert (
        "\n#   piston_group: [pin, piston]   # not used: no complete sequence with it as one "
        f"unit ({proof}" in text
    )
    said = [line for line in result.output.splitlines() if "piston_group" in line]
    assert len(said) == 1 and said[0].startswith("the file's sub-assembly piston_group: no")
    assert said[0].endswith("; planned without it")

    planned = pipeline.plan(out, time_limit=5)
    doc = planned.to_dict()
    assert doc["subassemblies"] == {}
    line = plan_operations(doc)
    check_line(planned.assembly.spec, planned.assembly.relations, line)
    parts = [planned.assembly.spec.operation(o).parts[0] for o in line]
    assert parts.index("pin") > max(parts.index("piston"), parts.index("rod"))


def test_the_plan_of_the_file_gives_the_group_up_with_the_same_proof(tmp_path):
    from asmplan import pipeline
    from asp.subassemblies import cad_units, file_units, refuted_reasons

    write_glb(tmp_path / "engine.glb", piston_on_rod(), PISTON_TREE)
    assembly = pipeline.load(tmp_path / "engine.glb")
    spec, relations = assembly.spec, assembly.relations
    assert [u.used for u in cad_units(spec, relations)] == [True]  # the checks pass it
    reasons = refuted_reasons(spec, relations)
    assert list(reasons) == ["piston_group"]
    (decided,) = file_units(spec, relations)
    assert not decided.used and "piston_group is blocked along every direction" in decided.reason


def test_a_proved_round_too_large_to_build_gives_the_files_units_up(monkeypatch):
    """The tower's first holder can never go in alone, whatever the file groups (the file's
    second level is a unit): the derived precedences prove it. When the round's automatic
    units come to nothing and its whole graph exceeds the state limit, the file's units
    are given up and the error is the proof, not the state limit."""
    from dataclasses import replace

    import pytest

    import asp.graph.state_graph
    import asp.subassemblies
    from asp.errors import InfeasibleAssembly, StateLimit
    from cad import Assembly, compute_relations
    from tests.cad.test_subassemblies import rod_tower, tower_spec

    relations = compute_relations(Assembly.from_meshes(rod_tower()))
    level_2 = ("holder_2", "bearing_2a", "bearing_2b")
    spec = replace(tower_spec(relations), generated=True, hierarchy=(("level_2", level_2),))
    real = asp.graph.state_graph.build_state_graph

    def over_the_limit(spec, *args, **kwargs):
        if kwargs.get("check", True) is False:
            raise StateLimit(f"{spec.source}: the state graph exceeds the limit")
        return real(spec, *args, **kwargs)

    monkeypatch.setattr(asp.graph.state_graph, "build_state_graph", over_the_limit)
    monkeypatch.setattr(asp.subassemblies, "_new_units", lambda *args, **kwargs: None)
    lines = []
    with pytest.raises(InfeasibleAssembly, match="holder_1"):
        asp.subassemblies.build_with_units(
            spec, relations, hierarchy=True, reduce=True, on_unit=lines.append
        )
    assert any(line.startswith("the file's sub-assembly level_2: ") for line in lines)


def collared_tower():
    """The rod tower (each holder touches only its two flanged bearings, so it can only go
    in with them) with a collar on each lower bearing's flange; the file groups each lower
    bearing with its collar (buildable, insertable: the unit checks pass both)."""
    from tests.cad.real_shapes import annulus
    from tests.cad.test_subassemblies import LEVELS, RODS, rod_tower

    parts = rod_tower()
    z = LEVELS["1"]
    for side, x in zip("ab", RODS, strict=True):
        parts[f"collar_1{side}"] = annulus(4, 7, z + 8, z + 10, 40, 48, (x, 0))
    return parts


COLLAR_UNITS = (
    ("bearing_a", ("bearing_1a", "collar_1a")),
    ("bearing_b", ("bearing_1b", "collar_1b")),
)


def test_init_gives_up_the_file_units_a_loose_part_can_only_go_in_with():
    """The lower holder's one host group is its two bearings, each in a unit of the file:
    with those units fixed no automatic unit can take the holder in, so the spec ``init``
    writes would have no plan. ``file_units`` gives both up with the proof and the hosts
    (the rule the plan's rounds apply, ``_units_in_the_way``); the spec without them
    plans, the holders going in with their bearings."""
    from dataclasses import replace

    import pytest

    from asp.errors import InfeasibleAssembly
    from asp.subassemblies import build_with_units, cad_units, file_units
    from cad import Assembly, compute_relations
    from tests.cad.test_subassemblies import tower_spec

    relations = compute_relations(Assembly.from_meshes(collared_tower()))
    spec = replace(tower_spec(relations), generated=True, hierarchy=COLLAR_UNITS)
    assert [u.used for u in cad_units(spec, relations)] == [True, True]  # the checks pass them
    with pytest.raises(InfeasibleAssembly, match="part holder_1"):  # the spec with them fixed
        build_with_units(tower_spec(relations, {u: list(ms) for u, ms in COLLAR_UNITS}), relations)

    said: list[str] = []
    decided = file_units(spec, relations, on_unit=said.append)
    assert [u.used for u in decided] == [False, False]
    proof = "part holder_1 (operation holder_1) is blocked along every direction"
    hosts = "it can go in only with bearing_1a, bearing_1b holding it"
    assert said == [
        f"the file's sub-assemblies bearing_a, bearing_b: no complete sequence with them as "
        f"units ({proof} by parts that must be there before it; {hosts}); planned without them"
    ]
    assert all(u.reason.startswith("no complete sequence with them as units (") for u in decided)
    graph = build_with_units(tower_spec(relations), relations)
    assert sorted(map(sorted, dict(graph.spec.subassemblies).values())) == [
        ["bearing_1a", "bearing_1b", "holder_1"],
        ["bearing_2a", "bearing_2b", "holder_2"],
    ]
