"""Relation extraction from part meshes (SPEC §4 "Processing").

Two sibling parts (same parent; object roots are siblings under the implicit scene root) are
copies of one design when their shape signatures match: the same vertex and face counts, the same
sorted principal extents (extents along the principal axes of the vertices, so a rotated or
mirrored copy has the same ones), and the same surface area and enclosed volume. A matching pair
is ``symmetric`` when its centroids mirror across a principal plane (yz, xz, xy, tried in that
order) through the parent's centre, else ``instance``; instance groups are then written as stars
anchored at their smallest id (canonical form).

Centroids and centres are bounding-box centres in the normalised frame (the parent part's box for
children, the frame origin, i.e. the object's centre, for roots).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from itertools import combinations

import numpy as np
import trimesh

from jax3dc.structure.canonical import canonical_relations
from jax3dc.structure.schema import Relation, Structure

# Tolerances (nu = normalised units: the object's largest extent is 1).
EXTENT_TOLERANCE = 2e-3  # nu, absolute, on each sorted principal extent
EXTENT_RELATIVE_TOLERANCE = 0.01  # plus this fraction of the extent
MEASURE_RELATIVE_TOLERANCE = 0.02  # surface area and volume
MEASURE_TOLERANCE = 1e-6  # nu^2 / nu^3, so that tiny parts compare by their absolute size
COVARIANCE_DIGITS = 9  # decimals kept of the trace-normalised second-moment matrix
MIRROR_TOLERANCE = 5e-3  # nu; a mirrored centroid this close to the other centroid is a mirror image

PLANE_AXES: tuple[tuple[str, int], ...] = (("yz", 0), ("xz", 1), ("xy", 2))


@dataclass(frozen=True)
class ShapeSignature:
    """What a rigid motion or reflection of a part leaves unchanged."""

    vertices: int
    faces: int
    extents: tuple[float, float, float]  # sorted principal extents, nu
    area: float
    volume: float  # |enclosed volume| for a watertight mesh, else 0


def principal_extents(vertices: np.ndarray) -> np.ndarray:
    """Sorted extents of the vertices along their principal axes.

    The second-moment matrix is rounded (COVARIANCE_DIGITS, relative to its trace) before its
    eigenvectors are taken: for shapes with equal moments (a cube, a cylinder's cross-section) the
    axes are otherwise decided by float noise, and two translated copies would get different
    axes and extents. Rounded, identical copies give identical matrices and so identical axes.
    """
    centred = vertices - vertices.mean(axis=0)
    moments = centred.T @ centred
    scale = float(np.trace(moments))
    if scale > 0:
        moments = np.round(moments / scale, COVARIANCE_DIGITS) * scale
    _, axes = np.linalg.eigh(moments)
    projected = centred @ axes
    return np.sort(projected.max(axis=0) - projected.min(axis=0))


def shape_signature(mesh: trimesh.Trimesh) -> ShapeSignature | None:
    """The signature of one part; None for a mesh without vertices (it matches nothing)."""
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    if len(vertices) == 0:
        return None
    volume = abs(float(mesh.volume)) if mesh.is_watertight else 0.0
    extents = principal_extents(vertices)
    return ShapeSignature(len(vertices), len(mesh.faces), (float(extents[0]), float(extents[1]), float(extents[2])),
                          float(mesh.area), volume)


def _close(a: float, b: float, absolute: float, relative: float) -> bool:
    return abs(a - b) <= absolute + relative * max(abs(a), abs(b))


def same_design(a: ShapeSignature, b: ShapeSignature) -> bool:
    """Whether two parts are copies of one design (rotated, mirrored or moved)."""
    if (a.vertices, a.faces) != (b.vertices, b.faces):
        return False
    if not all(_close(x, y, EXTENT_TOLERANCE, EXTENT_RELATIVE_TOLERANCE) for x, y in zip(a.extents, b.extents)):
        return False
    return (_close(a.area, b.area, MEASURE_TOLERANCE, MEASURE_RELATIVE_TOLERANCE)
            and _close(a.volume, b.volume, MEASURE_TOLERANCE, MEASURE_RELATIVE_TOLERANCE))


def mirror_plane(a: np.ndarray, b: np.ndarray, centre: np.ndarray) -> str | None:
    """The principal plane through ``centre`` that maps centroid ``a`` onto ``b``, if any."""
    if np.linalg.norm(a - b) <= MIRROR_TOLERANCE:  # coincident copies mirror across nothing useful
        return None
    for plane, k in PLANE_AXES:
        mirrored = a.copy()
        mirrored[k] = 2.0 * centre[k] - mirrored[k]
        if np.linalg.norm(mirrored - b) <= MIRROR_TOLERANCE:
            return plane
    return None


def _box_centre(mesh: trimesh.Trimesh) -> np.ndarray:
    lo, hi = np.asarray(mesh.bounds, dtype=np.float64)
    return (lo + hi) / 2.0


def extract_relations(structure: Structure, parts: dict[int, trimesh.Trimesh]) -> tuple[Relation, ...]:
    """Symmetric and instance relations among sibling parts, in canonical form (sorted, stars)."""
    signatures = {pid: shape_signature(parts[pid]) for pid in structure.nodes if pid in parts}
    centres = {pid: _box_centre(parts[pid]) for pid, sig in signatures.items() if sig is not None}
    siblings: dict[int | None, list[int]] = {}
    for pid, node in sorted(structure.nodes.items()):
        if signatures.get(pid) is not None:
            siblings.setdefault(node.parent, []).append(pid)
    found: list[Relation] = []
    for parent, ids in siblings.items():
        if parent is None:
            centre = np.zeros(3)
        elif parent in parts and len(parts[parent].vertices):
            centre = _box_centre(parts[parent])
        else:
            centre = None  # no geometry for the parent: copies can only be instances
        for a, b in combinations(ids, 2):
            if not same_design(signatures[a], signatures[b]):
                continue
            plane = None if centre is None else mirror_plane(centres[a], centres[b], centre)
            found.append(Relation("symmetric", a, b, plane) if plane else Relation("instance", a, b))
    return canonical_relations(tuple(found))


def with_extracted_relations(structure: Structure, parts: dict[int, trimesh.Trimesh]) -> Structure:
    """``structure`` with its symmetric / instance relations replaced by those found in ``parts``;
    other relations (``support``) are kept."""
    kept = tuple(r for r in structure.relations if r.type not in ("symmetric", "instance"))
    return replace(structure, relations=canonical_relations(kept + extract_relations(structure, parts)))
