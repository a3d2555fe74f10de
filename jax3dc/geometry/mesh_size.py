"""How many faces a mesh file holds, counted without building the mesh.

Mesh files come from datasets, the web and other tools: an OBJ of 5 million faces on 4 vertices
is 60 MB of text that trimesh would turn into gigabytes before any check could run. Readers
count first (OBJ ``f`` lines, the STL/PLY/OFF headers, glTF accessor counts) and refuse a file
over their cap in one line.
"""

from __future__ import annotations

import json
import re
import struct
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from jax3dc.errors import Jax3dcError

MAX_PART_FACES = 2_000_000
"""Triangles of one part mesh file read by load_parts (a part of the dataset has under 100 k)."""
PHYSICS_MAX_FACES = 300_000
"""Triangles of one object the physics check and the MJCF export (the same model) take unless
raised: their time and memory grow with them (a 327 k-triangle part: check 62 s and 1.0 GB, MJCF
export 10 s and 0.8 GB on 2 CPU cores; 1.3 M: check 156 s and 3.9 GB), while the largest real
object of the training pool has 247 k."""
MAX_COORDINATE = 1e12
"""Vertices beyond this (e.g. +-1e308) overflow volumes, convex hulls and normalisation."""

_CHUNK = 1 << 24


def check_object_faces(parts: Mapping[int, Any], cap: int, task: str, flag: str = "--max-faces") -> None:
    """Refuse, in one line naming the cap and how to raise it, an object whose part meshes (anything
    with ``faces``) hold more than ``cap`` triangles."""
    faces_per_part = {part_id: len(mesh.faces) for part_id, mesh in parts.items()}
    total = sum(faces_per_part.values())
    if total > cap:
        largest = max(faces_per_part, key=faces_per_part.get)
        raise Jax3dcError(f"the parts have {total} triangles (part {largest}: {faces_per_part[largest]}); {task} "
                          f"takes at most {cap} (raise it with {flag})")


def _occurrences(path: Path, needle: bytes, start: bytes = b"") -> int:
    """Occurrences of ``needle`` in ``start`` + the file, read in chunks (a 100 MB OBJ never sits
    in memory at once)."""
    count, previous = 0, start
    with path.open("rb") as f:
        while chunk := f.read(_CHUNK):
            block = previous + chunk
            count += block.count(needle)
            previous = block[-(len(needle) - 1):]  # a needle split across two chunks is counted once
    return count


def _ply_faces(path: Path) -> int | None:
    with path.open("rb") as f:
        header = f.read(4096).split(b"end_header")[0]
    found = re.search(rb"element\s+face\s+(\d+)", header)
    return int(found.group(1)) if found else None


def _stl_faces(path: Path) -> int:
    with path.open("rb") as f:
        head = f.read(84)
    size = path.stat().st_size
    if len(head) == 84 and 84 + 50 * struct.unpack("<I", head[80:84])[0] == size:
        return struct.unpack("<I", head[80:84])[0]  # binary STL: the count is in the header
    return _occurrences(path, b"endfacet")


def _gltf_faces(path: Path) -> int | None:
    """Triangles an (embedded-JSON) glTF / GLB declares, from its accessors' counts."""
    data = path.read_bytes() if path.suffix.lower() == ".gltf" else None
    if data is None:
        with path.open("rb") as f:
            head = f.read(20)
            if len(head) < 20 or head[:4] != b"glTF":
                return None
            data = f.read(struct.unpack("<I", head[12:16])[0])
    try:
        doc = json.loads(data)
        accessors = doc.get("accessors", [])
        total = 0
        for mesh in doc.get("meshes", []):
            for primitive in mesh.get("primitives", []):
                index = primitive.get("indices", primitive.get("attributes", {}).get("POSITION"))
                total += int(accessors[index]["count"]) // 3
        return total
    except (ValueError, KeyError, IndexError, TypeError, AttributeError, RecursionError):
        return None  # trimesh reports the broken file when it reads it


def declared_faces(path: Path) -> int | None:
    """Faces a mesh file holds, counted without building the mesh; None when the format does not say."""
    suffix = path.suffix.lower()
    if suffix == ".obj":
        return _occurrences(path, b"\nf ", b"\n") + _occurrences(path, b"\nf\t", b"\n")
    if suffix == ".ply":
        return _ply_faces(path)
    if suffix == ".stl":
        return _stl_faces(path)
    if suffix in (".glb", ".gltf"):
        return _gltf_faces(path)
    if suffix == ".off":
        with path.open("rb") as f:
            words = f.read(4096).split()
        numbers = [w for w in words[1:4] if w.isdigit()] if words[:1] == [b"OFF"] else []
        return int(numbers[1]) if len(numbers) >= 2 else None
    return None


