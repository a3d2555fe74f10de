"""Loading the geometry of links: mesh files (materials and textures ignored) and primitives.

Only geometry matters for parts, so OBJ material libraries are skipped: real datasets ship
``.mtl`` files that name texture images which are not there.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

from jax3dc.errors import InputFileError

MESH_SUFFIXES = (".obj", ".stl", ".ply", ".glb", ".gltf", ".off")


def load_mesh_file(path: Path, referenced_by: Path, where: str) -> trimesh.Trimesh:
    """Triangle mesh of ``path``; errors name the referencing file and element (``where``)."""
    if not path.is_file():
        raise InputFileError(referenced_by, f"{where}: mesh file {path} not found")
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise InputFileError(referenced_by, f"{where}: unsupported mesh format {path.suffix!r} ({path})")
    try:
        kwargs = {"skip_materials": True} if path.suffix.lower() == ".obj" else {}
        loaded = trimesh.load(str(path), force="mesh", process=False, **kwargs)
    except Exception as e:  # trimesh raises many types for corrupt files
        raise InputFileError(referenced_by, f"{where}: cannot read mesh {path}: {e}") from None
    if not isinstance(loaded, trimesh.Trimesh):
        # force="mesh" gives an empty Scene-derived object for files without faces
        return trimesh.Trimesh()
    return trimesh.Trimesh(np.asarray(loaded.vertices, float), np.asarray(loaded.faces), process=False)


def transformed(mesh: trimesh.Trimesh, matrix: np.ndarray) -> trimesh.Trimesh:
    """A copy of ``mesh`` moved by the 4x4 ``matrix`` (may include scaling)."""
    out = mesh.copy()
    out.apply_transform(matrix)
    return out


def merged(meshes: list[trimesh.Trimesh]) -> trimesh.Trimesh | None:
    """One mesh of all non-empty ``meshes``, or None when there is no triangle at all."""
    meshes = [m for m in meshes if len(m.faces)]
    if not meshes:
        return None
    return trimesh.util.concatenate(meshes)


def box(extents) -> trimesh.Trimesh:
    return trimesh.creation.box(extents=np.asarray(extents, float))


def cylinder(radius: float, length: float) -> trimesh.Trimesh:
    """Cylinder along Z, centred at the origin (URDF and MuJoCo convention)."""
    return trimesh.creation.cylinder(radius=radius, height=length, sections=32)


def sphere(radius: float) -> trimesh.Trimesh:
    return trimesh.creation.icosphere(subdivisions=2, radius=radius)


def capsule(radius: float, length: float) -> trimesh.Trimesh:
    """Capsule along Z; ``length`` is the cylinder part, without the caps."""
    return trimesh.creation.capsule(height=length, radius=radius)


def ellipsoid(radii) -> trimesh.Trimesh:
    mesh = sphere(1.0)
    mesh.vertices = mesh.vertices * np.asarray(radii, float)
    return mesh
