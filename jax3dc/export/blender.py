"""Blender export: a Python script that, run in Blender, rebuilds the parts, their parenting,
materials, linked / mirrored duplicates for relations, and joint limits as constraints.

Nothing from the data is ever pasted into code: everything (names, descriptions, geometry) is
one JSON document embedded as a single string literal written with ``repr`` and read back with
``json.loads`` in Blender; the code around it is a fixed text. So a part named
``a"); import os #`` stays a string.

Objects per part (all in metres, object frame +Z up): an empty ``<label>`` carrying the part's
frame, a child mesh object ``<label>_mesh`` holding its geometry, and for a jointed part a static
empty ``<label>_joint`` at the pivot whose Z axis is the joint axis; the part empty is its child
and moves only about / along that Z (Limit Rotation / Limit Location constraints in local space,
plus locked channels in the UI). Child parts hang under their parent's part empty.

Relations: the mesh of part b reuses part a's mesh data (a linked duplicate) when b's surface is
a's moved by a translation (``instance``) or reflected in the relation's plane (``symmetric``,
giving the mesh object a mirroring transform) — same vertices and triangles, in any order, to
1e-6 of the object size; otherwise (e.g. near-copies of different sizes) b keeps its own mesh. Every part records its relations in a custom property either way.

A scene of several objects (several roots, SPEC §2): the plan lists them under ``objects`` and the
script, after building, moves each object's Blender objects (part empties, joint empties, meshes)
into a child collection ``object_<root>`` of the scene's collection, so each object can be
selected, hidden or moved alone. A single object's script is the plain one.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import trimesh
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from jax3dc.export.assembly import assemble, object_label, objects, unit_axis
from jax3dc.export.files import write_files
from jax3dc.export.gltf import relation_extras
from jax3dc.materials import MATERIALS
from jax3dc.structure.schema import Structure

MIRRORS = {"yz": np.diag([-1.0, 1.0, 1.0]), "xz": np.diag([1.0, -1.0, 1.0]), "xy": np.diag([1.0, 1.0, -1.0])}


def _short(x: float) -> float:
    """9 significant digits, so the embedded JSON is compact and the same for the same input."""
    return float("%.9g" % (float(x) + 0.0))


def _matrix(m: np.ndarray) -> list[list[float]]:
    return [[_short(v) for v in row] for row in m]


def _translation(t) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = t
    return m


def axis_to_z_rotation(axis: np.ndarray) -> np.ndarray:
    """4x4 rotation taking +Z to the unit ``axis`` (the smallest such rotation).

    +Z -> -Z is a half turn about X, written out: scipy would pick some perpendicular axis, and the
    exported joint frames should not depend on that choice.
    """
    m = np.eye(4)
    if float(axis[2]) < -1 + 1e-12:
        m[:3, :3] = np.diag([1.0, -1.0, -1.0])
    else:
        m[:3, :3] = Rotation.align_vectors(np.asarray(axis, dtype=np.float64)[None], [[0.0, 0.0, 1.0]])[0].as_matrix()
    return m


def _area(vertices: np.ndarray, faces: np.ndarray) -> float:
    corners = vertices[faces]
    return float(np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1).sum() / 2)


def _relation_transform(relation, va: np.ndarray, fa: np.ndarray, vb: np.ndarray, fb: np.ndarray,
                        tol: float) -> np.ndarray | None:
    """4x4 A taking part a's surface onto part b's (a translation, or a reflection in the plane), or None.

    The meshes must be the same point set under A, in any vertex order (a mirrored box lists its
    corners in another order), with the same surface area: the triangles may split planar faces
    along other diagonals (a mirrored quad does), which changes neither the look nor the area.
    """
    if va.shape != vb.shape or fa.shape != fb.shape:
        return None
    linear = MIRRORS[relation.plane] if relation.type == "symmetric" else np.eye(3)
    moved = va @ linear.T
    shift = (vb.min(axis=0) + vb.max(axis=0) - moved.min(axis=0) - moved.max(axis=0)) / 2
    distance, match = cKDTree(vb).query(moved + shift)
    if distance.max() > tol or len(np.unique(match)) != len(match):
        return None
    area_a, area_b = _area(va, fa), _area(vb, fb)
    if abs(area_a - area_b) > 1e-6 * max(area_a, area_b):
        return None
    a = np.eye(4)
    a[:3, :3], a[:3, 3] = linear, shift
    return a


def blender_plan(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float = 1.0,
                 model_name: str = "object") -> dict:
    """Everything the Blender script builds, as JSON-ready data (testable without Blender)."""
    export = assemble(structure, parts, scale)
    by_id = {part.part_id: part for part in export}
    world: dict[int, np.ndarray] = {}  # world matrix of each part empty
    joint_world: dict[int, np.ndarray] = {}
    for part in export:
        parent_world = world[part.parent] if part.parent is not None else np.eye(4)
        if part.joint is not None:
            joint_world[part.part_id] = _translation(part.frame_nu * scale) @ axis_to_z_rotation(unit_axis(part.joint))
            world[part.part_id] = joint_world[part.part_id]
        elif part.parent is not None:
            world[part.part_id] = parent_world
        else:
            world[part.part_id] = _translation(part.frame_nu * scale)
    world_vertices = {p.part_id: np.asarray(p.mesh.vertices) + p.frame_nu * scale for p in export}
    faces = {p.part_id: np.asarray(p.mesh.faces, dtype=np.int64) for p in export}
    size = max(float(np.ptp(np.concatenate(list(world_vertices.values())), axis=0).max()), 1e-9)
    tol = 1e-6 * max(size, 1.0)

    source = {pid: pid for pid in by_id}  # whose mesh data a part shows
    shape = {pid: world[pid] for pid in by_id}  # world matrix applied to that mesh data
    linked_to: set[int] = set()
    for relation in structure.relations:
        a, b = relation.a, relation.b
        if relation.type == "support" or source[b] != b or b in linked_to or source[a] == b:
            continue
        transform = _relation_transform(relation, world_vertices[a], faces[a], world_vertices[b], faces[b], tol)
        if transform is not None:
            source[b], shape[b] = source[a], transform @ shape[a]
            linked_to.add(source[a])

    meshes = {}
    for pid in sorted(set(source.values())):
        local = np.c_[world_vertices[pid], np.ones(len(world_vertices[pid]))] @ np.linalg.inv(world[pid]).T
        meshes[str(pid)] = {"vertices": [[_short(v) for v in row] for row in local[:, :3]],
                            "faces": faces[pid].tolist()}
    plan_parts = []
    for part in export:
        pid = part.part_id
        parent_world = world[part.parent] if part.parent is not None else np.eye(4)
        entry = {
            "id": pid, "label": part.label, "name": part.name,
            "parent": by_id[part.parent].label if part.parent is not None else None,
            "material": part.material_id, "mesh": str(source[pid]),
            "mesh_basis": _matrix(np.linalg.inv(world[pid]) @ shape[pid]),
            "relations": [relation_extras(r) for r in structure.relations if pid in (r.a, r.b)],
            "joint": None,
        }
        if part.joint is not None:
            entry["joint"] = {"type": part.joint.type, "range": [_short(v) for v in part.range_si],
                              "basis": _matrix(np.linalg.inv(parent_world) @ joint_world[pid])}
            entry["basis"] = _matrix(np.eye(4))
        else:
            entry["basis"] = _matrix(np.linalg.inv(parent_world) @ world[pid])
        plan_parts.append(entry)
    materials = {str(mid): {"family": m.family, "desc": m.desc, "rgba": list(MATERIALS[m.family].rgba)}
                 for mid, m in sorted(structure.materials.items())}
    plan = {"name": model_name, "scale_m_per_nu": float(scale), "materials": materials,
            "meshes": meshes, "parts": plan_parts}
    trees = objects(structure)
    if len(trees) > 1:
        plan["objects"] = [{"name": object_label(root), "root": root, "parts": members} for root, members in trees.items()]
    return plan


_SCRIPT = '''\
"""Generated by jax3dc: rebuilds an articulated object in Blender.

