"""``overlap_ok:``: pairs a file overlaps as modelled, all accepted by one spec line.

Scene files of purchased parts and visual assets overlap for real (Khronos'
``2CylinderEngine.glb``: 12 pairs; the Cesium milk truck's axles drawn through its body
shell). The error names every pair and the one line ``overlap_ok: [[a, b], ...]`` that
takes each as touching; ``asmplan init`` writes that line commented; with it the product
plans, a pair nested too deep to part passing *through* (touching, never blocking).
Geometry built here: blocks sunk into a base, and a block drawn inside another.
"""

from __future__ import annotations

import re

import pytest
from typer.testing import CliRunner

import cad
from asmplan.cli import app
from asp.spec import load_spec
from cad.errors import GeometryError
from tests.asmplan.checked import plan_and_check
from tests.cad import shapes


def sunk_blocks() -> dict:
    """A base 60 x 20 x 10 mm with three blocks sunk 1 mm into its top face."""
    out = {"base": shapes.box_between((0, 0, 0), (60, 20, 10))}
    for k in range(3):
        x = 5.0 + 20.0 * k
        out[f"block_{k}"] = shapes.box_between((x, 5, 9), (x + 10, 15, 19))
    return out


def test_every_pair_is_in_the_one_line_the_error_names():
    assembly = cad.Assembly.from_meshes(sunk_blocks())
    with pytest.raises(GeometryError) as info:
        cad.compute_relations(assembly)
    message = str(info.value)
    assert message.startswith("3 pairs of parts interpenetrate") and "\n" not in message
    line = re.search(r"`(overlap_ok: [^`]*)`", message).group(1)
    assert line == "overlap_ok: [[base, block_0], [base, block_1], [base, block_2]]"
    assert info.value.pairs == (("base", "block_0"), ("base", "block_1"), ("base", "block_2"))


def test_accepted_pairs_touch_and_the_others_still_fail():
    assembly = cad.Assembly.from_meshes(sunk_blocks())
    pairs = [("block_0", "base"), ("base", "block_1"), ("base", "block_2")]
    relations = cad.compute_relations(assembly, overlap_ok=pairs)
    ids = list(relations.parts)
    base = ids.index("base")
    for k in range(3):
        b = ids.index(f"block_{k}")
        assert relations.tc[b, base].any()  # touching
        assert not relations.tt[b, base].all()  # parted by erosion, not passing through
    assert {f[0] for f in relations.fits} == {"block_0", "block_1", "block_2"}
    with pytest.raises(GeometryError, match=r"`overlap_ok: \[\[base, block_2\]\]`"):
        cad.compute_relations(assembly, overlap_ok=pairs[:2])


def test_a_pair_nested_too_deep_passes_through():
    """A block drawn wholly inside another (an axle in a visual body shell): accepted, the
    pair touches, rests on each other and neither blocks the other."""
    meshes = {
        "body": shapes.box_between((0, 0, 0), (40, 40, 40)),
        "core": shapes.box_between((10, 10, 10), (30, 30, 30)),
    }
    assembly = cad.Assembly.from_meshes(meshes)
    relations = cad.compute_relations(assembly, overlap_ok=[("body", "core")])
    assert relations.through == (("body", "core"),) and relations.fits == ()
    assert relations.tt[0, 1].all() and relations.tt[1, 0].all()
    assert relations.tc[0, 1].all() and relations.sp[1, 0].all()


def test_init_writes_the_line_commented_and_with_it_the_product_plans(tmp_path):
    source = tmp_path / "sunk"
    source.mkdir()
    for name, mesh in sunk_blocks().items():
        mesh.export(source / f"{name}.stl")
    refused = CliRunner().invoke(app, ["plan", str(source), "-o", str(tmp_path / "no")])
    assert refused.exit_code == 2 and "overlap_ok: [[base, block_0]" in refused.stderr
    spec_file = source / "assembly.yaml"
    made = CliRunner().invoke(app, ["init", str(source), "-o", str(spec_file)])
    assert made.exit_code == 0, made.output
    text = spec_file.read_text()
    assert "# overlap_ok: [[base, block_0], [base, block_1], [base, block_2]]" in text
    assert load_spec(spec_file).overlap_ok == ()  # commented: the user decides
    spec_file.write_text(text.replace("# overlap_ok:", "overlap_ok:"))
    assert len(load_spec(spec_file).overlap_ok) == 3
    doc = plan_and_check(source, tmp_path / "out")
    assert len(doc["geometry"]["fits"]) == 3 and "through" not in doc["geometry"]


