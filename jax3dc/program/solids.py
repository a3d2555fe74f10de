"""Closed triangle meshes built by the part-program primitives (pure numpy).

Every builder returns a `Solid` whose faces are wound counter-clockwise seen from outside
and whose vertices are shared, so the result is watertight without a merge pass; that keeps
a whole object's program well under a few milliseconds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import ConvexHull
from scipy.spatial.transform import Rotation

from jax3dc.program.polygon import signed_area, triangulate

AXES = ("x", "y", "z")


@dataclass(frozen=True, eq=False)  # compared by identity: arrays have no single truth value
class Solid:
    """A triangle mesh value of the language: vertices [V,3] float64, faces [F,3] int64."""

    vertices: np.ndarray
    faces: np.ndarray

    @property
    def triangle_count(self) -> int:
        return int(len(self.faces))

    def signed_volume(self) -> float:
        a, b, c = (self.vertices[self.faces[:, k]] for k in range(3))
        cross = np.stack([b[:, 1] * c[:, 2] - b[:, 2] * c[:, 1],  # explicit: np.cross is slow on
                          b[:, 2] * c[:, 0] - b[:, 0] * c[:, 2],  # the many small arrays here
                          b[:, 0] * c[:, 1] - b[:, 1] * c[:, 0]], axis=1)
        return float(np.einsum("ij,ij->i", a, cross).sum() / 6.0)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        return self.vertices.min(axis=0), self.vertices.max(axis=0)

    def flipped(self) -> Solid:
        return Solid(self.vertices, self.faces[:, ::-1].copy())

    def outward(self) -> Solid:
        """The same solid with faces wound so that its volume is positive."""
        return self.flipped() if self.signed_volume() < 0 else self


def _axis_frame(axis: str) -> np.ndarray:
    """Rows map local (a, b, c) with c along `axis` to world; cyclic, so handedness is kept."""
    if axis == "z":
        return np.eye(3)
    if axis == "x":  # world = (c, a, b)
        return np.array([[0, 1, 0], [0, 0, 1], [1, 0, 0]], dtype=np.float64)
    if axis == "y":  # world = (b, c, a)
        return np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0]], dtype=np.float64)
    raise ValueError(f"axis must be one of {AXES}, got {axis!r}")


def _place(local: np.ndarray, axis: str, center) -> np.ndarray:
    return local @ _axis_frame(axis) + np.asarray(center, dtype=np.float64)


def box(size, center) -> Solid:
    half = np.asarray(size, dtype=np.float64) / 2.0
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=np.float64)
    faces = np.array([
        [0, 1, 3], [0, 3, 2],  # -x
        [4, 6, 7], [4, 7, 5],  # +x
        [0, 4, 5], [0, 5, 1],  # -y
        [2, 3, 7], [2, 7, 6],  # +y
        [0, 2, 6], [0, 6, 4],  # -z
        [1, 5, 7], [1, 7, 3],  # +z
    ], dtype=np.int64)
    return Solid(corners * half + np.asarray(center, dtype=np.float64), faces)


def frustum(radius_bottom: float, radius_top: float, depth: float, center, axis: str, segments: int) -> Solid:
    """Cylinder (equal radii) or cone / truncated cone along `axis`, centred on `center`."""
    t = np.linspace(0.0, 2 * np.pi, segments, endpoint=False)
    ring = np.stack([np.cos(t), np.sin(t)], axis=1)
    h = depth / 2.0
    verts = [np.column_stack([ring * radius_bottom, np.full(segments, -h)])]
    faces = []
    n = segments
    k = np.arange(n)
    k1 = (k + 1) % n
    bottom_centre = n
    if radius_top > 0:
        verts.append(np.column_stack([ring * radius_top, np.full(n, h)]))
        top = n + k
        faces.append(np.column_stack([k, k1, n + k1]))
        faces.append(np.column_stack([k, n + k1, top]))
        bottom_centre = 2 * n
        top_centre = 2 * n + 1
        faces.append(np.column_stack([np.full(n, top_centre), n + k, n + k1]))
        verts.append(np.array([[0.0, 0.0, -h], [0.0, 0.0, h]]))
    else:
        apex = n + 1
        faces.append(np.column_stack([k, k1, np.full(n, apex)]))
        verts.append(np.array([[0.0, 0.0, -h], [0.0, 0.0, h]]))
    faces.append(np.column_stack([np.full(n, bottom_centre), k1, k]))
    local = np.concatenate(verts)
    return Solid(_place(local, axis, center), np.concatenate(faces).astype(np.int64))


def uv_sphere(radius: float, center, segments: int, rings: int) -> Solid:
    theta = np.linspace(0.0, np.pi, rings + 1)[1:-1]  # polar angles of the inner rings
    phi = np.linspace(0.0, 2 * np.pi, segments, endpoint=False)
    st, ct = np.sin(theta)[:, None], np.cos(theta)[:, None]
    body = np.stack([st * np.cos(phi), st * np.sin(phi), np.broadcast_to(ct, (len(theta), segments))], axis=-1)
    verts = np.concatenate([body.reshape(-1, 3), [[0, 0, 1], [0, 0, -1]]]) * radius
    n, r = segments, rings - 1
    north, south = r * n, r * n + 1
    k = np.arange(n)
    k1 = (k + 1) % n
    faces = [np.column_stack([np.full(n, north), k, k1])]
    for i in range(r - 1):
        a, b = i * n, (i + 1) * n
        faces.append(np.column_stack([a + k, b + k, b + k1]))
        faces.append(np.column_stack([a + k, b + k1, a + k1]))
    last = (r - 1) * n
    faces.append(np.column_stack([np.full(n, south), last + k1, last + k]))
    return Solid(verts + np.asarray(center, dtype=np.float64), np.concatenate(faces).astype(np.int64))


def torus(major: float, minor: float, center, axis: str, major_segments: int, minor_segments: int) -> Solid:
    u = np.linspace(0.0, 2 * np.pi, major_segments, endpoint=False)[:, None]
    v = np.linspace(0.0, 2 * np.pi, minor_segments, endpoint=False)[None, :]
    rad = major + minor * np.cos(v) + 0.0 * u
    local = np.stack([rad * np.cos(u), rad * np.sin(u), np.broadcast_to(minor * np.sin(v), rad.shape)], axis=-1)
    m, n = major_segments, minor_segments
    i, j = np.meshgrid(np.arange(m), np.arange(n), indexing="ij")
    a = i * n + j
    b = ((i + 1) % m) * n + j
    c = ((i + 1) % m) * n + (j + 1) % n
    d = i * n + (j + 1) % n
    faces = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    return Solid(_place(local.reshape(-1, 3), axis, center), faces.astype(np.int64)).outward()


def prism(profile: np.ndarray, depth: float, center, axis: str) -> Solid:
    """A 2-D polygon extruded symmetrically along `axis` (total length `depth`).

    Profile coordinates (u, v) lie in the plane across the axis: axis z -> (x, y),
    axis y -> (x, z), axis x -> (y, z).
    """
    pts = np.asarray(profile, dtype=np.float64)
    if signed_area(pts) < 0:
        pts = pts[::-1]
    tris = triangulate(pts)
    n = len(pts)
    h = depth / 2.0
    local = np.concatenate([np.column_stack([pts, np.full(n, -h)]), np.column_stack([pts, np.full(n, h)])])
    k = np.arange(n)
    k1 = (k + 1) % n
    faces = np.concatenate([tris[:, ::-1], tris + n, np.column_stack([k, k1, n + k1]), np.column_stack([k, n + k1, n + k])])
    world = {"z": [0, 1, 2], "y": [0, 2, 1], "x": [2, 0, 1]}[axis]
    placed = local[:, world] + np.asarray(center, dtype=np.float64)
    return Solid(placed, faces.astype(np.int64)).outward()


def revolve(profile: np.ndarray, center, axis: str, segments: int) -> Solid:
    """A closed (r, h) outline revolved a full turn about `axis`; points with r == 0 become poles."""
    pts = np.asarray(profile, dtype=np.float64)
    t = np.linspace(0.0, 2 * np.pi, segments, endpoint=False)
    cos, sin = np.cos(t), np.sin(t)
    verts: list[np.ndarray] = []
    index: list[np.ndarray] = []  # per profile vertex, its ring of vertex indices
    count = 0
    for r, h in pts:
        if r <= 1e-12:
            verts.append(np.array([[0.0, 0.0, h]]))
            index.append(np.full(segments, count))
            count += 1
        else:
            verts.append(np.column_stack([r * cos, r * sin, np.full(segments, h)]))
            index.append(count + np.arange(segments))
            count += segments
    faces = []
    n = len(pts)
    for i in range(n):
        a, b = index[i], index[(i + 1) % n]
        a1, b1 = np.roll(a, -1), np.roll(b, -1)
        if a[0] == a[1] and b[0] == b[1]:
            continue  # an edge lying on the axis sweeps no surface
        if a[0] == a[1]:
            faces.append(np.column_stack([a, b, b1]))
        elif b[0] == b[1]:
            faces.append(np.column_stack([a, b, a1]))
        else:
            faces.append(np.column_stack([a, b, b1]))
            faces.append(np.column_stack([a, b1, a1]))
    local = np.concatenate(verts)
    return Solid(_place(local, axis, center), np.concatenate(faces).astype(np.int64)).outward()


def _perpendicular(t: np.ndarray) -> np.ndarray:
    helper = np.array([0.0, 0.0, 1.0]) if abs(t[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    p = np.cross(t, helper)
    return p / np.linalg.norm(p)


def sweep(path: np.ndarray, profile: np.ndarray) -> Solid:
    """A 2-D profile (around the path) carried along an open polyline, mitred at bends, capped."""
    path = np.asarray(path, dtype=np.float64)
    pts = np.asarray(profile, dtype=np.float64)
    if signed_area(pts) < 0:
        pts = pts[::-1]
    seg = np.diff(path, axis=0)
    lengths = np.linalg.norm(seg, axis=1)
    if np.any(lengths < 1e-12):
        raise ValueError("the path has two equal consecutive points")
    d = seg / lengths[:, None]
    m = len(path)
    # the plane each ring lies in: across the path at the ends, the mitre (bisector) plane at bends
    planes = np.concatenate([d[:1], d[:-1] + d[1:], d[-1:]])
    norms = np.linalg.norm(planes, axis=1)
    if np.any(norms < 1e-9):
        raise ValueError("the path turns back on itself")
    planes /= norms[:, None]
    normal = _perpendicular(d[0])
    binormal = np.cross(d[0], normal)
    n = len(pts)
    ring = path[0] + pts[:, :1] * normal + pts[:, 1:2] * binormal
    rings = [ring]
    for i in range(1, m):
        # carry the previous ring along the segment direction onto this ring's plane, so each
        # segment is an exact prism and the section never twists
        along = float(np.dot(d[i - 1], planes[i]))
        if along < 0.1:
            raise ValueError("the path turns too sharply (more than about 168 degrees)")
        shift = ((path[i] - ring) @ planes[i]) / along
        ring = ring + shift[:, None] * d[i - 1]
        rings.append(ring)
    verts = np.concatenate(rings)
    k = np.arange(n)
    k1 = (k + 1) % n
    faces = []
    for i in range(m - 1):
        a, b = i * n, (i + 1) * n
        faces.append(np.column_stack([a + k, a + k1, b + k1]))
        faces.append(np.column_stack([a + k, b + k1, b + k]))
    tris = triangulate(pts)
    faces.append(tris[:, ::-1])
    faces.append(tris + (m - 1) * n)
    return Solid(verts, np.concatenate(faces).astype(np.int64)).outward()


def chamfered_box(size, width: float, center) -> Solid:
    """A box with every edge cut at 45 degrees by `width` (convex hull of three shrunk boxes)."""
    half = np.asarray(size, dtype=np.float64) / 2.0
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=np.float64)
    points = []
    for keep in range(3):
        shrunk = half - width
        shrunk[keep] = half[keep]
        points.append(signs * shrunk)
    pts = np.concatenate(points)
    hull = ConvexHull(pts)
    faces = hull.simplices.astype(np.int64)
    tri = pts[faces]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    outward = np.einsum("ij,ij->i", normal, tri.mean(axis=1)) > 0
    faces = np.where(outward[:, None], faces, faces[:, ::-1])
    used, remap = np.unique(faces, return_inverse=True)
    return Solid(pts[used] + np.asarray(center, dtype=np.float64), remap.reshape(-1, 3).astype(np.int64))


def combine(solids: list[Solid]) -> Solid:
    """Several solids as one mesh value (no boolean union: pieces may touch or overlap)."""
    offsets = np.cumsum([0] + [len(s.vertices) for s in solids[:-1]])
    return Solid(
        np.concatenate([s.vertices for s in solids]),
        np.concatenate([s.faces + o for s, o in zip(solids, offsets)]),
    )


def rotation_matrix(axis: np.ndarray, angle_rad: float) -> np.ndarray:
    """Right-handed rotation by ``angle_rad`` about ``axis`` (any length)."""
    a = np.asarray(axis, dtype=np.float64)
    return Rotation.from_rotvec(a / np.linalg.norm(a) * angle_rad).as_matrix()


def transformed(solid: Solid, matrix: np.ndarray, center) -> Solid:
    """`matrix` applied about `center`; a reflection (negative determinant) rewinds the faces."""
    c = np.asarray(center, dtype=np.float64)
    out = Solid((solid.vertices - c) @ matrix.T + c, solid.faces)
    return out.flipped() if np.linalg.det(matrix) < 0 else out


def translated(solid: Solid, offset) -> Solid:
    return Solid(solid.vertices + np.asarray(offset, dtype=np.float64), solid.faces)