Run: blender --python THIS_FILE (or paste into Blender's Text Editor and press Run Script).
All data is the JSON document in DATA; the code below only reads it.
"""
import json

import bpy
from mathutils import Matrix

DATA = json.loads({data})


def link(obj, collection, parent, basis):
    collection.objects.link(obj)
    obj.parent = parent
    obj.matrix_basis = Matrix(basis)
    return obj


def make_material(key, entry):
    mat = bpy.data.materials.new("material_" + key)
    mat.diffuse_color = entry["rgba"]
    mat["family"] = entry["family"]
    mat["desc"] = entry["desc"]
    tree = getattr(mat, "node_tree", None)
    bsdf = tree.nodes.get("Principled BSDF") if tree is not None else None
    if bsdf is not None:
        bsdf.inputs["Base Color"].default_value = entry["rgba"]
        bsdf.inputs["Alpha"].default_value = entry["rgba"][3]
        bsdf.inputs["Metallic"].default_value = 1.0 if entry["family"] == "Metal" else 0.0
    return mat


def make_mesh(key, entry, material):
    mesh = bpy.data.meshes.new("mesh_" + key)
    mesh.from_pydata(entry["vertices"], [], entry["faces"])
    mesh.update()
    mesh.materials.append(material)
    return mesh


def limit_joint(obj, joint):
    lo, hi = joint["range"]
    hinge = joint["type"] == "hinge"
    rot = obj.constraints.new("LIMIT_ROTATION")
    rot.owner_space = "LOCAL"
    rot.use_limit_x = rot.use_limit_y = rot.use_limit_z = True
    rot.min_x = rot.max_x = rot.min_y = rot.max_y = 0.0
    rot.min_z, rot.max_z = (lo, hi) if hinge else (0.0, 0.0)
    loc = obj.constraints.new("LIMIT_LOCATION")
    loc.owner_space = "LOCAL"
    loc.use_min_x = loc.use_max_x = loc.use_min_y = loc.use_max_y = True
    loc.use_min_z = loc.use_max_z = True
    loc.min_x = loc.max_x = loc.min_y = loc.max_y = 0.0
    loc.min_z, loc.max_z = (0.0, 0.0) if hinge else (lo, hi)
    obj.lock_location = (True, True, hinge)
    obj.lock_rotation = (True, True, not hinge)
    obj.rotation_mode = "XYZ"


def build():
    collection = bpy.data.collections.new(DATA["name"])
    bpy.context.scene.collection.children.link(collection)
    collection["scale_m_per_nu"] = DATA["scale_m_per_nu"]
    materials = dict((key, make_material(key, entry)) for key, entry in DATA["materials"].items())
    meshes = {{}}
    frames = {{}}
    for part in DATA["parts"]:
        parent = frames[part["parent"]] if part["parent"] is not None else None
        if part["joint"] is not None:
            pivot = link(bpy.data.objects.new(part["label"] + "_joint", None), collection, parent,
                         part["joint"]["basis"])
            pivot.empty_display_type = "SINGLE_ARROW"
            parent = pivot
        frame = link(bpy.data.objects.new(part["label"], None), collection, parent, part["basis"])
        frame.empty_display_type = "PLAIN_AXES"
        frame.empty_display_size = 0.05
        frame["part_id"] = part["id"]
        frame["part_name"] = part["name"] or ""
        frame["relations"] = json.dumps(part["relations"])
        if part["joint"] is not None:
            limit_joint(frame, part["joint"])
        key = part["mesh"]
        if key not in meshes:
            meshes[key] = make_mesh(key, DATA["meshes"][key], materials[str(part["material"])])
        shown = link(bpy.data.objects.new(part["label"] + "_mesh", meshes[key]), collection, frame,
                     part["mesh_basis"])
        shown.material_slots[0].link = "OBJECT"
        shown.material_slots[0].material = materials[str(part["material"])]
        frames[part["label"]] = frame
'''

_BUILD = "\n\nbuild()\n"

_BUILD_SCENE = '''

def group_objects(collection, made):
    """Each object of the scene into a child collection of its own (DATA["objects"])."""
    object_of = dict((part, entry["name"]) for entry in DATA["objects"] for part in entry["parts"])
    groups = {}
    for entry in DATA["objects"]:
        groups[entry["name"]] = bpy.data.collections.new(entry["name"])
        groups[entry["name"]]["root_part_id"] = entry["root"]
        collection.children.link(groups[entry["name"]])
    for obj in made:
        # a mesh hangs under its part's empty, a joint empty under the parent part's (the same object)
        owner = obj if "part_id" in obj else obj.parent
        groups[object_of[owner["part_id"]]].objects.link(obj)
        collection.objects.unlink(obj)


def build_scene():
    objects_before = set(bpy.data.objects)
    collections_before = set(bpy.context.scene.collection.children)
    build()
    collection = (set(bpy.context.scene.collection.children) - collections_before).pop()
    group_objects(collection, set(bpy.data.objects) - objects_before)


build_scene()
'''


def blender_script(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float = 1.0,
                   model_name: str = "object") -> str:
    """The script text; the same input gives the same text."""
    plan = blender_plan(structure, parts, scale, model_name)
    data = json.dumps(plan, sort_keys=True, separators=(",", ":"))
    return _SCRIPT.format(data=repr(data)) + (_BUILD_SCENE if "objects" in plan else _BUILD)


def export_blender(structure: Structure, parts: dict[int, trimesh.Trimesh], out_dir: str | Path, scale: float = 1.0, *,
                   model_name: str = "object") -> Path:
    """Write ``<out_dir>/<model_name>_blender.py``; returns its path."""
    text = blender_script(structure, parts, scale, model_name)
    return write_files(Path(out_dir), f"{model_name}_blender.py", text, {})