def test_overlap_ok_refuses_what_is_not_pairs_of_parts(tmp_path):
    from asp.cad_keys import parse_overlap_ok

    assert parse_overlap_ok(["a", "b"], {"a", "b"}, "s.yaml") == (("a", "b"),)
    for bad, why in (
        ([["a"]], "expected pairs"),
        ([["a", "z"]], "unknown part 'z'"),
        ([["a", "a"]], "a pair of one part"),
    ):
        with pytest.raises(ValueError, match=why):
            parse_overlap_ok(bad, {"a", "b"}, "s.yaml")


def caged_cube() -> dict:
    """A block sunk 1 mm into a base (an overlap), and a cage on the base with a cube shut
    in its closed cavity, resting on its floor (a pair that locks once placed)."""
    import trimesh

    cavity = shapes.box_between((34, 6, 12), (46, 14, 22))
    cavity.invert()
    cage = trimesh.util.concatenate([shapes.box_between((30, 2, 10), (50, 18, 26)), cavity])
    return {
        "base": shapes.box_between((0, 0, 0), (60, 20, 10)),
        "block": shapes.box_between((5, 5, 9), (15, 15, 19)),
        "cage": cage,
        "cube": shapes.box_between((37, 8, 12), (43, 12, 16)),
    }


def test_one_message_names_every_line_the_file_needs_and_with_them_it_plans(tmp_path):
    """The overlap error is computed on with its pairs accepted: the pairs that then lock
    each other and the ``flex:`` line (the smaller of each pair) are in the same message,
    ``init`` writes both lines commented, and with both uncommented the product plans."""
    source = tmp_path / "caged"
    source.mkdir()
    for name, mesh in caged_cube().items():
        mesh.export(source / f"{name}.stl")
    with pytest.raises(GeometryError) as info:
        cad.compute_relations(cad.load_assembly(source))
    message = str(info.value)
    assert "`overlap_ok: [[base, block]]`" in message and "\n" not in message
    assert "cage and cube block each other along every direction" in message
    assert "`flex: [cube]`" in message and info.value.flex == ("cube",)
    refused = CliRunner().invoke(app, ["plan", str(source), "-o", str(tmp_path / "no")])
    assert refused.exit_code == 2 and "`flex: [cube]`" in refused.stderr
    spec_file = source / "assembly.yaml"
    made = CliRunner().invoke(app, ["init", str(source), "-o", str(spec_file)])
    assert made.exit_code == 0, made.output
    text = spec_file.read_text()
    assert "# overlap_ok: [[base, block]]" in text and "# flex: [cube]" in text
    spec_file.write_text(text.replace("# overlap_ok:", "overlap_ok:").replace("# flex:", "flex:"))
    planned = CliRunner().invoke(app, ["plan", str(spec_file), "-o", str(tmp_path / "out")])
    assert planned.exit_code == 0, planned.output


def test_init_decides_the_file_groups_with_its_own_flex_line_applied(tmp_path):
    """The FM1 satellite's XBee with its adapter is a unit only while the XBee's pins flex
    in: ``init`` judged the file's groups without the ``flex:`` line it writes commented,
    so the group was written commented and the spec, its lines uncommented, never planned.
    The groups are now judged as the spec plans once the lines are uncommented: the
    relations given to the decision let the flexing cube pass its cage."""
    import numpy as np
    import trimesh

    from asp.fromcad.generate import spec_text

    meshes = caged_cube()
    scene = trimesh.Scene()
    scene.graph.update(frame_to="module", frame_from=scene.graph.base_frame)
    for name, mesh in meshes.items():
        parent = "module" if name in ("block", "cage") else scene.graph.base_frame
        scene.add_geometry(mesh, node_name=name, geom_name=name, parent_node_name=parent)
    source = tmp_path / "caged.glb"
    scene.export(source)
    seen = []

    def decide(spec, relations):
        seen.append((spec.flex, relations))
        return ()

    text = spec_text(source, tmp_path, decide_units=decide)
    assert "# flex: [cube]" in text
    ((flex, relations),) = seen
    ids = list(relations.parts)
    assert flex == ("cube",)
    assert relations.tt[ids.index("cube"), ids.index("cage")].all()  # it flexes past
    assert not np.asarray(relations.tt)[ids.index("cage"), ids.index("cube")].any()
