"""Part meshes on disk and in memory: one triangle mesh per part id, in the normalised frame.

A parts directory holds ``<id>.obj`` (or ``.stl``, ``.ply``, ``.glb``) per part; ids are the
positive integers of SPEC §2. Other files (``parts.json``, ``.mtl``) are ignored. Everything here
is numpy / trimesh: no JAX.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

from jax3dc.errors import InputFileError, shorten
from jax3dc.geometry.mesh_size import MAX_COORDINATE, MAX_PART_FACES, declared_faces
from jax3dc.structure.schema import Box

PART_SUFFIXES: tuple[str, ...] = (".obj", ".stl", ".ply", ".glb")


def load_parts(directory: str | Path, max_faces: int = MAX_PART_FACES) -> dict[int, trimesh.Trimesh]:
    """Part id -> mesh of every ``<id>.<suffix>`` file in ``directory``, sorted by id.

    A GLB (a scene) is flattened into one mesh with its node transforms applied. Raises
    InputFileError for a missing directory, no part files, a mesh file whose name is not a
    positive integer, two files with the same id, or a file that cannot be read or has no
    triangles, or more than ``max_faces`` triangles in one file (counted before the mesh is built).
    """
    directory = Path(directory)
    if not directory.is_dir():
        raise InputFileError(directory, "parts directory not found")
    paths: dict[int, Path] = {}
    for path in sorted(directory.iterdir()):
        if path.suffix.lower() not in PART_SUFFIXES or not path.is_file():
            continue
        stem = path.stem
        if not (stem.isascii() and stem.isdigit() and int(stem) >= 1):
            raise InputFileError(path, "part file names must be a positive integer part id, e.g. 3.obj")
        part_id = int(stem)
        if part_id in paths:
            raise InputFileError(path, f"part {part_id} is given twice (also {paths[part_id].name})")
        paths[part_id] = path
    if not paths:
        raise InputFileError(directory, f"no part meshes (<id>{'|'.join(PART_SUFFIXES)}) in the directory")
    return {part_id: load_part_mesh(paths[part_id], max_faces) for part_id in sorted(paths)}


def load_part_mesh(path: Path, max_faces: int = MAX_PART_FACES) -> trimesh.Trimesh:
    """One part's triangles exactly as stored (no merging or reordering of vertices)."""
    kwargs = {"skip_materials": True} if path.suffix.lower() == ".obj" else {}
    try:
        declared = declared_faces(path)
    except OSError as e:
        raise InputFileError(path, f"cannot read the mesh: {e.strerror or e}") from None
    if declared is not None and declared > max_faces:
        raise InputFileError(path, f"the mesh has {declared} faces; a part has at most {max_faces} "
                                   "(raise it with --max-part-faces)")
    try:
        loaded = trimesh.load(str(path), force="mesh", process=False, **kwargs)
    except Exception as e:  # trimesh raises many exception types for corrupt files
        raise InputFileError(path, f"cannot read the mesh: {shorten(str(e), 200)}") from None
    faces = np.asarray(getattr(loaded, "faces", np.zeros((0, 3))), dtype=np.int64).reshape(-1, 3)
    vertices = np.asarray(getattr(loaded, "vertices", np.zeros((0, 3))), dtype=np.float64).reshape(-1, 3)
    if len(faces) == 0:
        raise InputFileError(path, "the mesh has no triangles")
    if len(faces) > max_faces:
        raise InputFileError(path, f"the mesh has {len(faces)} triangles; a part has at most {max_faces} "
                                   "(raise it with --max-part-faces)")
    if not np.isfinite(vertices).all():
        raise InputFileError(path, "the mesh has non-finite vertex coordinates")
    if np.abs(vertices).max() > MAX_COORDINATE:
        raise InputFileError(path, f"the mesh has vertex coordinates beyond +-{MAX_COORDINATE:g}")
    return trimesh.Trimesh(vertices, faces, process=False)


def save_parts(parts: dict[int, trimesh.Trimesh], directory: str | Path) -> None:
    """Write each part as ``<id>.obj`` (vertices and triangles only; same input, same bytes)."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    for part_id in sorted(parts):
        (directory / f"{part_id}.obj").write_text(obj_text(parts[part_id]))


def obj_text(mesh: trimesh.Trimesh) -> str:
    """Wavefront OBJ of ``mesh``: ``v`` lines with 9 significant digits, 1-based ``f`` lines."""
    vertices = np.asarray(mesh.vertices, dtype=np.float64) + 0.0  # + 0.0 turns -0.0 into 0.0
    faces = np.asarray(mesh.faces, dtype=np.int64) + 1
    lines = ["v %.9g %.9g %.9g" % (x, y, z) for x, y, z in vertices.tolist()]
    lines += ["f %d %d %d" % (a, b, c) for a, b, c in faces.tolist()]
    return "\n".join(lines) + "\n"


def part_boxes(parts: dict[int, trimesh.Trimesh]) -> dict[int, Box]:
    """Axis-aligned box of each part: centroid = bounding-box centre, extent = its size."""
    boxes = {}
    for part_id in sorted(parts):
        lo, hi = np.asarray(parts[part_id].bounds, dtype=np.float64)
        boxes[part_id] = Box(centroid=tuple(float(v) for v in (lo + hi) / 2),
                             extent=tuple(float(v) for v in hi - lo))
    return boxes


def parts_bounds(parts: dict[int, trimesh.Trimesh]) -> np.ndarray:
    """[2, 3] lower and upper corner of the box around all parts."""
    bounds = np.array([np.asarray(m.bounds, dtype=np.float64) for m in parts.values()])
    return np.stack([bounds[:, 0].min(axis=0), bounds[:, 1].max(axis=0)])


def normalise_parts(parts: dict[int, trimesh.Trimesh]) -> tuple[dict[int, trimesh.Trimesh], float]:
    """Parts moved and scaled so the box around all of them is centred and its largest side is 1.

    Returns the new parts and the scale kept beside the structure (SPEC §2): input units per nu,
    i.e. metres per nu when the input is in metres. Raises ValueError on no parts or a
    zero-size object, which have no normalised frame.
    """
    if not parts:
        raise ValueError("no parts to normalise")
    lo, hi = parts_bounds(parts)
    size = float((hi - lo).max())
    if not np.isfinite(size) or size <= 0.0:
        raise ValueError("the parts have zero size: no normalised frame")
    centre = (lo + hi) / 2
    out = {}
    for part_id in sorted(parts):
        vertices = (np.asarray(parts[part_id].vertices, dtype=np.float64) - centre) / size
        out[part_id] = trimesh.Trimesh(vertices, np.asarray(parts[part_id].faces), process=False)
    return out, size
