"""glTF reloads in trimesh with the structure's hierarchy, geometry and extras; the Blender script
compiles, embeds data only as a JSON string, and its transforms rebuild the parts and joints."""

from __future__ import annotations

import ast
import io
import json

import numpy as np
import pytest
import trimesh

from export_cases import CASES, EVIL_NAME, box
from jax3dc.export.assembly import label_of
from jax3dc.export.blender import blender_plan, blender_script, export_blender
from jax3dc.export.gltf import export_gltf, gltf_bytes
from jax3dc.materials import MATERIALS

SCALE = 1.7


def _reload(structure, parts) -> trimesh.Scene:
    return trimesh.load(io.BytesIO(gltf_bytes(structure, parts, SCALE)), file_type="glb", process=False)


@pytest.mark.parametrize("case", sorted(CASES))
def test_gltf_hierarchy_follows_the_parents(case):
    structure, parts = CASES[case]()
    scene = _reload(structure, parts)
    parents = scene.graph.transforms.parents
    several = len(structure.roots()) > 1  # a scene: each root under its object's node
    for pid, node in structure.nodes.items():
        label = label_of(pid, node.name)
        top = f"object_{pid}" if several else scene.graph.base_frame
        expected = label_of(node.parent, structure.nodes[node.parent].name) if node.parent is not None else top
        assert parents[label] == expected


@pytest.mark.parametrize("case", sorted(CASES))
def test_gltf_geometry_is_in_place_in_metres(case):
    structure, parts = CASES[case]()
    scene = _reload(structure, parts)
    for pid, node in structure.nodes.items():
        matrix, geometry = scene.graph[label_of(pid, node.name)]
        vertices = trimesh.transform_points(scene.geometry[geometry].vertices, matrix)
        np.testing.assert_allclose(vertices, np.asarray(parts[pid].vertices) * SCALE, atol=1e-6)


def test_gltf_extras_hold_joints_relations_and_raw_names():
    structure, parts = CASES["cabinet"]()
    scene = _reload(structure, parts)
    edges = scene.graph.transforms.edge_data
    parents = scene.graph.transforms.parents
    for pid, node in structure.nodes.items():
        label = label_of(pid, node.name)
        extras = edges[(parents[label], label)]["metadata"]
        assert extras["part_id"] == pid and extras["name"] == node.name
        assert extras["material"]["family"] == structure.materials[node.material].family
        assert extras["material"]["desc"] == structure.materials[node.material].desc
        if node.joint is None:
            assert extras["joint"] is None
        else:
            factor = 1.0 if node.joint.type == "hinge" else SCALE
            assert extras["joint"]["type"] == node.joint.type
            np.testing.assert_allclose(extras["joint"]["axis"], node.joint.axis, atol=1e-9)
            np.testing.assert_allclose(extras["joint"]["pivot"], np.asarray(node.joint.pivot) * SCALE, atol=1e-9)
            np.testing.assert_allclose(extras["joint"]["range"], np.asarray(node.joint.range) * factor, atol=1e-9)
        expected_relations = [r for r in structure.relations if pid in (r.a, r.b)]
        assert len(extras["relations"]) == len(expected_relations)
    assert extras is not None
    door = edges[(parents[label_of(2, EVIL_NAME)], label_of(2, EVIL_NAME))]["metadata"]
    assert door["name"] == EVIL_NAME
    assert scene.metadata["jax3dc"]["relations"] == [{"type": "symmetric", "a": 2, "b": 3, "plane": "yz"}]
    assert scene.metadata["jax3dc"]["scale_m_per_nu"] == SCALE


def test_gltf_colours_are_the_family_colours():
    structure, parts = CASES["chain"]()
    scene = _reload(structure, parts)
    for pid, node in structure.nodes.items():
        _, geometry = scene.graph[label_of(pid, node.name)]
        material = scene.geometry[geometry].visual.material
        rgba = np.asarray(material.baseColorFactor, dtype=float) / 255
        np.testing.assert_allclose(rgba, MATERIALS[structure.materials[node.material].family].rgba, atol=1 / 255)


def test_gltf_bytes_are_deterministic(tmp_path):
    structure, parts = CASES["two_roots"]()
    a = export_gltf(structure, parts, tmp_path / "a", SCALE).read_bytes()
    b = export_gltf(structure, dict(reversed(list(parts.items()))), tmp_path / "b", SCALE).read_bytes()
    assert a == b and a[:4] == b"glTF"


def _data_literal(tree: ast.Module) -> str:
    """The one string given to json.loads for DATA."""
    for node in tree.body:
        if isinstance(node, ast.Assign) and node.targets[0].id == "DATA":
            return node.value.args[0].value
    raise AssertionError("no DATA")


