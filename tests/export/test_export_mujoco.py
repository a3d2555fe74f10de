"""MJCF and URDF exports load in C MuJoCo with the structure's joints, tree, masses and motion."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import mujoco
import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from export_cases import CASES, EVIL_NAME, SLANT, box, chain
from jax3dc.errors import StructureError
from jax3dc.export.assembly import label_of
from jax3dc.export.mjcf import export_mjcf
from jax3dc.export.urdf import SCENE_ROOT, export_urdf
from jax3dc.materials import MATERIALS
from jax3dc.structure.schema import Material, Node, Structure

EXPORTERS = {"mjcf": export_mjcf, "urdf": export_urdf}
SCALE = 0.8


def _load(fmt: str, structure, parts, out, scale=SCALE) -> tuple[mujoco.MjModel, mujoco.MjData]:
    path = EXPORTERS[fmt](structure, parts, out, scale)
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    return model, data


@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("fmt", sorted(EXPORTERS))
def test_joints_match_the_structure_in_the_world_frame(tmp_path, case, fmt):
    structure, parts = CASES[case]()
    model, data = _load(fmt, structure, parts, tmp_path)
    joints = structure.joints()
    assert model.njnt == len(joints) > 0
    for pid, joint in joints.items():
        j = model.joint(f"joint_{pid}").id
        expected_type = mujoco.mjtJoint.mjJNT_HINGE if joint.type == "hinge" else mujoco.mjtJoint.mjJNT_SLIDE
        assert model.jnt_type[j] == expected_type
        axis = np.asarray(joint.axis) / np.linalg.norm(joint.axis)
        np.testing.assert_allclose(data.xaxis[j], axis, atol=1e-6)
        np.testing.assert_allclose(data.xanchor[j], np.asarray(joint.pivot) * SCALE, atol=1e-6)
        factor = 1.0 if joint.type == "hinge" else SCALE
        assert model.jnt_limited[j]
        np.testing.assert_allclose(model.jnt_range[j], np.asarray(joint.range) * factor, atol=1e-6)
        assert model.body(model.jnt_bodyid[j]).name == label_of(pid, structure.nodes[pid].name)


@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("fmt", sorted(EXPORTERS))
def test_body_tree_follows_the_parents(tmp_path, case, fmt):
    structure, parts = CASES[case]()
    model, _ = _load(fmt, structure, parts, tmp_path)
    several_roots = len(structure.roots()) > 1
    for pid, node in structure.nodes.items():
        body = model.body(label_of(pid, node.name))
        parent_name = model.body(int(body.parentid[0])).name
        if node.parent is not None:
            assert parent_name == label_of(node.parent, structure.nodes[node.parent].name)
        else:
            assert parent_name == (SCENE_ROOT if fmt == "urdf" and several_roots else "world")


def test_mjcf_and_urdf_masses_agree_with_density_times_volume(tmp_path):
    structure, parts = CASES["cabinet"]()
    masses = {}
    for fmt in EXPORTERS:
        model, _ = _load(fmt, structure, parts, tmp_path / fmt)
        masses[fmt] = {pid: model.body(label_of(pid, n.name)).mass[0] for pid, n in structure.nodes.items()}
    for pid, node in structure.nodes.items():
        density = MATERIALS[structure.materials[node.material].family].density_kg_m3
        if pid == 6:  # the flat sticker: a 1 mm thick box of its bounds
            extents = np.maximum(parts[pid].extents * SCALE, 1e-3)
        else:
            extents = parts[pid].extents * SCALE
        assert masses["mjcf"][pid] == pytest.approx(density * np.prod(extents), rel=1e-6), pid
        assert masses["urdf"][pid] == pytest.approx(masses["mjcf"][pid], rel=1e-6), pid


def test_mjcf_material_colour_and_friction_come_from_the_family(tmp_path):
    structure, parts = CASES["chain"]()
    model, _ = _load("mjcf", structure, parts, tmp_path)
    for pid, node in structure.nodes.items():
        props = MATERIALS[structure.materials[node.material].family]
        assert model.geom(f"collision_{pid}_0").friction[0] == pytest.approx(props.friction)
        np.testing.assert_allclose(model.mat_rgba[model.geom(f"visual_{pid}").matid[0]], props.rgba, atol=1e-6)


@pytest.mark.parametrize("fmt", sorted(EXPORTERS))
def test_moving_the_joints_moves_the_parts_as_the_structure_says(tmp_path, fmt):
    """Forward kinematics in MuJoCo against rotations about / shifts along the structure's axes."""
    structure, parts = chain()
    model, data = _load(fmt, structure, parts, tmp_path)
    q = {2: 0.7, 3: 0.08, 4: -0.4}
    for pid, value in q.items():
        data.qpos[model.joint(f"joint_{pid}").qposadr[0]] = value * (SCALE if pid == 3 else 1.0)
    mujoco.mj_kinematics(model, data)

    def moved(point, upto):
        """World position (nu) of a point rigidly attached to part ``upto`` after the motions."""
        p = np.asarray(point, dtype=float)
        pid = upto
        while pid is not None:
            joint = structure.nodes[pid].joint
            if joint is not None:
                axis = np.asarray(joint.axis) / np.linalg.norm(joint.axis)
                if joint.type == "hinge":
                    p = np.asarray(joint.pivot) + Rotation.from_rotvec(axis * q[pid]).apply(p - np.asarray(joint.pivot))
                else:
                    p = p + axis * q[pid]
            pid = structure.nodes[pid].parent
        return p

    tip = np.array([0.3, 0.0, 0.45])  # top of part 5, which shares part 4's frame (origin at its pivot)
    body5 = model.body("part_5").id
    local = (tip - np.asarray(structure.nodes[4].joint.pivot)) * SCALE
    tip_mujoco = data.xpos[body5] + data.xmat[body5].reshape(3, 3) @ local
    np.testing.assert_allclose(tip_mujoco, moved(tip, 5) * SCALE, atol=1e-6)
    j4 = model.joint("joint_4").id
    rotated_axis = Rotation.from_rotvec(np.array([0, 0, 1.0]) * q[2]).apply(np.asarray(SLANT))
    np.testing.assert_allclose(data.xaxis[j4], rotated_axis, atol=1e-6)
    np.testing.assert_allclose(data.xanchor[j4], moved(structure.nodes[4].joint.pivot, 3) * SCALE, atol=1e-6)


