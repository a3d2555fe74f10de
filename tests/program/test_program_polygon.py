"""Polygon triangulation: the triangles tile the polygon exactly (area), for convex and concave outlines."""

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
}


@pytest.mark.parametrize("name", sorted(SHAPES))
def test_triangles_tile_the_polygon(name):
    pts = SHAPES[name]
    tris = triangulate(pts)
    assert len(tris) == len(pts) - 2
    assert tri_area(pts, tris) == pytest.approx(abs(signed_area(np.asarray(pts, float))))  # all counter-clockwise
    p = np.asarray(pts, float)[tris]
    assert np.all(cross2(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]) > 0)


def test_convexity_and_simplicity():
    assert is_convex(np.asarray(SHAPES["square"], float)) and not is_convex(np.asarray(SHAPES["L"], float))
    star = [(np.cos(t), np.sin(t)) for t in np.linspace(0, 4 * np.pi, 5, endpoint=False)]  # pentagram: all left turns
    assert not is_convex(np.asarray(star, float)) and not is_simple(np.asarray(star, float))
    with pytest.raises(ValueError, match="simple"):
        triangulate(star)
