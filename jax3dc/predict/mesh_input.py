"""Stage-1 mesh backend input: a part-segmented mesh made by any external tool.

Two layouts are read (SPEC §1):
* GLB / glTF with one node per part (node transforms applied; a node holding several primitives is
  one part);
* Wavefront OBJ with groups (``g``) or objects (``o``): each group is one part. trimesh merges OBJ
  groups into one mesh, so the few OBJ statements that matter (``v``, ``f``, ``g``, ``o``) are read
  here; texture and normal indices (``f 1/2/3``) are ignored, polygons are fanned into triangles.
  A file with ``o`` lines has one part per object and its ``g`` lines are ignored (Blender writes
  ``o name`` per object, then optional ``g`` groups inside it, e.g. one per material).

Up axis: our frame is +Z up with the front at -Y. A file made with +Y up (glTF's convention, which
Blender's glTF exporter follows) is read with ``up="y"``: (x, y, z) -> (x, -z, y), so its +Y becomes
+Z and its front (+Z) becomes -Y.

Part ids: when every part name is a positive integer, the names are the ids (a mesh written by
this project, or by a tool told to name parts by id, round-trips unchanged). Otherwise parts are
numbered 1..K in natural name order ("leg2" before "leg10"), the same on every run.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import trimesh

from jax3dc.errors import InputFileError
from jax3dc.palette import PALETTE_SIZE

MESH_SUFFIXES: tuple[str, ...] = (".glb", ".gltf", ".obj")
UP_AXES: tuple[str, ...] = ("z", "y")
Y_UP_TO_Z_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])  # a proper rotation (det 1)


def natural_key(name: str) -> list:
    """Sort key that compares digit runs as numbers: part2 < part10."""
    return [int(t) if t.isdigit() else t for t in re.split(r"(\d+)", name)]


def number_parts(named: dict[str, trimesh.Trimesh]) -> tuple[dict[int, trimesh.Trimesh], dict[int, str]]:
    """(part id -> mesh, part id -> source name): integer names (1..PALETTE_SIZE) are the ids (and
    no names are kept), else parts are numbered 1..K in natural name order."""
    if (all(n.isascii() and n.isdigit() and 1 <= int(n) <= PALETTE_SIZE for n in named)
            and len({int(n) for n in named}) == len(named)):
        order = sorted(named, key=int)
        return {int(n): named[n] for n in order}, {}  # the names are the ids: nothing more to keep
    order = sorted(named, key=natural_key)
    return ({pid: named[n] for pid, n in enumerate(order, start=1)},
            {pid: n for pid, n in enumerate(order, start=1)})


def _checked(path: Path, name: str, vertices: np.ndarray, faces: np.ndarray) -> trimesh.Trimesh:
    if len(faces) == 0:
        raise InputFileError(path, f"part {name!r} has no triangles")
    if not np.isfinite(vertices).all():
        raise InputFileError(path, f"part {name!r} has non-finite vertex coordinates")
    return trimesh.Trimesh(vertices, faces, process=False)


def _obj_index(token: str, count: int, path: Path, line: int) -> int:
    try:
        i = int(token.split("/")[0])
    except ValueError:
        raise InputFileError(path, f"line {line}: bad face index {token!r}") from None
    i = i - 1 if i > 0 else count + i  # OBJ indices are 1-based; negative ones count back from the end
    if not 0 <= i < count:
        raise InputFileError(path, f"line {line}: face index {token!r} refers to no vertex read so far")
    return i


def read_obj_groups(path: Path) -> dict[str, trimesh.Trimesh]:
    """Group name -> mesh of an OBJ file (faces before any ``g``/``o`` form the group "default")."""
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as e:
        raise InputFileError(path, f"cannot read the mesh: {e.strerror or e}") from None
    vertices: list[list[float]] = []
    faces: dict[str, list[list[int]]] = {}
    group = "default"
    part_statements = ("o",) if re.search(r"^[ \t]*o[ \t]", text, flags=re.MULTILINE) else ("g",)
    for number, raw in enumerate(text.splitlines(), start=1):
        fields = raw.split("#", 1)[0].split()
        if not fields:
            continue
        if fields[0] == "v":
            try:
                vertices.append([float(v) for v in fields[1:4]])
            except ValueError:
                raise InputFileError(path, f"line {number}: bad vertex {raw.strip()!r}") from None
            if len(vertices[-1]) != 3:
                raise InputFileError(path, f"line {number}: a vertex needs 3 coordinates")
        elif fields[0] in part_statements:
            group = " ".join(fields[1:]) or "default"
        elif fields[0] == "f":
            if len(fields) < 4:
                raise InputFileError(path, f"line {number}: a face needs at least 3 vertices")
            ids = [_obj_index(t, len(vertices), path, number) for t in fields[1:]]
            faces.setdefault(group, []).extend([ids[0], ids[k], ids[k + 1]] for k in range(1, len(ids) - 1))
    if not faces:
        raise InputFileError(path, "the mesh has no faces (an OBJ with one group of faces per part is expected)")
    all_vertices = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
    out = {}
    for name, tris in faces.items():
        tris_array = np.asarray(tris, dtype=np.int64)
        used, local = np.unique(tris_array, return_inverse=True)  # each part keeps only its own vertices
        out[name] = _checked(path, name, all_vertices[used], local.reshape(-1, 3))
    return out


def read_gltf_nodes(path: Path) -> dict[str, trimesh.Trimesh]:
    """Node name -> mesh (in the scene frame) of a GLB / glTF file."""
    try:
        scene = trimesh.load(str(path), force="scene", process=False)
    except Exception as e:  # trimesh raises many exception types for corrupt files
        raise InputFileError(path, f"cannot read the mesh: {e}") from None
    pieces: dict[str, list[trimesh.Trimesh]] = {}
    for node in scene.graph.nodes_geometry:
        transform, geometry_name = scene.graph[node]
        geometry = scene.geometry.get(geometry_name)
        if not isinstance(geometry, trimesh.Trimesh) or len(geometry.faces) == 0:
            continue  # point clouds, lines and empty primitives are not parts
        mesh = trimesh.Trimesh(np.asarray(geometry.vertices, dtype=np.float64), np.asarray(geometry.faces),
                               process=False)
        mesh.apply_transform(np.asarray(transform, dtype=np.float64))
        pieces.setdefault(str(node), []).append(mesh)
    if not pieces:
        raise InputFileError(path, "the mesh has no triangles (a GLB with one mesh node per part is expected)")
    out = {}
    for name, meshes in pieces.items():
        merged = meshes[0] if len(meshes) == 1 else trimesh.util.concatenate(meshes)
        out[name] = _checked(path, name, np.asarray(merged.vertices, dtype=np.float64), np.asarray(merged.faces))
    return out


def load_segmented_mesh(path: str | Path, up: str = "z") -> tuple[dict[int, trimesh.Trimesh], dict[int, str]]:
    """(part id -> mesh in the file's units, turned to +Z up; part id -> the part's name in the file).

    ``up``: the file's up axis, "z" (ours, and what jax3dc's exports write) or "y" (glTF's).
    """
    if up not in UP_AXES:
        raise ValueError(f"up must be one of {UP_AXES}, got {up!r}")
    path = Path(path)
    if not path.is_file():
        raise InputFileError(path, "mesh file not found")
    suffix = path.suffix.lower()
    if suffix not in MESH_SUFFIXES:
        raise InputFileError(path, f"unsupported mesh format {suffix or '(none)'}; "
                                   f"use one of {', '.join(MESH_SUFFIXES)}")
    named = read_obj_groups(path) if suffix == ".obj" else read_gltf_nodes(path)
    if len(named) > PALETTE_SIZE:
        raise InputFileError(path, f"the mesh has {len(named)} parts; at most {PALETTE_SIZE} are supported "
                                   "(one segmentation colour per part)")
    if up == "y":
        named = {name: trimesh.Trimesh(np.asarray(mesh.vertices) @ Y_UP_TO_Z_UP.T, mesh.faces, process=False)
                 for name, mesh in named.items()}
    return number_parts(named)