@pytest.mark.parametrize("fmt", sorted(EXPORTERS))
def test_flat_tiny_and_open_parts_still_load(tmp_path, fmt):
    closed = box([0.5, 0.5, 0.5], [0, 0, 0])
    parts = {
        1: closed,
        2: trimesh.Trimesh([[0, 0, 0.3], [0.1, 0, 0.3], [0, 0.1, 0.3]], [[0, 1, 2]], process=False),  # one triangle
        3: box([1e-5, 1e-5, 1e-5], [0.3, 0, 0]),  # far below a millimetre
        4: trimesh.Trimesh(closed.vertices + [0, 0, 1], closed.faces[:-2], process=False),  # open box
    }
    nodes = {1: Node(None, 0), 2: Node(1, 0), 3: Node(1, 0), 4: Node(1, 0)}
    structure = Structure({0: Material("Metal")}, nodes)
    model, _ = _load(fmt, structure, parts, tmp_path, scale=1.0)
    density = MATERIALS["Metal"].density_kg_m3
    assert model.body("part_2").mass[0] == pytest.approx(density * 0.1 * 0.1 * 1e-3)
    assert model.body("part_3").mass[0] == pytest.approx(density * 1e-9)
    assert model.body("part_4").mass[0] == pytest.approx(density * 0.125)  # its convex hull


@pytest.mark.parametrize("fmt", sorted(EXPORTERS))
def test_export_is_byte_deterministic(tmp_path, fmt):
    structure, parts = CASES["cabinet"]()
    first = EXPORTERS[fmt](structure, parts, tmp_path / "a", SCALE)
    second = EXPORTERS[fmt](structure, dict(reversed(list(parts.items()))), tmp_path / "b", SCALE)
    files_a = sorted(p.relative_to(tmp_path / "a") for p in (tmp_path / "a").rglob("*") if p.is_file())
    files_b = sorted(p.relative_to(tmp_path / "b") for p in (tmp_path / "b").rglob("*") if p.is_file())
    assert files_a == files_b and len(files_a) > 1
    for rel in files_a:
        assert (tmp_path / "a" / rel).read_bytes() == (tmp_path / "b" / rel).read_bytes(), rel
    assert first.name == second.name


