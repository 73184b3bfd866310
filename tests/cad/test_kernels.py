"""The geometric kernels: box broad phase, projected height range, mesh offset."""

from __future__ import annotations

import numpy as np
import pytest

from cad.offset import offset_vertices
from cad.projection import box_pair_chunks, box_pairs, height_gap_range
from tests.cad import shapes


def brute_pairs(a, b):
    hit = (
        (a[:, None, 0] <= b[None, :, 2])
        & (b[None, :, 0] <= a[:, None, 2])
        & (a[:, None, 1] <= b[None, :, 3])
        & (b[None, :, 1] <= a[:, None, 3])
    )
    return set(zip(*map(list, np.nonzero(hit)), strict=True))


@pytest.mark.parametrize("seed", range(5))
def test_box_pairs_match_brute_force(seed):
    rng = np.random.default_rng(seed)
    lo = rng.uniform(0, 10, (300, 2))
    a = np.hstack([lo, lo + rng.exponential(0.6, (300, 2))])
    lo = rng.uniform(0, 10, (200, 2))
    b = np.hstack([lo, lo + rng.exponential(0.6, (200, 2))])
    expected = brute_pairs(a, b)
    ia, ib = box_pairs(a, b)
    assert set(zip(ia.tolist(), ib.tolist(), strict=True)) == expected and len(ia) == len(expected)
    chunks = [
        p for ia, ib in box_pair_chunks(a, b) for p in zip(ia.tolist(), ib.tolist(), strict=True)
    ]
    assert set(chunks) == expected and len(chunks) == len(expected)


UNIT = np.array([[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]])


@pytest.mark.parametrize(
    ("q_uv", "q_h", "expected"),
    [
        (UNIT * 2 + 0.2, [[1.0, 1.0, 1.0]], (True, 1.0, 1.0)),  # overlapping, flat
        (UNIT + 5.0, [[1.0, 1.0, 1.0]], (False, np.inf, -np.inf)),  # apart
        (UNIT * 1.8 + 0.2, [[0.0, 3.0, 0.0]], (True, 0.0, 1.0)),  # sloped
        (np.array([[[1.0, 0.0], [2.0, 0.0], [1.0, 1.0]]]), [[2.0, 2.0, 2.0]], (True, 2.0, 2.0)),
    ],
    ids=["flat", "apart", "sloped", "touching at a vertex"],
)
def test_height_gap_range(q_uv, q_h, expected):
    overlap, lo, hi = height_gap_range(UNIT, np.zeros((1, 3)), np.asarray(q_uv), np.asarray(q_h))
    assert (bool(overlap[0]), lo[0], hi[0]) == pytest.approx(expected)


def test_offset_moves_every_face_of_a_box():
    mesh = shapes.box_between((0, 0, 0), (10, 20, 30))
    moved = offset_vertices(mesh, -0.5)
    assert np.allclose(moved.min(axis=0), [0.5, 0.5, 0.5])
    assert np.allclose(moved.max(axis=0), [9.5, 19.5, 29.5])


def test_offset_of_cylinder_keeps_its_shape():
    mesh = shapes.cylinder(5.0, 0.0, 10.0, sections=64)
    moved = offset_vertices(mesh, -0.25)
    radius = np.linalg.norm(moved[:, :2], axis=1)
    rim = radius > 1.0
    apothem = 5.0 * np.cos(np.pi / 64)
    # the faces of the polygon move in by 0.25: the new apothem is 0.25 smaller
    assert np.allclose(radius[rim] * np.cos(np.pi / 64), apothem - 0.25, atol=1e-9)
    assert np.allclose(np.sort(np.unique(moved[:, 2].round(9))), [0.25, 9.75])


@pytest.mark.parametrize("seed", range(3))
def test_grid_with_strips_and_slivers_matches_brute_force(seed):
    """Thin strips (side walls seen edge-on) and long slivers (fan-triangulated caps)."""
    rng = np.random.default_rng(seed)
    lo = rng.uniform(0, 50, (400, 2))
    strips = np.hstack([lo, lo + [0.05, 10.0]])
    lo = rng.uniform(0, 50, (60, 2))
    slivers = np.hstack([lo, lo + rng.uniform(10, 40, (60, 2))])
    a = np.vstack([strips, slivers])
    lo = rng.uniform(0, 50, (300, 2))
    b = np.hstack([lo, lo + rng.exponential(0.5, (300, 2))])
    expected = brute_pairs(a, b)
    ia, ib = box_pairs(a, b)
    assert set(zip(ia.tolist(), ib.tolist(), strict=True)) == expected and len(ia) == len(expected)


def test_refined_slivers_tile_the_triangle_and_keep_heights():
    from cad.faces import axis_face_sets, refine, unit_normals

    tri = np.array([[[0.0, 0.0, 1.0], [40.0, 1.0, 2.0], [0.0, 2.0, 3.0]]])
    up = axis_face_sets(tri, unit_normals(tri), 2, 1e-9)
    faces = up[0] if len(up[0]) else up[1]
    fine = refine(faces, 5.0)
    edges = np.linalg.norm(fine.uv[:, [1, 2, 0]] - fine.uv, axis=2)
    assert edges.max() <= 5.0 + 1e-12 and len(fine) > 8
    d1, d2 = fine.uv[:, 1] - fine.uv[:, 0], fine.uv[:, 2] - fine.uv[:, 0]
    area = 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]).sum()
    assert area == pytest.approx(40.0)
    # every piece lies in the plane of the original triangle
    normal = np.cross(tri[0, 1] - tri[0, 0], tri[0, 2] - tri[0, 0])
    points = np.concatenate([fine.uv, fine.h[:, :, None]], axis=2).reshape(-1, 3)
    assert np.allclose((points - tri[0, 0]) @ normal, 0.0, atol=1e-9)
