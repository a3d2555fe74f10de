"""URDF export: one link per part, revolute / prismatic / fixed joints, inertials, OBJ meshes.

Each link's frame is at its joint pivot (rigid parts share their parent's frame; see
``assembly``), so a joint's origin is the pivot relative to the parent link, with no rotation,
and its axis is the structure's axis. Inertials come from the part's solid (closed mesh, else
convex hull, else a thin box) × the family density. Meshes are written beside the URDF, already in
the link frame and in metres: the part mesh ``meshes/<id>.obj`` is the visual, and the link
collides through the part's convex pieces, the MJCF's (``jax3dc.geometry.convex_pieces``, at
least ``MIN_PIECE_M`` thick): one ``<collision>`` per piece, the hull ``meshes/<id>_collision_<k>.obj``,
so PyBullet, MuJoCo and the MJCF collide alike (a concave carcass is not its hull; a flat part is
a 2 mm plate).
A scene with several roots gets a ``scene_root`` base link holding each root by a fixed joint. It
has an explicit zero-mass inertial, since PyBullet gives a link without one 1 kg where MuJoCo
gives 0; a massless base is then fixed in PyBullet, as the MJCF fixes its roots to the world.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import trimesh

from jax3dc.export.assembly import ExportPart, assemble, unit_axis, vec
from jax3dc.export.files import write_files
from jax3dc.export.simulation import MIN_PIECE_M
from jax3dc.geometry.convex_pieces import convex_pieces, hull_mesh
from jax3dc.geometry.parts import obj_text
from jax3dc.materials import MATERIALS
from jax3dc.structure.schema import Structure

MESH_DIR = "meshes"
SCENE_ROOT = "scene_root"
JOINT_TYPES = {"hinge": "revolute", "slide": "prismatic"}
# URDF requires effort (N or N·m) and velocity (rad/s or m/s) limits; generous household values.
EFFORT_LIMIT = 100.0
VELOCITY_LIMIT = 10.0


def urdf_model(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float = 1.0, *,
               model_name: str = "object") -> tuple[str, dict[str, bytes]]:
    """URDF text and its mesh files ({path relative to the URDF file: bytes})."""
    export = assemble(structure, parts, scale)
    robot = ET.Element("robot", name=model_name)
    # MuJoCo's URDF compiler reads this extension (others ignore it): keep the meshes' folder.
    ET.SubElement(ET.SubElement(robot, "mujoco"), "compiler", strippath="false", discardvisual="true",
                  fusestatic="false")
    for material_id, material in sorted(structure.materials.items()):
        ET.SubElement(ET.SubElement(robot, "material", name=f"material_{material_id}"), "color",
                      rgba=vec(MATERIALS[material.family].rgba))
    labels = {part.part_id: part.label for part in export}
    roots = [part for part in export if part.parent is None]
    if len(roots) > 1:  # a URDF has one root link: the scene's, implicit in the structure (SPEC §2)
        robot.append(ET.Comment(f" a scene of {len(roots)} objects: {SCENE_ROOT} holds each object's root link "
                                f"({', '.join(p.label for p in roots)}) by a fixed joint fix_<root id> "))
        _add_inertial(ET.SubElement(robot, "link", name=SCENE_ROOT), np.zeros(3), 0.0, np.zeros((3, 3)))
    files: dict[str, bytes] = {}
    for part in export:
        file_name = f"{MESH_DIR}/{part.part_id}.obj"
        files[file_name] = obj_text(part.mesh).encode()
        collision_files = []
        for k, vertices in enumerate(convex_pieces(part.mesh, MIN_PIECE_M, scale)):
            collision_files.append(f"{MESH_DIR}/{part.part_id}_collision_{k}.obj")
            files[collision_files[-1]] = obj_text(hull_mesh(vertices)).encode()
        _add_link(robot, part, file_name, collision_files)
        if part.parent is not None:
            _add_joint(robot, part, labels[part.parent])
        elif len(roots) > 1:
            joint = ET.SubElement(robot, "joint", name=f"fix_{part.part_id}", type="fixed")
            ET.SubElement(joint, "parent", link=SCENE_ROOT)
            ET.SubElement(joint, "child", link=part.label)
            ET.SubElement(joint, "origin", xyz=vec(part.offset_m), rpy="0 0 0")
    ET.indent(robot, space="  ")
    return '<?xml version="1.0"?>\n' + ET.tostring(robot, encoding="unicode") + "\n", files


def _add_link(robot: ET.Element, part: ExportPart, mesh_file: str, collision_files: list[str]) -> None:
    link = ET.SubElement(robot, "link", name=part.label)
    _add_inertial(link, part.mass.center_of_mass, part.mass.mass, part.mass.inertia)
    visual = ET.SubElement(link, "visual")
    ET.SubElement(visual, "origin", xyz="0 0 0", rpy="0 0 0")
    ET.SubElement(ET.SubElement(visual, "geometry"), "mesh", filename=mesh_file)
    ET.SubElement(visual, "material", name=f"material_{part.material_id}")
    for k, file_name in enumerate(collision_files):
        collision = ET.SubElement(link, "collision", name=f"collision_{part.part_id}_{k}")
        ET.SubElement(collision, "origin", xyz="0 0 0", rpy="0 0 0")
        ET.SubElement(ET.SubElement(collision, "geometry"), "mesh", filename=file_name)


def _add_inertial(link: ET.Element, center_of_mass: np.ndarray, mass: float, inertia: np.ndarray) -> None:
    """The full tensor about the centre of mass, in the link's axes (the loaders all read the products)."""
    inertial = ET.SubElement(link, "inertial")
    ET.SubElement(inertial, "origin", xyz=vec(center_of_mass), rpy="0 0 0")
    ET.SubElement(inertial, "mass", value=vec([mass]))
    i = inertia
    ET.SubElement(inertial, "inertia", ixx=vec([i[0, 0]]), ixy=vec([i[0, 1]]), ixz=vec([i[0, 2]]),
                  iyy=vec([i[1, 1]]), iyz=vec([i[1, 2]]), izz=vec([i[2, 2]]))


def _add_joint(robot: ET.Element, part: ExportPart, parent_label: str) -> None:
    kind = "fixed" if part.joint is None else JOINT_TYPES[part.joint.type]
    joint = ET.SubElement(robot, "joint", name=f"joint_{part.part_id}", type=kind)
    ET.SubElement(joint, "parent", link=parent_label)
    ET.SubElement(joint, "child", link=part.label)
    ET.SubElement(joint, "origin", xyz=vec(part.offset_m), rpy="0 0 0")
    if part.joint is not None:
        lo, hi = part.range_si
        ET.SubElement(joint, "axis", xyz=vec(unit_axis(part.joint)))
        ET.SubElement(joint, "limit", lower=vec([lo]), upper=vec([hi]), effort=vec([EFFORT_LIMIT]),
                      velocity=vec([VELOCITY_LIMIT]))


def export_urdf(structure: Structure, parts: dict[int, trimesh.Trimesh], out_dir: str | Path, scale: float = 1.0, *,
                model_name: str = "object") -> Path:
    """Write ``<out_dir>/<model_name>.urdf`` and ``<out_dir>/meshes/<id>.obj``; returns the URDF path."""
    text, files = urdf_model(structure, parts, scale, model_name=model_name)
    return write_files(Path(out_dir), f"{model_name}.urdf", text, files)