@pytest.mark.parametrize("fmt", sorted(EXPORTERS))
def test_names_from_data_cannot_break_the_xml(tmp_path, fmt):
    structure, parts = CASES["cabinet"]()
    path = EXPORTERS[fmt](structure, parts, tmp_path, SCALE)
    text = path.read_text()
    root = ET.fromstring(text)  # well-formed
    assert EVIL_NAME not in text and "import os" not in text
    names = {el.get("name") for el in root.iter() if el.get("name")}
    assert "part_2_a_import_os_name" in names
    assert all(set(n) <= set("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_") for n in names)


def test_nodes_and_meshes_must_match(tmp_path):
    structure, parts = CASES["chain"]()
    del parts[5]
    with pytest.raises(StructureError, match=r"no mesh for parts \[5\]"):
        export_mjcf(structure, parts, tmp_path)


def test_every_factory_object_exports_to_models_with_its_joints(tmp_path):
    """Real part meshes (sweeps, lathes, CSG) of every procedural category, through both formats."""
    from jax3dc.factories.registry import FACTORIES, generate_object

    for category in sorted(FACTORIES):
        obj = generate_object(category, 3)
        for fmt in EXPORTERS:
            model, data = _load(fmt, obj.structure, obj.parts, tmp_path / category / fmt, obj.scale_m_per_nu)
            joints = obj.structure.joints()
            assert model.njnt == len(joints), (category, fmt)
            for pid, joint in joints.items():
                j = model.joint(f"joint_{pid}").id
                np.testing.assert_allclose(data.xaxis[j], np.asarray(joint.axis) / np.linalg.norm(joint.axis), atol=1e-6)
                np.testing.assert_allclose(data.xanchor[j], np.asarray(joint.pivot) * obj.scale_m_per_nu, atol=1e-6)
            if fmt == "mjcf":  # in the URDF the scene_root link of a scene has no mass
                assert np.all(model.body_mass[1:] > 0), category


@pytest.mark.parametrize("case", ["cabinet", "chain"])
@pytest.mark.parametrize("fmt", sorted(EXPORTERS))
def test_the_projects_importers_read_the_export_back(tmp_path, case, fmt):
    """Export, then import with data_pipeline: the canonical structure comes back, renormalised."""
    from data_pipeline.importers.source import import_object
    from jax3dc.geometry.parts import part_boxes
    from jax3dc.structure import canonicalize

    structure, parts = CASES[case]()
    imported = import_object(EXPORTERS[fmt](structure, parts, tmp_path, SCALE))
    expected = canonicalize(structure, part_boxes(parts))
    labels = {label_of(pid, n.name): pid for pid, n in structure.nodes.items()}
    original = {int(new): labels[link] for new, link in imported.meta["part_links"].items()}
    centre = np.asarray(imported.meta["normalisation"]["centre"])
    units_per_nu = imported.meta["normalisation"]["source_units_per_nu"]
    assert units_per_nu == pytest.approx(SCALE * max(np.ptp(np.concatenate([m.vertices for m in parts.values()]), axis=0)))
    for new, node in imported.structure.nodes.items():
        want = expected.nodes[original[new]]
        assert (original[node.parent] if node.parent is not None else None) == want.parent
        assert (node.joint is None) == (want.joint is None)
        if node.joint is not None:
            assert node.joint.type == want.joint.type
            np.testing.assert_allclose(node.joint.axis, want.joint.axis, atol=1e-6)
            factor = 1.0 if node.joint.type == "hinge" else SCALE / units_per_nu
            np.testing.assert_allclose(node.joint.range, np.asarray(want.joint.range) * factor, atol=1e-6)
            np.testing.assert_allclose(node.joint.pivot, (np.asarray(want.joint.pivot) * SCALE - centre) / units_per_nu,
                                       atol=1e-5)
