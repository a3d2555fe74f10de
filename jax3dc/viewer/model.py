"""What the viewer's side panel lists, read from the JSON chunk of a GLB written by
``jax3dc.export.gltf``: per part its id, label, name, parent, material and joint; the relations
and the scale. The page's JavaScript loads the same GLB for the geometry and finds each part's
node by its ``part_id`` extra.
"""

from __future__ import annotations

import json
import struct
from dataclasses import dataclass
from typing import Any

from jax3dc.errors import InputFileError

GLB_MAGIC = b"glTF"
JSON_CHUNK = 0x4E4F534A  # "JSON" little-endian


@dataclass(frozen=True)
class ViewerModel:
    """The object as the page lists it; lengths as in the GLB (metres), angles in radians."""

    parts: list[dict[str, Any]]  # {"id", "label", "name", "parent", "material", "joint", "object"} in file order
    relations: list[dict[str, Any]]
    scale_m_per_nu: float


def glb_json(glb: bytes, where: str) -> dict[str, Any]:
    """The JSON chunk of a binary glTF (the first chunk, as the format requires)."""
    if len(glb) < 20 or glb[:4] != GLB_MAGIC:
        raise InputFileError(where, "not a binary glTF (GLB) file")
    length, kind = struct.unpack_from("<II", glb, 12)
    if kind != JSON_CHUNK or 20 + length > len(glb):
        raise InputFileError(where, "GLB without a readable JSON chunk")
    try:
        return json.loads(glb[20:20 + length].decode("utf-8"))
    except (UnicodeDecodeError, ValueError) as e:
        raise InputFileError(where, f"GLB JSON chunk is not JSON: {e}") from None


def _mark_objects(parts: list[dict[str, Any]]) -> None:
    """Each part's ``object``: the id of its tree's root (SPEC §2: one tree per object), so the page
    can list a scene's objects apart."""
    parent = {p["id"]: p["parent"] for p in parts}
    for p in parts:
        root, seen = p["id"], set()
        while parent.get(root) is not None and root not in seen:  # a parent outside the file ends the walk
            seen.add(root)
            root = parent[root]
        p["object"] = root


def viewer_model(glb: bytes, where: str) -> ViewerModel:
    """The parts, joints and relations of a jax3dc GLB; a GLB from elsewhere is an input error
    (its nodes lack the ``part_id`` extras that say which node is which part)."""
    doc = glb_json(glb, where)
    nodes = doc.get("nodes") or []
    parent_of: dict[int, int] = {child: i for i, node in enumerate(nodes) for child in node.get("children", [])}
    parts = []
    for index, node in enumerate(nodes):
        extras = node.get("extras")
        if not isinstance(extras, dict) or "part_id" not in extras:
            continue
        up = parent_of.get(index)
        while up is not None and "part_id" not in (nodes[up].get("extras") or {}):
            up = parent_of.get(up)
        parts.append({
            "id": int(extras["part_id"]),
            "label": str(node.get("name", "")),
            "name": extras.get("name"),
            "parent": None if up is None else int(nodes[up]["extras"]["part_id"]),
            "material": extras.get("material"),
            "joint": extras.get("joint"),
        })
    if not parts:
        raise InputFileError(where, "no node carries a part_id extra: not a glTF written by jax3dc export")
    _mark_objects(parts)
    scene = (doc.get("scenes") or [{}])[doc.get("scene", 0)]
    meta = (scene.get("extras") or {}).get("jax3dc") or {}
    return ViewerModel(parts, list(meta.get("relations", [])), float(meta.get("scale_m_per_nu", 1.0)))
