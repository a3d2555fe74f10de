"""A scene (several trees, SPEC §2) through every export: each file loads back, each object stays one
subtree of its own, an object resting on another stays on it, and a single object's files are the
bytes they were before scenes got their own layout."""

from __future__ import annotations

import ast
import hashlib
import io
import json
import subprocess

import mujoco
import numpy as np
import pytest
import trimesh
from pxr import Usd, UsdPhysics

from export_cases import CASES, box
from tests.blender_env import blender_python
from jax3dc.export.assembly import label_of, objects
from jax3dc.export.blender import blender_plan, export_blender
from jax3dc.export.gltf import export_gltf
from jax3dc.export.mjcf import export_mjcf
from jax3dc.export.urdf import SCENE_ROOT, export_urdf
from jax3dc.export.usd import export_usd
from jax3dc.physics.verdict import verdict_with_curves
from jax3dc.structure.schema import Material, Node, Structure
from jax3dc.viewer.model import viewer_model

SCALE = 0.9


def table_box_and_lone_cube() -> tuple[Structure, dict[int, trimesh.Trimesh]]:
    """``two_roots`` (a table, a lidded box resting on it) and a third object that is one rigid part:
    a cube on the floor beside the table."""
    structure, parts = CASES["two_roots"]()
    parts[6] = box([0.2, 0.2, 0.2], [0.8, 0.6, -0.125])
    nodes = {**structure.nodes, 6: Node(None, 1)}
    return Structure(structure.materials, nodes, structure.relations), parts


SCENES = {"two_roots": CASES["two_roots"], "lone_part": table_box_and_lone_cube}


def _labels(structure: Structure) -> dict[int, str]:
    return {pid: label_of(pid, node.name) for pid, node in structure.nodes.items()}


@pytest.mark.parametrize("scene", sorted(SCENES))
@pytest.mark.parametrize("export", [export_mjcf, export_urdf])
def test_mujoco_loads_each_object_as_its_own_tree(tmp_path, scene, export):
    structure, parts = SCENES[scene]()
    model = mujoco.MjModel.from_xml_path(str(export(structure, parts, tmp_path, SCALE)))
    body = {pid: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, label) for pid, label in _labels(structure).items()}
    base = 0 if export is export_mjcf else mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, SCENE_ROOT)
    assert min(body.values()) > 0 and base >= 0
    for root, members in objects(structure).items():
        assert model.body_parentid[body[root]] == base  # every object hangs from the world / the scene root
        for pid in members:
            b = body[pid]
            while model.body_parentid[b] != base:
                b = model.body_parentid[b]
            assert b == body[root], (pid, root)


def test_urdf_says_what_its_scene_root_is(tmp_path):
    structure, parts = table_box_and_lone_cube()
    text = export_urdf(structure, parts, tmp_path, SCALE).read_text()
    assert "<!-- a scene of 3 objects: scene_root holds each object's root link (part_1, part_3, part_6)" in text
    assert text.count('type="fixed"') >= 3 and 'name="fix_6"' in text


def test_gltf_has_one_node_per_object_under_one_scene_node(tmp_path):
    structure, parts = table_box_and_lone_cube()
    glb = export_gltf(structure, parts, tmp_path, SCALE).read_bytes()
    scene = trimesh.load(io.BytesIO(glb), file_type="glb", process=False)
    graph = scene.graph
    top = graph.transforms.children[graph.base_frame]
    assert top == ["scene"]
    assert sorted(graph.transforms.children["scene"]) == ["object_1", "object_3", "object_6"]
    labels = _labels(structure)
    for root, members in objects(structure).items():
        for pid in members:
            node = labels[pid]
            while graph.transforms.parents[node] != f"object_{root}":
                node = graph.transforms.parents[node]
                assert not node.startswith("object_") and node != graph.base_frame, (pid, root)
    for pid, mesh in parts.items():  # wrapping nodes move nothing
        matrix, geometry = graph[labels[pid]]
        np.testing.assert_allclose(trimesh.transform_points(scene.geometry[geometry].vertices, matrix),
                                   np.asarray(mesh.vertices) * SCALE, atol=1e-6)
    model = viewer_model(glb, "scene.glb")
    assert {p["id"]: p["object"] for p in model.parts} == {1: 1, 2: 1, 5: 1, 3: 3, 4: 3, 6: 6}


def test_usd_holds_each_object_under_its_own_prim(tmp_path):
    structure, parts = table_box_and_lone_cube()
    stage = Usd.Stage.Open(str(export_usd(structure, parts, tmp_path, SCALE)))
    held = [str(c.GetPath()) for c in stage.GetDefaultPrim().GetChildren() if c.GetName().startswith("object_")]
    assert held == ["/object/object_1", "/object/object_3", "/object/object_6"]
    for root, members in objects(structure).items():
        holder = stage.GetPrimAtPath(f"/object/object_{root}")
        assert list(holder.GetCustomDataByKey("jax3dc")["parts"]) == members
        bodies = {p.GetCustomDataByKey("jax3dc")["part_id"] for p in Usd.PrimRange(holder) if p.HasAPI(UsdPhysics.RigidBodyAPI)}
        assert bodies == set(members)
        assert stage.GetPrimAtPath(f"/object/object_{root}/{label_of(root, None)}").HasAPI(UsdPhysics.ArticulationRootAPI)


