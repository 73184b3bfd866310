"""Node names that carry HTML stay text: ``init``, ``plan`` and ``report.html``.

A CAD file's node names are whatever its author (or a downloaded model) wrote. A glTF built
here names its parts with tags, attribute breakouts and entities; ``init`` must write a spec
that reads back (ids slugged), ``plan`` must plan it, ``plan.json`` must keep the names as
they were read, and ``report.html`` must show them as text: parsed with
:mod:`html.parser`, no element or attribute of the page comes from a name.
"""

from __future__ import annotations

import json
import re
from html.parser import HTMLParser
from pathlib import Path

import trimesh
from typer.testing import CliRunner

from asmplan.cli import app
from asp.spec import load_spec
from cad.scene import display_name
from tests.cad import shapes

EVIL = (
    "<script>alert(1)</script>",
    '"><img src=x onerror=alert(1)>',
    "<img src=x onerror=alert(2)>",
    "Tom &amp; Jerry's &lt;b&gt;",
    "</table></style><svg onload=alert(3)>",
    '<i" onmouseover="alert(4)',
)
PAYLOAD = ("alert(", "onerror", "onload", "onmouseover")


def write_glb(path: Path) -> Path:
    """One box per name, stacked along z (the first the widest), in metres, under a tagged
    product node."""
    scene = trimesh.Scene()
    scene.graph.update(frame_from="world", frame_to="<b>Product</b>")
    for k, name in enumerate(EVIL):
        half = 20 - 3 * k
        mesh = shapes.box_between((-half, -half, 5 * k), (half, half, 5 * k + 5))
        scene.add_geometry(
            mesh.apply_scale(0.001),
            node_name=name,
            geom_name=f"Mesh_{k}",
            parent_node_name="<b>Product</b>",
        )
    scene.export(path)
    return path


class Page(HTMLParser):
    """The elements (tag, attributes), the text and the scripts' text of a page."""

    def __init__(self) -> None:
        super().__init__()  # character references converted: the text as a reader sees it
        self.elements: list[tuple[str, dict]] = []
        self.text: list[str] = []
        self.scripts: list[str] = []
        self._in_script = False

    def handle_starttag(self, tag, attrs):
        self.elements.append((tag, dict(attrs)))
        if tag == "script":
            self._in_script = True
            self.scripts.append("")

    def handle_endtag(self, tag):
        if tag == "script":
            self._in_script = False

    def handle_data(self, data):
        if self._in_script:
            self.scripts[-1] += data
        else:
            self.text.append(data)


def assert_names_are_text(report: Path, names: list[str]) -> None:
    """No element of ``report`` comes from a name, and every name is in its text."""
    page = Page()
    page.feed(report.read_text(encoding="utf-8"))
    page.close()
    for tag, attrs in page.elements:
        assert tag not in ("svg", "b"), (tag, attrs)  # only the names have these
        assert not [a for a in attrs if a.startswith("on")], (tag, attrs)
        if tag == "img":  # the page's own pictures are inline PNGs
            assert (attrs.get("src") or "").startswith("data:image/png;base64,"), attrs
    for script in page.scripts:  # the page's own scripts, if any
        assert not [p for p in PAYLOAD if p in script], script
    text = "".join(page.text)
    for name in names:  # shown as text, its entities literal
        assert name in text, name
    assert "Tom &amp; Jerry's &lt;b&gt;" in names


def test_html_in_node_names_is_text_through_init_plan_and_report(tmp_path):
    source = write_glb(tmp_path / "evil.glb")
    spec_file = tmp_path / "assembly.yaml"
    runner = CliRunner()
    result = runner.invoke(app, ["init", str(source), "-o", str(spec_file)])
    assert result.exit_code == 0, result.output

    spec = load_spec(spec_file)
    ids = [p.id for p in spec.parts]
    assert len(set(ids)) == len(EVIL)
    assert all(re.fullmatch(r"[a-z][a-z0-9_]*", i) for i in ids), ids
    names = {p.id: p.name for p in spec.parts}
    assert sorted(names.values()) == sorted(display_name(n) for n in EVIL)
    assert "<script>alert(1)</script>" in names.values()

    out = tmp_path / "plan"
    result = runner.invoke(app, ["plan", str(spec_file), "-o", str(out)])
    assert result.exit_code == 0, result.output
    doc = json.loads((out / "plan.json").read_text(encoding="utf-8"))
    assert {p["id"]: p["name"] for p in doc["parts"]} == names

    assert_names_are_text(out / "report.html", list(names.values()))
    redrawn = tmp_path / "redrawn.html"
    result = runner.invoke(app, ["report", str(out), "-o", str(redrawn)])
    assert result.exit_code == 0, result.output
    assert_names_are_text(redrawn, list(names.values()))
