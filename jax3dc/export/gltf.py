"""glTF (binary GLB) export: one node per part under its parent's node, PBR colours, and the
structure's joints and relations in node / scene ``extras`` so that a viewer or a game engine
gets an object it can articulate.

Node transforms are translations only (rest pose): each node's origin is its part frame (the
joint pivot for a jointed part; see ``assembly``) and its mesh is stored in that frame, in
metres. Node extras: ``part_id``, ``name`` (the semantic name, verbatim: JSON escapes it),
``material`` (family, description), ``joint`` (type, unit axis, pivot in object-frame metres,
range in rad or m) and the ``relations`` the part is in. Scene extras: the scale and all relations.

A scene of several objects (several roots, SPEC §2) gets one top node ``scene`` (extras:
``objects``, the root ids) with a node ``object_<root>`` per object (extras: ``object``, its root,
and ``parts``, its part ids) holding that object's root part, so each object is one subtree an
engine can move or hide alone. A single object keeps its root part as the top node.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh
from trimesh.visual.material import PBRMaterial

from jax3dc.export.assembly import ExportPart, assemble, object_label, objects, unit_axis
from jax3dc.export.files import write_files
from jax3dc.structure.schema import Relation, Structure

WORLD = "world"
SCENE_NODE = "scene"


def relation_extras(relation: Relation) -> dict:
    out = {"type": relation.type, "a": relation.a, "b": relation.b}
    if relation.plane is not None:
        out["plane"] = relation.plane
    return out


def _material(part: ExportPart) -> PBRMaterial:
    rgba = np.asarray(part.props.rgba, dtype=np.float64)
    return PBRMaterial(
        name=f"material_{part.material_id}",
        baseColorFactor=np.round(rgba * 255).astype(np.uint8),
        metallicFactor=1.0 if part.family == "Metal" else 0.0,
        roughnessFactor=0.4 if part.family in ("Metal", "Glass", "Ceramic") else 0.8,
        alphaMode="BLEND" if rgba[3] < 1 else "OPAQUE",
        doubleSided=True,
    )


def _node_extras(part: ExportPart, structure: Structure, scale: float) -> dict:
    material = structure.materials[part.material_id]
    extras: dict = {
        "part_id": part.part_id,
        "name": part.name,
        "material": {"id": part.material_id, "family": material.family, "desc": material.desc},
        "joint": None,
        "relations": [relation_extras(r) for r in structure.relations if part.part_id in (r.a, r.b)],
    }
    if part.joint is not None:
        extras["joint"] = {
            "type": part.joint.type,
            "axis": [float(v) for v in unit_axis(part.joint)],
            "pivot": [float(v) for v in np.asarray(part.joint.pivot, dtype=np.float64) * scale],
            "range": [float(v) for v in part.range_si],
            "range_unit": "rad" if part.joint.type == "hinge" else "m",
        }
    return extras


def gltf_scene(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float = 1.0) -> trimesh.Scene:
    """The export as a trimesh Scene: node per part named by its label, parented as in the tree."""
    export = assemble(structure, parts, scale)
    labels = {part.part_id: part.label for part in export}
    scene = trimesh.Scene(base_frame=WORLD)
    scene.metadata["jax3dc"] = {
        "scale_m_per_nu": float(scale),
        "relations": [relation_extras(r) for r in structure.relations],
    }
    top = _object_nodes(scene, objects(structure))
    for part in export:
        mesh = part.mesh.copy()
        mesh.visual = trimesh.visual.TextureVisuals(material=_material(part))
        scene.add_geometry(
            mesh,
            geom_name=f"mesh_{part.part_id}",
            node_name=part.label,
            parent_node_name=top[part.part_id] if part.parent is None else labels[part.parent],
            transform=trimesh.transformations.translation_matrix(part.offset_m),
            metadata=_node_extras(part, structure, scale),
        )
    return scene


def _object_nodes(scene: trimesh.Scene, trees: dict[int, list[int]]) -> dict[int, str]:
    """The node each root hangs from: the world for one object; for a scene, ``object_<root>``
    nodes under one ``scene`` node (see the module docstring)."""
    if len(trees) == 1:
        return {root: WORLD for root in trees}
    scene.graph.update(frame_from=WORLD, frame_to=SCENE_NODE, matrix=np.eye(4), metadata={"objects": list(trees)})
    for root, members in trees.items():
        scene.graph.update(frame_from=SCENE_NODE, frame_to=object_label(root), matrix=np.eye(4),
                           metadata={"object": root, "parts": members})
    return {root: object_label(root) for root in trees}


def gltf_bytes(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float = 1.0) -> bytes:
    """GLB bytes; the same structure and parts give the same bytes."""
    return gltf_scene(structure, parts, scale).export(file_type="glb", include_normals=False)


def export_gltf(structure: Structure, parts: dict[int, trimesh.Trimesh], out_dir: str | Path, scale: float = 1.0, *,
                model_name: str = "object") -> Path:
    """Write ``<out_dir>/<model_name>.glb``; returns its path."""
    return write_files(Path(out_dir), f"{model_name}.glb", gltf_bytes(structure, parts, scale), {})
