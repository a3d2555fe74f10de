"""Polygon triangulation (mapbox-earcut behind our simplicity check): the triangles tile the polygon
exactly (shoelace area), use every vertex, and crossing outlines are refused."""

import numpy as np
import pytest

from jax3dc.program.polygon import is_convex, is_simple, signed_area, triangulate


def cross2(a, b):
    return a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]


def tri_area(points, tris):
    p = np.asarray(points, dtype=float)[tris]
    return 0.5 * cross2(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]).sum()


SHAPES = {
    "square": [(0, 0), (1, 0), (1, 1), (0, 1)],
    "circle_cw": [(np.cos(t), -np.sin(t)) for t in np.linspace(0, 2 * np.pi, 17, endpoint=False)],
    "L": [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)],
    "comb": [(0, 0), (5, 0), (5, 3), (4, 3), (4, 1), (3, 1), (3, 3), (2, 3), (2, 1), (1, 1), (1, 3), (0, 3)],
    "collinear_cw": [(0, 0), (0, 2), (2, 2), (2, 0), (1, 0)],  # (1, 0) lies on an edge: it must stay a vertex
}


@pytest.mark.parametrize("name", sorted(SHAPES))
def tiles(pts, tris) -> None:
    """n - 2 counter-clockwise triangles over every vertex whose areas add up to the polygon's."""
    p = np.asarray(pts, float)
    assert len(tris) == len(p) - 2
    assert sorted(np.unique(tris)) == list(range(len(p)))
    corners = p[tris]
    assert np.all(cross2(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]) > 0)
    assert tri_area(p, tris) == pytest.approx(abs(signed_area(p)), rel=1e-12)


@pytest.mark.parametrize("name", sorted(SHAPES))
def test_triangles_tile_the_polygon(name):
    tiles(SHAPES[name], triangulate(SHAPES[name]))


def test_random_star_shaped_polygons_tile():
    """Star-shaped outlines with random radii: concave, in either orientation, 3 to 256 vertices."""
    rng = np.random.default_rng(0)
    for k in range(300):
        n = int(rng.integers(3, 257)) if k % 10 == 0 else int(rng.integers(3, 40))
        t = np.sort(rng.uniform(0, 2 * np.pi, n))
        r = rng.uniform(0.2, 1.0, n)
        pts = np.stack([r * np.cos(t), r * np.sin(t)], axis=1)
        pts = pts[::-1] if k % 2 else pts
        if abs(signed_area(pts)) > 1e-6 and is_simple(pts):
            tiles(pts, triangulate(pts))


def test_crossing_outlines_are_refused():
    star = [(np.cos(t), np.sin(t)) for t in np.linspace(0, 4 * np.pi, 5, endpoint=False)]  # pentagram
    bowtie = [(0, 0), (3, 2), (3, 0), (0, 1)]  # unequal lobes, so its signed area is not zero
    touching = [(0, 0), (2, 0), (2, 2), (1, 0), (0, 2)]  # a vertex on a non-adjacent edge
    for outline in (star, bowtie, touching):  # the pentagram turns left at every corner: not convex either
        assert not is_simple(np.asarray(outline, float)) and not is_convex(np.asarray(outline, float))
        with pytest.raises(ValueError, match="simple"):
            triangulate(outline)
    assert is_simple(np.asarray(SHAPES["comb"], float)) and not is_convex(np.asarray(SHAPES["comb"], float))
    assert is_convex(np.asarray(SHAPES["circle_cw"], float))
