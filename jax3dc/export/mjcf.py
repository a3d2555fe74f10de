"""MJCF (MuJoCo) export: one body per part nested as in the structure, in metres.

Each body's frame is at its joint pivot (or its parent's frame when rigid, see ``assembly``), so
hinge and slide joints sit at the body origin with the structure's axis; ranges are limited.
Geoms carry the family's density and friction, and a material with the family colour.

Mass follows the same solid as the URDF inertials (``jax3dc.geometry.mass``): a closed mesh uses
MuJoCo's exact mesh inertia, an open one its convex hull (``inertia="convex"``), and a flat or
degenerate part — which MuJoCo refuses as a mesh ("coplanar vertices", "volume too small") —
becomes a box geom of its bounds, at least 1 mm thick.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import trimesh

from jax3dc.export.assembly import ExportPart, assemble, check_nesting, unit_axis, vec
from jax3dc.export.files import write_files
from jax3dc.geometry.parts import obj_text
from jax3dc.materials import MATERIALS
from jax3dc.structure.schema import Structure

MESH_DIR = "meshes"


def mjcf_model(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float = 1.0, *,
               model_name: str = "object", free_roots: bool = False) -> tuple[str, dict[str, bytes]]:
    """MJCF text and its mesh files ({path relative to the MJCF file: bytes}).

    ``free_roots`` gives each root a free joint (an object that can fall or be pushed); by default
    roots are fixed to the world and the model has exactly the structure's joints.
    """
    check_nesting(structure)
    export = assemble(structure, parts, scale)
    root = ET.Element("mujoco", model=model_name)
    ET.SubElement(root, "compiler", angle="radian", meshdir=MESH_DIR, autolimits="true")
    asset = ET.SubElement(root, "asset")
    for material_id, material in sorted(structure.materials.items()):
        ET.SubElement(asset, "material", name=f"material_{material_id}", rgba=vec(MATERIALS[material.family].rgba))
    files: dict[str, bytes] = {}
    for part in export:
        if part.solid != "box":
            file_name = f"{part.part_id}.obj"
            files[f"{MESH_DIR}/{file_name}"] = obj_text(part.mesh).encode()
            ET.SubElement(asset, "mesh", name=f"mesh_{part.part_id}", file=file_name,
                          inertia="exact" if part.solid == "mesh" else "convex")
    worldbody = ET.SubElement(root, "worldbody")
    bodies: dict[int, ET.Element] = {}
    for part in export:
        parent = worldbody if part.parent is None else bodies[part.parent]
        body = ET.SubElement(parent, "body", name=part.label, pos=vec(part.offset_m))
        bodies[part.part_id] = body
        if part.parent is None and free_roots:
            ET.SubElement(body, "freejoint", name=f"free_{part.part_id}")
        if part.joint is not None:
            ET.SubElement(body, "joint", name=f"joint_{part.part_id}", type=part.joint.type,
                          pos="0 0 0", axis=vec(unit_axis(part.joint)), range=vec(part.range_si), limited="true")
        ET.SubElement(body, "geom", _geom_attributes(part))
    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="unicode") + "\n", files


def _geom_attributes(part: ExportPart) -> dict[str, str]:
    common = {
        "material": f"material_{part.material_id}",
        "density": vec([part.props.density_kg_m3]),
        "friction": vec([part.props.friction, 0.005, 0.0001]),
    }
    if part.solid == "box":
        centre, size = part.box_fallback()
        return {"name": f"geom_{part.part_id}", "type": "box", "pos": vec(centre), "size": vec(size / 2), **common}
    return {"name": f"geom_{part.part_id}", "type": "mesh", "mesh": f"mesh_{part.part_id}", **common}


def export_mjcf(structure: Structure, parts: dict[int, trimesh.Trimesh], out_dir: str | Path, scale: float = 1.0, *,
                model_name: str = "object", free_roots: bool = False) -> Path:
    """Write ``<out_dir>/<model_name>.xml`` and ``<out_dir>/meshes/<id>.obj``; returns the XML path."""
    text, files = mjcf_model(structure, parts, scale, model_name=model_name, free_roots=free_roots)
    return write_files(Path(out_dir), f"{model_name}.xml", text, files)
