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


def _inside_triangle(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> bool:
    eps = 1e-12
    return _cross(a, b, p) >= -eps and _cross(b, c, p) >= -eps and _cross(c, a, p) >= -eps


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
            if any(_inside_triangle(pts[q], a, b, c) for q in order if q not in (i, j, l)):
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
