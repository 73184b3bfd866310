"""Property tests: random axis-aligned boxes against an independent box oracle."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from cad import Assembly, compute_relations, unit_scale
from tests.cad import shapes

OPPOSITE = [1, 0, 3, 2, 5, 4]


@st.composite
def box_layout(draw):
    """2-4 integer boxes on a small grid, interiors pairwise disjoint."""
    count = draw(st.integers(2, 4))
    boxes = []
    for _ in range(count):
        lo = np.array([draw(st.integers(0, 6)) for _ in range(3)], dtype=float)
        size = np.array([draw(st.integers(1, 3)) for _ in range(3)], dtype=float)
        boxes.append((lo, lo + size))
    for a in range(count):
        for b in range(a + 1, count):
            (alo, ahi), (blo, bhi) = boxes[a], boxes[b]
            assume(not np.all((alo < bhi) & (blo < ahi)))
    return boxes


def oracle(boxes):
    """Exact TC and TT of disjoint axis-aligned boxes (touching allowed)."""
    n = len(boxes)
    tc = np.zeros((n, n, 6), dtype=bool)
    tt = np.ones((n, n, 6), dtype=bool)
    for i, (ilo, ihi) in enumerate(boxes):
        for j, (jlo, jhi) in enumerate(boxes):
            if i == j:
                tt[i, j] = False
                continue
            for k in range(3):
                o = [m for m in range(3) if m != k]
                closed = all(ilo[m] <= jhi[m] and jlo[m] <= ihi[m] for m in o)
                open_ = all(ilo[m] < jhi[m] and jlo[m] < ihi[m] for m in o)
                tc[i, j, 2 * k] = closed and jlo[k] == ihi[k]
                tc[i, j, 2 * k + 1] = closed and jhi[k] == ilo[k]
                tt[i, j, 2 * k] = not (open_ and jhi[k] > ilo[k])
                tt[i, j, 2 * k + 1] = not (open_ and jlo[k] < ihi[k])
    return tc, tt


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(box_layout())
def test_random_boxes_match_oracle_and_symmetries(boxes):
    meshes = {f"b{k}": shapes.box_between(lo, hi) for k, (lo, hi) in enumerate(boxes)}
    rel = compute_relations(Assembly.from_meshes(meshes))
    tc, tt = oracle(boxes)
    assert np.array_equal(rel.tc, tc)
    assert np.array_equal(rel.tt, tt)
    assert np.array_equal(rel.tc, rel.tc.transpose(1, 0, 2)[:, :, OPPOSITE])
    assert np.array_equal(rel.tt, rel.tt.transpose(1, 0, 2)[:, :, OPPOSITE])


@pytest.mark.parametrize("unit", ["cm", "m", "in"])
def test_scale_of_units_does_not_change_tables(unit):
    """The same assembly drawn in another unit gives the same tables."""
    ref = compute_relations(shapes.boxed_container())
    factor = 1.0 / unit_scale(unit)
    scaled = {p.id: p.mesh.copy().apply_scale(factor) for p in shapes.boxed_container().parts}
    rel = compute_relations(Assembly.from_meshes(scaled, units=unit))
    assert rel.parts == ref.parts
    assert np.array_equal(rel.tc, ref.tc) and np.array_equal(rel.tt, ref.tt)
