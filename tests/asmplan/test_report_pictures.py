"""The report's pictures a person reads: Gantt charts legible at the size shown, with a
legend and units; step pictures with a camera on the part placed, an arrow for each way in
and the parts by name."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from asmplan.report.gantt import (
    GANTT_DPI,
    LABEL_PT,
    SHOWN_WIDTH,
    draw_gantt,
    label_fits,
    plot_gantt,
)
from asmplan.report.steps import (
    DEFAULT_VIEW,
    MAX_ZOOM,
    camera_angles,
    part_label,
    step_title,
    step_view,
)
from asp.concurrent.describe import Bar

BARS = [
    Bar("H", "1.1", 0, 2),
    Bar("H", "1.2", 2, 17, deviation=True),
    Bar("R2", "1.3", 2, 10),
    Bar("R1", "1.6", 29, 39),
]


@pytest.mark.parametrize(
    ("label", "bar", "span", "fits"),
    [
        ("1.2", 15, 215, True),  # 0.69 in for 0.36 in of text
        ("1.1", 2, 215, False),  # 0.09 in
        ("screw_cover_12", 10, 215, False),
        ("screw_cover_12", 60, 215, True),
        ("a", 1, 10, True),
    ],
)
def test_a_label_is_written_in_its_bar_only_where_it_fits(label, bar, span, fits):
    assert label_fits(label, bar, span) is fits


def test_the_gantt_chart_has_a_legend_units_and_only_labels_that_fit():
    from matplotlib.figure import Figure

    ax = Figure(figsize=(SHOWN_WIDTH, 3)).subplots()
    drawn = draw_gantt(ax, BARS, makespan=215, unit="s")
    assert drawn["legend"] == ["H", "R1", "R2", "deviation", "makespan 215 s"]
    assert drawn["labels"] == ["1.2", "1.3", "1.6"]  # 1.1 (2 s of 215) has no room
    assert ax.get_xlabel() == "time (s)"
    assert all(t.get_fontsize() >= LABEL_PT for t in ax.texts)
    plain = draw_gantt(Figure().subplots(), BARS[2:])
    assert plain["legend"] == ["R1", "R2"]  # no deviation, no makespan: no entry for them


def test_the_gantt_png_is_drawn_at_the_size_shown_at_twice_the_pixels(tmp_path):
    path = plot_gantt(BARS, tmp_path / "g.png", makespan=215, title="t")
    width, height = Image.open(path).size
    assert width == SHOWN_WIDTH * GANTT_DPI  # the report shows it 1150 px wide: text at size
    assert height < width / 2


@pytest.mark.parametrize(
    ("free", "check"),
    [
        ("+z", lambda e, a: e > 30),  # put in from above: the camera looks down
        ("-z", lambda e, a: e < -30),  # from below (a held part): it looks up
        ("+x", lambda e, a: abs(e) < 45 and np.cos(np.radians(a)) > 0.6),
        ("-x", lambda e, a: abs(e) < 45 and np.cos(np.radians(a)) < -0.6),
        ("+y", lambda e, a: abs(e) < 45 and np.sin(np.radians(a)) > 0.6),
        ("-y", lambda e, a: abs(e) < 45 and np.sin(np.radians(a)) < -0.6),
    ],
)
def test_the_camera_stands_on_the_side_the_part_comes_from(free, check):
    elev, azim = camera_angles(free)
    assert check(elev, azim), (free, elev, azim)
    assert abs(elev) < 80  # never straight down an axis: the picture keeps its depth
    assert camera_angles(None) == DEFAULT_VIEW


def _box(lo, hi):
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    corners = np.array(
        [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    )
    return corners, np.array([[0, 1, 2]])


def test_a_small_part_put_in_from_above_is_framed_with_a_downward_arrow():
    meshes = {"block": _box((0, 0, 0), (100, 100, 20)), "peg": _box((45, 45, 20), (51, 51, 30))}
    step = {
        "operation": "2",
        "agent": "H",
        "parts": ["peg"],
        "insertions": [{"parts": ["peg"], "free_along": "+z", "insert_along": "-z"}],
    }
    view = step_view(step, meshes, np.zeros(3), np.array([100.0, 100.0, 40.0]))
    assert np.allclose(view.center, [48, 48, 25])
    assert view.zoom == MAX_ZOOM  # a 10 mm peg in a 100 mm product: as close as it goes
    ((start, vector),) = view.arrows
    assert vector[2] < 0 and np.allclose(vector[:2], 0)  # along -z
    assert start[2] > 30 and (start + vector)[2] > 30  # comes from above, ends at its top
    assert np.allclose(start[:2], [48, 48])
    assert view.ways == ["-z"] and view.elev > 30
    first = step_view(
        {**step, "insertions": [{"parts": ["peg"], "insert_along": None}]},
        meshes,
        np.zeros(3),
        np.array([100.0, 100.0, 40.0]),
    )
    assert first.arrows == [] and (first.elev, first.azim) == DEFAULT_VIEW


def test_titles_name_the_parts():
    names = {"PC": "Plastic case", "VT1": "", "b": "b"}
    assert part_label("PC", names) == "Plastic case (PC)"
    assert part_label("VT1", names) == "VT1" and part_label("b", names) == "b"
    title = step_title({"operation": "1.4", "agent": "H", "parts": ["PC", "VT1"]}, names, ["-z"])
    assert title.replace("\n", " ") == "1.4 by H: Plastic case (PC), VT1 (in along\u00a0-z)"
