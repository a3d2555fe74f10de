"""Writing an imported object as the files of one converted object directory, and reading it back.

Layout: ``structure.json`` (canonical O), ``parts/<id>.obj`` (normalised frame), ``boxes.json``
(per-part boxes) and ``meta.json`` (scale, source, part names, warnings). A converted folder is
what travels where the sources cannot (a pool of URDFs with their textured meshes is several times
its size), and ``jax3dc data import`` renders it like the source it came from.
"""

from __future__ import annotations

import json
import re
from dataclasses import replace
from pathlib import Path

from data_pipeline.importers.assemble import ImportedObject
from jax3dc.errors import InputFileError, StructureError
from jax3dc.geometry.parts import load_parts, part_boxes, save_parts
from jax3dc.structure import parse_structure, save_boxes, to_json

_PART_FILE = re.compile(r"^\d+\.(obj|stl|ply|glb)$")


def write_imported(obj: ImportedObject, out_dir: Path) -> None:
    """Write ``obj`` under ``out_dir``; part files left from an earlier conversion are replaced."""
    out_dir = Path(out_dir)
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        parts_dir = out_dir / "parts"
        if parts_dir.is_dir():
            for stale in parts_dir.iterdir():
                if _PART_FILE.match(stale.name):
                    stale.unlink()
        save_parts(obj.parts, parts_dir)
        (out_dir / "structure.json").write_text(to_json(obj.structure) + "\n")
        save_boxes(obj.boxes, out_dir / "boxes.json")
        (out_dir / "meta.json").write_text(json.dumps(obj.meta, indent=1) + "\n")
    except OSError as e:
        raise InputFileError(out_dir, f"cannot write the converted object: {e.strerror or e}") from None


def is_converted(path: Path) -> bool:
    """Whether ``path`` is a folder written by :func:`write_imported`."""
    path = Path(path)
    return all((path / name).is_file() for name in ("structure.json", "meta.json")) and (path / "parts").is_dir()


def read_imported(path: Path) -> ImportedObject:
    """The object a converted folder holds; its structure must name exactly its part files."""
    path = Path(path)
    parts = load_parts(path / "parts")
    try:
        meta = json.loads((path / "meta.json").read_text())
        structure = parse_structure((path / "structure.json").read_text(), part_ids=parts)
    except (OSError, ValueError, StructureError) as e:
        raise InputFileError(path, f"not a readable converted object: {e}") from None
    if not isinstance(meta, dict):
        raise InputFileError(path / "meta.json", "must hold a JSON object")
    names = meta.get("part_names") or {}
    if not isinstance(names, dict) or not all(isinstance(v, str) for v in names.values()):
        raise InputFileError(path / "meta.json", "part_names must map part ids to names")
    # structure.json keeps no names (SPEC §2); the parts' names travel in meta.json, and records
    # built from the folder must carry them as the source's own records do (stage 1's part kinds)
    nodes = {pid: replace(node, name=names.get(str(pid), node.name)) for pid, node in structure.nodes.items()}
    return ImportedObject(replace(structure, nodes=nodes), parts, part_boxes(parts), meta)
