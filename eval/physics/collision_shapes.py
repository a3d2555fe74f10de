"""Convex collision pieces of a part mesh: a cheap own convex decomposition.

MuJoCo collides every mesh through its convex hull, so a concave part (a cabinet carcass around a
drawer, a bucket) would read as one solid block. Pieces are: the mesh's connected components
(part programs build a carcass from separate boards, so each board is one piece); a closed
component whose hull is much larger than its volume is cut in half across its longest extent,
by voxels: its filled voxelisation is covered greedily by boxes, and each piece is the hull of the
surface points inside one box (``DECOMPOSITION_DEPTH`` sets the voxel size: 8·2^depth across). Each piece's hull is capped at ``HULL_MAX_VERTICES`` by
farthest-point sampling of the hull's vertices, which keeps the extreme points.
(The ``coacd`` wheel exists on PyPI but is not a project dependency; this is enough for
programmatic parts and PartNet-Mobility meshes, which are mostly unions of separate pieces.)
"""

from __future__ import annotations

import numpy as np
import trimesh

from eval.physics.tolerances import CONCAVITY_RATIO, DECOMPOSITION_DEPTH, HULL_MAX_VERTICES

MAX_PIECES_PER_PART = 64  # many tiny components (screws, text) are merged into one hull beyond this


def convex_pieces(mesh: trimesh.Trimesh, min_size: float) -> list[np.ndarray]:
    """Vertex arrays [k, 3] (k ≤ HULL_MAX_VERTICES) of convex pieces covering ``mesh``.

    ``min_size``: pieces smaller than this in every direction are thickened (so hulls are valid).
    """
    components = mesh.split(only_watertight=False) if len(mesh.faces) else []
    if not components or len(components) > MAX_PIECES_PER_PART:
        components = [mesh]
    pieces: list[np.ndarray] = []
    for component in components:
        for piece in _split_concave(component, DECOMPOSITION_DEPTH):
            pieces.append(capped_hull(np.asarray(piece.vertices, dtype=np.float64), min_size))
    return pieces


def _split_concave(mesh: trimesh.Trimesh, depth: int) -> list[trimesh.Trimesh]:
    """A closed, clearly concave component becomes the surface points inside each of a few boxes
    that cover its voxelisation (greedy box merging); others stay whole."""
    if not mesh.is_volume:
        return [mesh]
    try:
        if mesh.convex_hull.volume <= CONCAVITY_RATIO * abs(mesh.volume):
            return [mesh]
    except Exception:  # qhull: flat point set
        return [mesh]
    pitch = float(np.max(mesh.extents)) / (8 * 2 ** depth)
    grid = mesh.voxelized(pitch).fill()
    occupied = np.asarray(grid.matrix, dtype=bool)
    points = np.concatenate([mesh.vertices, mesh.sample(20000, seed=0)])
    # the voxel index of each surface point (points exactly on a wall stay with that wall's voxels)
    index = np.floor((points - grid.translation) / pitch + 0.5).astype(int)
    index = np.clip(index, 0, np.array(occupied.shape) - 1)
    pieces = []
    for lo, hi in _boxes(occupied):
        inside = np.all((index >= lo) & (index < hi), axis=1)
        if inside.sum() >= 4:
            pieces.append(trimesh.PointCloud(points[inside]))
    return pieces or [mesh]


def _boxes(occupied: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Greedy cover of the occupied voxels by axis-aligned boxes [lo, hi) of voxel indices."""
    free = occupied.copy()
    boxes = []
    for start in np.argwhere(occupied):
        if not free[tuple(start)]:
            continue
        lo, hi = start.copy(), start + 1
        for axis in range(3):  # grow along x, then y, then z while the whole face is free
            while hi[axis] < free.shape[axis]:
                face = [slice(lo[i], hi[i]) for i in range(3)]
                face[axis] = slice(hi[axis], hi[axis] + 1)
                if not free[tuple(face)].all():
                    break
                hi[axis] += 1
        free[lo[0]:hi[0], lo[1]:hi[1], lo[2]:hi[2]] = False
        boxes.append((lo, hi))
    return boxes


def capped_hull(points: np.ndarray, min_size: float) -> np.ndarray:
    """Hull vertices of ``points``, at most HULL_MAX_VERTICES, with every extent ≥ ``min_size``."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    thin = (hi - lo) < min_size
    if thin.any():  # flat piece: thicken it to ``min_size`` so the hull has a volume
        pad = np.where(thin, min_size / 2, 0.0)
        points = np.concatenate([points + pad, points - pad])
    try:
        vertices = np.asarray(trimesh.convex.convex_hull(points).vertices)
    except Exception:
        lo, hi = points.min(axis=0), points.max(axis=0)  # degenerate even after padding: its box
        vertices = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    if len(vertices) > HULL_MAX_VERTICES:
        vertices = vertices[_farthest_points(vertices, HULL_MAX_VERTICES)]
    return vertices


def _farthest_points(points: np.ndarray, k: int) -> np.ndarray:
    """Indices of k points chosen greedily far apart, starting from the point farthest from the centre."""
    chosen = [int(np.argmax(np.linalg.norm(points - points.mean(axis=0), axis=1)))]
    dist = np.linalg.norm(points - points[chosen[0]], axis=1)
    for _ in range(k - 1):
        nxt = int(np.argmax(dist))
        chosen.append(nxt)
        dist = np.minimum(dist, np.linalg.norm(points - points[nxt], axis=1))
    return np.asarray(chosen)
