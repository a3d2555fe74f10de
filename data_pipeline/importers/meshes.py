"""Loading the geometry of links: mesh files (materials and textures ignored) and primitives.

Only geometry matters for parts, so OBJ material libraries are skipped: real datasets ship
``.mtl`` files that name texture images which are not there.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

from data_pipeline.importers.limits import FaceBudget
from jax3dc.errors import InputFileError, shorten
from jax3dc.geometry.mesh_size import MAX_COORDINATE, declared_faces
MESH_SUFFIXES = (".obj", ".stl", ".ply", ".glb", ".gltf", ".off")


def load_mesh_file(path: Path, referenced_by: Path, where: str, budget: FaceBudget,
                   warnings: list[str]) -> trimesh.Trimesh | None:
    """Triangle mesh of ``path``; errors name the referencing file and element (``where``).

    A file without triangles (zero bytes, or vertices only) gives None and a warning naming it:
    the piece is dropped, and the user is told which file. Faces are counted against ``budget``
    before the file is parsed, and again once it is (quads and n-gons make more triangles).
    """
    if not path.is_file():
        raise InputFileError(referenced_by, f"{where}: mesh file {path} not found")
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise InputFileError(referenced_by, f"{where}: unsupported mesh format {path.suffix!r} ({path})")
    try:
        empty = path.stat().st_size == 0
        declared = None if empty else declared_faces(path)
    except OSError as e:
        raise InputFileError(referenced_by, f"{where}: cannot read mesh {path}: {e.strerror or e}") from None
    if empty:
        warnings.append(f"{where}: mesh file {path} is empty (0 bytes); that piece is skipped")
        return None
    if declared is not None:
        budget.check(declared, f"mesh {path}", referenced_by, where)
    try:
        kwargs = {"skip_materials": True} if path.suffix.lower() == ".obj" else {}
        loaded = trimesh.load(str(path), force="mesh", process=False, **kwargs)
    except Exception as e:  # trimesh raises many types for corrupt files
        raise InputFileError(referenced_by, f"{where}: cannot read mesh {shorten(str(path), 200)}: "
                                            f"{shorten(str(e), 200)}") from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        # force="mesh" gives an empty Scene-derived object for files without faces
        warnings.append(f"{where}: mesh file {path} has no triangles; that piece is skipped")
        return None
    budget.admit(len(loaded.faces), f"mesh {path}", referenced_by, where)
    vertices = np.asarray(loaded.vertices, float)
    if not np.isfinite(vertices).all() or np.abs(vertices).max() > MAX_COORDINATE:
        raise InputFileError(referenced_by, f"{where}: mesh {path} has vertices that are not finite or beyond "
                                            f"+-{MAX_COORDINATE:g}")
    return trimesh.Trimesh(vertices, np.asarray(loaded.faces), process=False)


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
