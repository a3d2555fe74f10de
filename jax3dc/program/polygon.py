"""2-D simple polygons: orientation, a simplicity check and triangulation for caps of extrusions
and sweeps (triangles from mapbox-earcut)."""

from __future__ import annotations

import mapbox_earcut
import numpy as np


def signed_area(points: np.ndarray) -> float:
    """Shoelace area, positive for counter-clockwise vertex order."""
    x, y = points[:, 0], points[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def _orient(o: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product (a - o) x (b - o) for rows of points [K, 2]."""
    return (a[:, 0] - o[:, 0]) * (b[:, 1] - o[:, 1]) - (a[:, 1] - o[:, 1]) * (b[:, 0] - o[:, 0])


def _on_segment(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Whether c is collinear with ab and within its bounding box (rows [K, 2])."""
    eps = 1e-14
    inside = np.all((np.minimum(a, b) - eps <= c) & (c <= np.maximum(a, b) + eps), axis=1)
    return (np.abs(_orient(a, b, c)) < eps) & inside


def is_simple(points: np.ndarray) -> bool:
    """No two non-adjacent edges of the closed outline meet (touching counts), all pairs at once."""
    pts = np.asarray(points, dtype=np.float64)
    n = len(pts)
    i, j = np.triu_indices(n, k=2)
    keep = ~((i == 0) & (j == n - 1))  # the closing edge is adjacent to the first
    i, j = i[keep], j[keep]
    ends = np.roll(pts, -1, axis=0)
    p1, p2, q1, q2 = pts[i], ends[i], pts[j], ends[j]
    d1, d2 = _orient(q1, q2, p1), _orient(q1, q2, p2)
    d3, d4 = _orient(p1, p2, q1), _orient(p1, p2, q2)
    proper = (d1 * d2 < 0) & (d3 * d4 < 0)
    touching = _on_segment(q1, q2, p1) | _on_segment(q1, q2, p2) | _on_segment(p1, p2, q1) | _on_segment(p1, p2, q2)
    return not bool(np.any(proper | touching))


def is_convex(points: np.ndarray) -> bool:
    """Strictly convex and simple: every turn has the same sense and they add up to one turn.

    O(n), so the common profiles (circles of sweeps, rectangles) skip the O(n^2) is_simple.
    """
    edges = np.roll(points, -1, axis=0) - points
    cross = edges[:, 0] * np.roll(edges[:, 1], -1) - edges[:, 1] * np.roll(edges[:, 0], -1)
    if not (np.all(cross > 1e-14) or np.all(cross < -1e-14)):
        return False
    dot = np.einsum("ij,ij->i", edges, np.roll(edges, -1, axis=0))
    return bool(abs(np.abs(np.arctan2(cross, dot)).sum() - 2 * np.pi) < 1e-6)


def triangulate(points: np.ndarray) -> np.ndarray:
    """Triangles (index triples, counter-clockwise) covering a simple polygon, by mapbox-earcut.

    The polygon may be given in either orientation; the triangles always follow the
    counter-clockwise order, so callers flip them for the opposite face. Earcut assumes a simple
    outline and does not check it, so crossing edges are refused here first. Raises ValueError
    for fewer than 3 vertices, zero area, a self-intersecting outline, or a triangulation that
    leaves a vertex out (the caps must share every vertex with the sides to stay watertight).
    """
    pts = np.asarray(points, dtype=np.float64)
    n = len(pts)
    if n < 3:
        raise ValueError("a polygon needs at least 3 vertices")
    if abs(signed_area(pts)) < 1e-14:
        raise ValueError("the polygon has zero area")
    if not is_convex(pts) and not is_simple(pts):
        raise ValueError("the polygon is not simple (its edges cross)")
    tris = mapbox_earcut.triangulate_float64(pts, np.array([n], dtype=np.uint32)).reshape(-1, 3).astype(np.int64)
    if len(tris) != n - 2:
        raise ValueError("the polygon could not be triangulated with all its vertices")
    return tris  # earcut winds its output counter-clockwise whatever the input's orientation
