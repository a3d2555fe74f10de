"""Loading the geometry of links: mesh files (materials and textures ignored) and primitives.

Only geometry matters for parts, so OBJ material libraries are skipped: real datasets ship
``.mtl`` files that name texture images which are not there.

Real datasets also ship mesh files that cannot be a piece of a part: missing, empty, unreadable,
or ones MuJoCo refuses (fewer than 4 vertices, all on one line; flat, where a colliding geom needs
a convex hull). Those raise :class:`UnusableMesh`, which the readers turn into a dropped piece and
a warning naming the file; what points at hostile input (faces over the cap, coordinates that are
not finite) stays an InputFileError that refuses the object.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import trimesh

from data_pipeline.importers.limits import FaceBudget
from jax3dc.errors import InputFileError, shorten
from jax3dc.geometry.mesh_size import MAX_COORDINATE, declared_faces

MESH_SUFFIXES = (".obj", ".stl", ".ply", ".glb", ".gltf", ".off")
_UNIT_BOX = trimesh.creation.box(bounds=((0.0, 0.0, 0.0), (1.0, 1.0, 1.0)))
OBJ_VERTEX = re.compile(rb"^v[ \t]+(\S+)[ \t]+(\S+)[ \t]+(\S+)", re.MULTILINE)
OBJ_FACE = re.compile(rb"^f[ \t]([^\n]*)", re.MULTILINE)
OBJ_INDEX = re.compile(rb"(?<=[ \t])-?\d+")  # the vertex index of each "v/vt/vn" corner of a face line
FLAT_TOLERANCE = 1e-9
"""Thickness, relative to a mesh's largest spread, below which its vertices count as coplanar
(or collinear): far below any real part, far above float round-off of a flat OBJ (~1e-13)."""


class UnusableMesh(Exception):
    """A mesh file that cannot be a piece of a part; the message names the file and the reason.

    Not an InputFileError: readers catch it and drop the one piece, since refusing a whole real
    object for one bad piece among good ones loses the object.
    """


def check_mesh_file(path: Path) -> None:
    """UnusableMesh when ``path`` is not a file or is empty: the checks that need no parsing."""
    if not path.is_file():
        raise UnusableMesh(f"mesh file {path} not found")
    try:
        empty = path.stat().st_size == 0
    except OSError as e:
        raise UnusableMesh(f"cannot read mesh file {path}: {e.strerror or e}") from None
    if empty:
        raise UnusableMesh(f"mesh file {path} is empty (0 bytes)")


def load_mesh_file(path: Path, referenced_by: Path, where: str, budget: FaceBudget) -> trimesh.Trimesh:
    """Triangle mesh of ``path``; errors name the referencing file and element (``where``).

    A file that is missing, of a format not read here, unreadable or without triangles raises
    UnusableMesh. Faces are counted against ``budget`` before the file is parsed, and again once
    it is (quads and n-gons make more triangles).
    """
    check_mesh_file(path)
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise UnusableMesh(f"mesh file {path} has an unsupported format {path.suffix!r}")
    try:
        declared = declared_faces(path)
    except OSError as e:
        raise UnusableMesh(f"cannot read mesh file {path}: {e.strerror or e}") from None
    if declared is not None:
        budget.check(declared, f"mesh {path}", referenced_by, where)
    try:
        kwargs = {"skip_materials": True} if path.suffix.lower() == ".obj" else {}
        loaded = trimesh.load(str(path), force="mesh", process=False, **kwargs)
    except Exception as e:  # trimesh raises many types for corrupt files
        raise UnusableMesh(f"cannot read mesh file {shorten(str(path), 200)}: {shorten(str(e), 200)}") from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        # force="mesh" gives an empty Scene-derived object for files without faces (or garbage bytes)
        raise UnusableMesh(f"mesh file {path} has no readable triangles")
    budget.admit(len(loaded.faces), f"mesh {path}", referenced_by, where)
    vertices = np.asarray(loaded.vertices, float)
    if not np.isfinite(vertices).all() or np.abs(vertices).max() > MAX_COORDINATE:
        raise InputFileError(referenced_by, f"{where}: mesh {path} has vertices that are not finite or beyond "
                                            f"+-{MAX_COORDINATE:g}")
    return trimesh.Trimesh(vertices, np.asarray(loaded.faces), process=False)


def _obj_used_vertices(data: bytes, path: Path) -> tuple[np.ndarray, int]:
    """The vertices that an OBJ file's faces use (a file may list others, as a full load drops
    them), and its face count, from the ``v`` and ``f`` lines alone."""
    last = data.rfind(b"\nv")
    end = data.find(b"\n", last + 1) if last >= 0 else -1
    faces = OBJ_FACE.findall(data)
    try:
        vertices = np.array(OBJ_VERTEX.findall(data, 0, len(data) if end < 0 else end), dtype=float).reshape(-1, 3)
        used = np.array(OBJ_INDEX.findall(b" " + b" ".join(faces)), dtype=np.int64)
    except ValueError:
        raise UnusableMesh(f"mesh file {path} has a vertex line that is not three numbers") from None
    if len(used) == 0 or used.min() < 0:  # relative indices: keep every vertex (a box at least as large)
        return vertices, len(faces)
    if used.min() == 0 or used.max() > len(vertices):
        raise UnusableMesh(f"mesh file {path} has a face naming vertex {used.max() if used.min() else 0} "
                           f"of {len(vertices)}")
    return vertices[np.unique(used) - 1], len(faces)


def load_mesh_bounds(path: Path, referenced_by: Path, where: str, budget: FaceBudget) -> trimesh.Trimesh:
    """The axis-aligned box of the vertices a mesh file's faces use, as a 12-triangle mesh.

    For imports that need part boxes and joints but no surface, e.g. checking the frames of a
    whole dataset: an OBJ's ``v`` and ``f`` lines are read without building a mesh (faster
    than :func:`load_mesh_file`); other formats are loaded in full. A
    file that a full load would drop (missing, empty, no faces, too few vertices) is dropped alike.
    """
    if path.suffix.lower() != ".obj":
        vertices = np.asarray(load_mesh_file(path, referenced_by, where, budget).vertices)
    else:
        check_mesh_file(path)
        try:
            data = path.read_bytes()
        except OSError as e:
            raise UnusableMesh(f"cannot read mesh file {path}: {e.strerror or e}") from None
        vertices, faces = _obj_used_vertices(data, path)
        if faces == 0:
            raise UnusableMesh(f"mesh file {path} has no readable triangles")
        budget.admit(faces, f"mesh {path}", referenced_by, where)
        if not np.isfinite(vertices).all() or np.abs(vertices).max(initial=0.0) > MAX_COORDINATE:
            raise InputFileError(referenced_by, f"{where}: mesh {path} has vertices that are not finite or beyond "
                                                f"+-{MAX_COORDINATE:g}")
    reason = refusal(vertices, colliding=False)
    if reason is not None:
        raise UnusableMesh(f"mesh file {path} {reason}")
    low, high = vertices.min(axis=0), vertices.max(axis=0)
    return trimesh.Trimesh(low + _UNIT_BOX.vertices * (high - low), _UNIT_BOX.faces, process=False)


def refusal(vertices: np.ndarray, colliding: bool) -> str | None:
    """Why MuJoCo refuses a mesh of these (finite) ``vertices``, or None: fewer than 4 distinct
    vertices, or all on one line, whatever the geom; all in one plane, only for a ``colliding``
    geom (MuJoCo needs its convex hull; a visual-only flat mesh, like a door panel, is fine)."""
    if len(vertices) < 4:
        return f"has {len(vertices)} vertices; MuJoCo needs at least 4 vertices"
    spread = np.linalg.svd(vertices - vertices.mean(axis=0), compute_uv=False)
    if spread[2] > FLAT_TOLERANCE * spread[0]:
        return None  # a solid, so at least 4 distinct vertices
    distinct = len(np.unique(vertices, axis=0))
    if distinct < 4:
        return f"has {distinct} distinct vertices; MuJoCo needs at least 4 vertices"
    if spread[1] <= FLAT_TOLERANCE * spread[0]:
        return "has no area: its vertices all lie on one line"
    if colliding:
        return "has zero volume: its vertices all lie in one plane, so a colliding geom has no convex hull"
    return None


def transformed(mesh: trimesh.Trimesh, matrix: np.ndarray) -> trimesh.Trimesh:
    """A copy of ``mesh`` moved by the 4x4 ``matrix`` (may include scaling); a mirroring matrix
    reverses the faces, so they keep facing outwards. Built directly rather than through
    ``Trimesh.apply_transform``, which costs several times more in cache bookkeeping."""
    linear = matrix[:3, :3]
    faces = np.asarray(mesh.faces)
    return trimesh.Trimesh(np.asarray(mesh.vertices) @ linear.T + matrix[:3, 3],
                           faces[:, ::-1] if np.linalg.det(linear) < 0 else faces, process=False)


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