def test_blender_groups_each_object(tmp_path):
    structure, parts = table_box_and_lone_cube()
    plan = blender_plan(structure, parts, SCALE)
    assert plan["objects"] == [{"name": "object_1", "root": 1, "parts": [1, 2, 5]},
                               {"name": "object_3", "root": 3, "parts": [3, 4]},
                               {"name": "object_6", "root": 6, "parts": [6]}]
    script = export_blender(structure, parts, tmp_path, SCALE).read_text()
    calls = [n.value.func.id for n in ast.parse(script).body if isinstance(n, ast.Expr) and isinstance(n.value, ast.Call)]
    assert calls == ["build_scene"]
    assert "objects" not in blender_plan(*CASES["cabinet"](), SCALE)


_BLENDER_GROUPS = """
import json, sys
import bpy
exec(compile(open(sys.argv[1]).read(), sys.argv[1], "exec"))
scene = bpy.data.collections["object"]
print(json.dumps({"loose": len(scene.objects), "groups": {c.name: sorted(o.name for o in c.objects) for c in scene.children}}))
"""


def test_blender_puts_each_object_in_its_own_collection(tmp_path):
    """Real Blender: every Blender object of a part (empty, joint empty, mesh) lands in its object's collection."""
    script = export_blender(*table_box_and_lone_cube(), tmp_path, SCALE)
    (tmp_path / "check.py").write_text(_BLENDER_GROUPS)
    run = subprocess.run([blender_python(), str(tmp_path / "check.py"), str(script)], capture_output=True, text=True,
                         timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    found = json.loads(run.stdout.strip().splitlines()[-1])
    assert found == {"loose": 0, "groups": {
        "object_1": ["part_1", "part_1_mesh", "part_2", "part_2_mesh", "part_5", "part_5_mesh"],
        "object_3": ["part_3", "part_3_mesh", "part_4", "part_4_joint", "part_4_mesh"],
        "object_6": ["part_6", "part_6_mesh"]}}


def test_objects_of_a_scene_keep_colliding_with_each_other(tmp_path):
    """The MJCF leaves out only contacts within one object: the box's lid opened to its upper limit
    (2 rad) swings down into the table top, and meets it instead of passing through."""
    structure, parts = table_box_and_lone_cube()
    path = export_mjcf(structure, parts, tmp_path, SCALE)
    model = mujoco.MjModel.from_xml_path(str(path))
    root_of = {label: root for root, members in objects(structure).items() for label in
               (label_of(pid, structure.nodes[pid].name) for pid in members)}
    for line in path.read_text().splitlines():
        if "<exclude " in line:
            a, b = (line.split(f'{k}="')[1].split('"')[0] for k in ("body1", "body2"))
            assert root_of[a] == root_of[b], line
    data = mujoco.MjData(model)
    data.qpos[model.jnt_qposadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, "joint_4")]] = 2.0
    mujoco.mj_forward(model, data)
    table, lid = (mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"part_{i}") for i in (1, 4))
    touching = {frozenset(int(model.geom_bodyid[g]) for g in (c.geom1, c.geom2)) for c in data.contact[:data.ncon]}
    assert frozenset((table, lid)) in touching


@pytest.mark.parametrize("scene", sorted(SCENES))
def test_every_object_of_a_scene_stands(scene):
    """The gravity test on a floor: the table and the lone cube stand on it, the box on the table."""
    structure, parts = SCENES[scene]()
    verdict, _ = verdict_with_curves(structure, parts, SCALE, checks=("gravity",))
    assert not [f for f in verdict.findings if f.check == "gravity"], verdict.to_json()["checks"]


def test_a_scene_gravity_finding_names_the_object():
    structure, parts = table_box_and_lone_cube()
    parts[3] = box([0.2, 0.2, 0.15], [0.2, 0, 1.0])  # the box floats far above the table: it falls
    parts[4] = box([0.2, 0.2, 0.02], [0.2, 0, 1.085])
    nodes = dict(structure.nodes)
    nodes[4] = Node(3, 1)
    verdict, _ = verdict_with_curves(Structure(structure.materials, nodes, structure.relations), parts, SCALE,
                                     checks=("gravity",))
    reasons = verdict.to_json()["checks"]["gravity"]
    assert len(reasons) == 1 and reasons[0].startswith("unstable under gravity: the object of root part 3 moved")


# sha256 of the cabinet case's files at scale 0.9 (MJCF free) before scenes had their own layout
SINGLE_OBJECT = {
    "object.urdf": "f57ac78d0dd0867c985342176d3b6ce88575c8768ccfb8abaeaaa4a393a8cdb0",
    "object.xml": "c6a80f0a262aa80aa4a665ea5ab3dd2c37e9659ea72860ff7479a62c4fb531cb",
    "object.glb": "4c14ca26621d401f5ed435e785a0127c4a7926fb6f5e72d16ac4bc5dac5bd3c4",
    "object.usda": "dbd74ded27d2615722b1c9794494ee10f788982ac637e880a24ad89d9337da27",
    "object_blender.py": "c9ee996cf4ea28dadc441a293ed3fc9451deb0c6148c64b57d9e9505787e53d0",
}


def test_a_single_object_writes_the_bytes_it_wrote_before(tmp_path):
    structure, parts = CASES["cabinet"]()
    for export in (export_urdf, export_gltf, export_usd, export_blender):
        export(structure, parts, tmp_path, SCALE)
    export_mjcf(structure, parts, tmp_path, SCALE, free=True)
    found = {name: hashlib.sha256((tmp_path / name).read_bytes()).hexdigest() for name in SINGLE_OBJECT}
    assert found == SINGLE_OBJECT, json.dumps(found, indent=1)