def test_blender_script_compiles_and_names_stay_data(tmp_path):
    structure, parts = CASES["cabinet"]()
    path = export_blender(structure, parts, tmp_path, SCALE)
    text = path.read_text()
    compile(text, str(path), "exec")
    tree = ast.parse(text)
    imported = {alias.name for node in ast.walk(tree) if isinstance(node, (ast.Import, ast.ImportFrom))
                for alias in node.names} | {node.module for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)}
    assert imported == {"json", "bpy", "mathutils", "Matrix"}
    data = json.loads(_data_literal(tree))
    assert data["parts"][1]["name"] == EVIL_NAME
    assert data["materials"]["1"]["desc"] == 'brushed "steel"'
    # every string constant other than DATA's is fixed code text, the same for any structure
    other, _ = CASES["chain"]()
    constants = {n.value for n in ast.walk(tree) if isinstance(n, ast.Constant) and isinstance(n.value, str)}
    other_constants = {n.value for n in ast.walk(ast.parse(blender_script(other, CASES["chain"]()[1])))
                       if isinstance(n, ast.Constant) and isinstance(n.value, str)}
    assert len(constants - other_constants) == 1


def _world(plan: dict) -> tuple[dict, dict]:
    """World matrices of each part's frame empty and mesh object, composing the script's bases."""
    frames, meshes = {}, {}
    for part in plan["parts"]:
        parent = frames[part["parent"]] if part["parent"] is not None else np.eye(4)
        if part["joint"] is not None:
            parent = parent @ np.asarray(part["joint"]["basis"])
        frames[part["label"]] = parent @ np.asarray(part["basis"])
        meshes[part["label"]] = frames[part["label"]] @ np.asarray(part["mesh_basis"])
    return frames, meshes


@pytest.mark.parametrize("case", sorted(CASES))
def test_blender_plan_rebuilds_the_parts_and_puts_joints_on_local_z(case):
    structure, parts = CASES[case]()
    plan = blender_plan(structure, parts, SCALE)
    frames, meshes = _world(plan)
    for part in plan["parts"]:
        pid = part["id"]
        data = plan["meshes"][part["mesh"]]
        vertices = trimesh.transform_points(np.asarray(data["vertices"]), meshes[part["label"]])
        np.testing.assert_allclose(vertices, np.asarray(parts[pid].vertices) * SCALE, atol=1e-6)
        joint = structure.nodes[pid].joint
        if joint is not None:
            frame = frames[part["label"]]
            axis = np.asarray(joint.axis) / np.linalg.norm(joint.axis)
            np.testing.assert_allclose(frame[:3, 2], axis, atol=1e-9)
            np.testing.assert_allclose(frame[:3, 3], np.asarray(joint.pivot) * SCALE, atol=1e-9)
            np.testing.assert_allclose(frame[:3, :3] @ frame[:3, :3].T, np.eye(3), atol=1e-9)
            assert np.asarray(part["basis"]) == pytest.approx(np.eye(4))


def test_blender_relations_become_linked_and_mirrored_duplicates():
    structure, parts = CASES["cabinet"]()
    plan = blender_plan(structure, parts, SCALE)
    by_id = {p["id"]: p for p in plan["parts"]}
    assert by_id[3]["mesh"] == by_id[2]["mesh"] == "2"  # the mirrored door shows the left door's mesh
    assert np.linalg.det(np.asarray(by_id[3]["mesh_basis"])[:3, :3]) == pytest.approx(-1)
    assert "3" not in plan["meshes"]
    parts[3] = box([0.3, 0.02, 0.6], [0.15, -0.26, 0.1])  # the same door built afresh: corners in another order
    plan = blender_plan(structure, parts, SCALE)
    assert [p["mesh"] for p in plan["parts"] if p["id"] == 3] == ["2"]
    structure, parts = CASES["two_roots"]()
    plan = blender_plan(structure, parts, SCALE)
    by_id = {p["id"]: p for p in plan["parts"]}
    assert by_id[5]["mesh"] == "2"  # instance: a linked duplicate moved by a translation
    assert np.linalg.det(np.asarray(by_id[5]["mesh_basis"])[:3, :3]) == pytest.approx(1)


def test_blender_keeps_its_own_mesh_when_a_relation_does_not_hold():
    structure, parts = CASES["two_roots"]()
    parts[5] = trimesh.creation.box(extents=[0.05, 0.06, 0.4])  # no longer a copy of leg 2
    plan = blender_plan(structure, parts, SCALE)
    assert {p["id"]: p["mesh"] for p in plan["parts"]}[5] == "5"


def test_blender_script_is_deterministic():
    structure, parts = CASES["cabinet"]()
    assert blender_script(structure, parts, SCALE) == blender_script(structure, dict(reversed(list(parts.items()))), SCALE)
