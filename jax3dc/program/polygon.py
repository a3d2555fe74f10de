"""2-D simple polygons: orientation and triangulation for caps of extrusions and sweeps.

Ear clipping is O(n^2) but part-program profiles have tens of vertices, and it needs no
geometry dependency (shapely / earcut are not installed here).
"""

from __future__ import annotations

import numpy as np


def signed_area(points: np.ndarray) -> float:
    """Shoelace area, positive for counter-clockwise vertex order."""
    x, y = points[:, 0], points[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def _cross(o: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))


def _any_inside_triangle(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> bool:
    """Whether any of the points [N, 2] lies in the closed counter-clockwise triangle abc."""
    eps = 1e-12

    def side(o, d):
        return (d[0] - o[0]) * (p[:, 1] - o[1]) - (d[1] - o[1]) * (p[:, 0] - o[0])

    return bool(np.any((side(a, b) >= -eps) & (side(b, c) >= -eps) & (side(c, a) >= -eps)))


def _segments_cross(p1, p2, q1, q2) -> bool:
    """True when segments p1p2 and q1q2 share a point (touching counts)."""
    d1, d2 = _cross(q1, q2, p1), _cross(q1, q2, p2)
    d3, d4 = _cross(p1, p2, q1), _cross(p1, p2, q2)
    if ((d1 > 0) != (d2 > 0)) and ((d3 > 0) != (d4 > 0)) and d1 * d2 != 0 and d3 * d4 != 0:
        return True
    def on(a, b, c):  # c collinear with ab and within its box
        return abs(_cross(a, b, c)) < 1e-14 and min(a[0], b[0]) - 1e-14 <= c[0] <= max(a[0], b[0]) + 1e-14 \
            and min(a[1], b[1]) - 1e-14 <= c[1] <= max(a[1], b[1]) + 1e-14
    return on(q1, q2, p1) or on(q1, q2, p2) or on(p1, p2, q1) or on(p1, p2, q2)


def is_convex(points: np.ndarray) -> bool:
    """Strictly convex and simple: every turn has the same sense and they add up to one turn."""
    edges = np.roll(points, -1, axis=0) - points
    cross = edges[:, 0] * np.roll(edges[:, 1], -1) - edges[:, 1] * np.roll(edges[:, 0], -1)
    if not (np.all(cross > 1e-14) or np.all(cross < -1e-14)):
        return False
    dot = np.einsum("ij,ij->i", edges, np.roll(edges, -1, axis=0))
    turning = np.abs(np.arctan2(cross, dot)).sum()
    return bool(abs(turning - 2 * np.pi) < 1e-6)


def is_simple(points: np.ndarray) -> bool:
    """No two non-adjacent edges of the closed outline meet."""
    n = len(points)
    for i in range(n):
        for j in range(i + 1, n):
            if j == i + 1 or (i == 0 and j == n - 1):
                continue
            if _segments_cross(points[i], points[(i + 1) % n], points[j], points[(j + 1) % n]):
                return False
    return True


def triangulate(points: np.ndarray) -> np.ndarray:
    """Triangles (index triples, counter-clockwise) covering a simple polygon.

    The polygon may be given in either orientation; the triangles always follow the
    counter-clockwise order, so callers flip them for the opposite face.
    Raises ValueError for fewer than 3 vertices, zero area or a self-intersecting outline
    (no ear can be found).
    """
    pts = np.asarray(points, dtype=np.float64)
    n = len(pts)
    if n < 3:
        raise ValueError("a polygon needs at least 3 vertices")
    area = signed_area(pts)
    if abs(area) < 1e-14:
        raise ValueError("the polygon has zero area")
    if is_convex(pts):  # the common case (circles, boxes): a fan, no O(n^2) checks
        order = np.arange(n) if area > 0 else np.arange(n)[::-1]
        return np.stack([np.full(n - 2, order[0]), order[1:-1], order[2:]], axis=1).astype(np.int64)
    if not is_simple(pts):
        raise ValueError("the polygon is not simple (its edges cross)")
    order = list(range(n)) if area > 0 else list(range(n - 1, -1, -1))
    triangles: list[tuple[int, int, int]] = []
    guard = 0
    while len(order) > 3:
        m = len(order)
        for k in range(m):
            i, j, l = order[k - 1], order[k], order[(k + 1) % m]
            a, b, c = pts[i], pts[j], pts[l]
            if _cross(a, b, c) <= 1e-14:
                continue  # reflex or degenerate corner: not an ear
            others = pts[[q for q in order if q not in (i, j, l)]]
            if len(others) and _any_inside_triangle(others, a, b, c):
                continue
            triangles.append((i, j, l))
            del order[k]
            break
        else:
            raise ValueError("the polygon is not simple (no ear found)")
        guard += 1
        if guard > n:
            raise ValueError("the polygon is not simple")
    triangles.append((order[0], order[1], order[2]))
    return np.asarray(triangles, dtype=np.int64)
