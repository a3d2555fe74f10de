"""USD export read back through OpenUSD's own UsdPhysics loader (what USD simulators build from): the
structure's bodies and joints (world axis and pivot at rest, limits in degrees or metres), meshes in
metres, the MJCF's masses, the MJCF's convex collision pieces as convex-hull colliders (as many per
body, each where the MJCF's is and of its extents), and the same bytes for the same input."""

from __future__ import annotations

import math
from pathlib import Path

import mujoco
import numpy as np
import pytest
import trimesh
from pxr import Sdf, Usd, UsdGeom, UsdPhysics, UsdShade
from scipy.spatial.transform import Rotation

from export_cases import CASES, EVIL_NAME, box
from jax3dc.export.assembly import label_of
from jax3dc.export.mjcf import mjcf_model
from jax3dc.export.simulation import MIN_PIECE_M
from jax3dc.export.usd import export_usd, usd_model
from jax3dc.factories.registry import FACTORIES, generate_object
from jax3dc.materials import MATERIALS
from jax3dc.structure.schema import Material, Node, Structure
from tests.shared_fixtures import partnet_object

SCALE = 0.8
PARTNET = ("box_rotate_100189", "bucket_swing_100435", "door_8877", "drawer_20453", "microwave_7119",
           "safe_rotate_101593", "switch_100952", "toaster_move_103482", "window_rotate_103135")
KIND = UsdPhysics.ObjectType
JOINT_TYPES = {KIND.RevoluteJoint: "hinge", KIND.PrismaticJoint: "slide", KIND.FixedJoint: None}
# MuJoCo's own hull of a piece can sit 1.8e-6 m inside the written one (PartNet-Mobility's switch)
ATOL_PIECE_M = 1e-5


def _parsed(stage: Usd.Stage) -> dict:
    """{object type: {prim path: description}}, as a simulator's UsdPhysics loader reads the stage."""
    found = UsdPhysics.UsdPhysicsLoadStageFromPrimRange(stage, ["/"])
    return {kind: dict(zip(paths, descs)) for kind, (paths, descs) in found.items()}


def _rotation(q) -> Rotation:
    x, y, z = q.GetImaginary()
    return Rotation.from_quat([x, y, z, q.GetReal()])


def _joint_frame(bodies: dict, body: Sdf.Path, position, orientation) -> tuple[np.ndarray, Rotation]:
    """World pose of a joint frame given in ``body``'s frame (in the world's when ``body`` is empty)."""
    if body.isEmpty:
        return np.asarray(position, dtype=float), _rotation(orientation)
    rotation = _rotation(bodies[body].rotation)
    return np.asarray(bodies[body].position) + rotation.apply(np.asarray(position)), rotation * _rotation(orientation)


def _body_path(structure: Structure, pid: int) -> Sdf.Path:
    node = structure.nodes[pid]
    top = Sdf.Path("/object")
    if len(structure.roots()) > 1:  # a scene: each object under its own Xform
        top = top.AppendChild(f"object_{pid}")
    parent = top if node.parent is None else _body_path(structure, node.parent)
    return parent.AppendChild(label_of(pid, node.name))


def _frame(structure: Structure, pid: int | None) -> np.ndarray:
    """Where a part's joint sits (nu): its own pivot, else the nearest jointed ancestor's, else the origin."""
    while pid is not None:
        if structure.nodes[pid].joint is not None:
            return np.asarray(structure.nodes[pid].joint.pivot, dtype=float)
        pid = structure.nodes[pid].parent
    return np.zeros(3)


def _inertia_tensor(moments, rotation: Rotation) -> np.ndarray:
    matrix = rotation.as_matrix()
    return matrix @ np.diag(moments) @ matrix.T


def _check_export(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float, out: Path) -> None:
    """Everything a simulator reads back from the USD file agrees with the structure and the MJCF."""
    path = export_usd(structure, parts, out, scale)
    assert path.read_text() == usd_model(structure, dict(reversed(list(parts.items()))), scale)
    stage = Usd.Stage.Open(str(path))
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.z
    assert UsdGeom.GetStageMetersPerUnit(stage) == 1.0 and UsdPhysics.GetStageKilogramsPerUnit(stage) == 1.0
    found = _parsed(stage)
    paths = {pid: _body_path(structure, pid) for pid in structure.nodes}
    bodies = found[KIND.RigidBody]
    assert set(bodies) == set(paths.values())
    joints = {desc.body1: (kind, desc) for kind in JOINT_TYPES for desc in found.get(kind, {}).values()}
    assert sum(len(found.get(kind, {})) for kind in JOINT_TYPES) == len(joints) == len(structure.nodes)

    for pid, node in structure.nodes.items():
        kind, desc = joints[paths[pid]]
        assert JOINT_TYPES[kind] == (node.joint.type if node.joint is not None else None), pid
        assert desc.body0 == (paths[node.parent] if node.parent is not None else Sdf.Path.emptyPath), pid
        assert desc.jointEnabled and not desc.excludeFromArticulation
        pos0, rot0 = _joint_frame(bodies, desc.body0, desc.localPose0Position, desc.localPose0Orientation)
        pos1, rot1 = _joint_frame(bodies, desc.body1, desc.localPose1Position, desc.localPose1Orientation)
        np.testing.assert_allclose(pos0, _frame(structure, pid) * scale, atol=1e-6, err_msg=str(pid))
        np.testing.assert_allclose(pos1, pos0, atol=1e-6, err_msg=str(pid))
        assert (rot0 * rot1.inv()).magnitude() < 1e-6, pid  # the two frames agree: nothing jumps at the start
        if node.joint is not None:
            axis = np.asarray(node.joint.axis) / np.linalg.norm(node.joint.axis)
            np.testing.assert_allclose(rot0.apply(np.eye(3)[int(desc.axis)]), axis, atol=1e-6, err_msg=str(pid))
            lower, upper = node.joint.range
            hinge = node.joint.type == "hinge"
            expected = (math.degrees(lower), math.degrees(upper)) if hinge else (lower * scale, upper * scale)
            assert desc.limit.enabled
            np.testing.assert_allclose([desc.limit.lower, desc.limit.upper], expected, rtol=1e-6, atol=1e-6)

    cache = UsdGeom.XformCache()
    model = mujoco.MjModel.from_xml_string(*mjcf_model(structure, parts, scale))
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    colliders: dict[Sdf.Path, list] = {}
    for desc in found[KIND.MeshShape].values():
        colliders.setdefault(desc.rigidBody, []).append(desc)
    assert set(colliders) == set(paths.values()) and not found.get(KIND.CubeShape)
    for pid, node in structure.nodes.items():
        mesh = UsdGeom.Mesh(stage.GetPrimAtPath(paths[pid].AppendChild("mesh")))
        world = np.asarray(cache.GetLocalToWorldTransform(mesh.GetPrim()))  # row vectors: p @ M
        points = np.asarray(mesh.GetPointsAttr().Get(), dtype=float)
        placed = points @ world[:3, :3] + world[3, :3]
        np.testing.assert_allclose(placed, np.asarray(parts[pid].vertices) * scale, atol=1e-6, err_msg=str(pid))
        assert set(mesh.GetFaceVertexCountsAttr().Get()) == {3}
        np.testing.assert_array_equal(mesh.GetFaceVertexIndicesAttr().Get(), np.asarray(parts[pid].faces).reshape(-1))
        assert not mesh.GetPrim().HasAPI(UsdPhysics.CollisionAPI), pid  # the part mesh is visual only
        _check_colliders(stage, cache, colliders[paths[pid]], model, data, label_of(pid, node.name))

        mass = UsdPhysics.MassAPI(stage.GetPrimAtPath(paths[pid]))
        body = model.body(label_of(pid, node.name))
        # MuJoCo reads the MJCF's meshes as float32: thin parts (a laptop lid) differ by up to ~5e-6
        assert mass.GetMassAttr().Get() == pytest.approx(body.mass[0], rel=2e-5), pid
        np.testing.assert_allclose(mass.GetCenterOfMassAttr().Get(), body.ipos, atol=1e-6, err_msg=str(pid))
        moments = mass.GetDiagonalInertiaAttr().Get()
        assert min(moments) > 0, pid  # simulators need a positive definite inertia, however small the part
        usd_inertia = _inertia_tensor(moments, _rotation(mass.GetPrincipalAxesAttr().Get()))
        w, x, y, z = body.iquat
        mujoco_inertia = _inertia_tensor(body.inertia, Rotation.from_quat([x, y, z, w]))
        np.testing.assert_allclose(usd_inertia, mujoco_inertia, atol=2e-5 * np.max(body.inertia), err_msg=str(pid))


def _world_bounds(points: np.ndarray) -> np.ndarray:
    return np.stack([points.min(axis=0), points.max(axis=0)])


def _check_colliders(stage: Usd.Stage, cache: UsdGeom.XformCache, colliders: list, model: mujoco.MjModel,
                     data: mujoco.MjData, body: str) -> None:
    """A body's colliders are the MJCF body's collision pieces in order: convex hulls, not rendered,
    of the same world extents (within ATOL_PIECE_M)."""
    body_id = model.body(body).id
    expected = []
    for g in range(model.ngeom):
        if model.geom_bodyid[g] == body_id and model.geom(g).name.startswith("collision_"):
            mesh = model.geom_dataid[g]
            local = model.mesh_vert[model.mesh_vertadr[mesh]:model.mesh_vertadr[mesh] + model.mesh_vertnum[mesh]]
            expected.append(_world_bounds(local @ data.geom_xmat[g].reshape(3, 3).T + data.geom_xpos[g]))
    by_name = {str(d.primPath.name): d for d in colliders}
    assert sorted(by_name) == sorted(f"collision_{k}" for k in range(len(expected))), body
    for k, want in enumerate(expected):
        desc = by_name[f"collision_{k}"]
        assert desc.approximation == UsdPhysics.Tokens.convexHull, (body, k)
        mesh = UsdGeom.Mesh(stage.GetPrimAtPath(desc.primPath))
        assert mesh.GetPurposeAttr().Get() == UsdGeom.Tokens.guide, (body, k)
        world = np.asarray(cache.GetLocalToWorldTransform(mesh.GetPrim()))
        points = np.asarray(mesh.GetPointsAttr().Get(), dtype=float) @ world[:3, :3] + world[3, :3]
        np.testing.assert_allclose(_world_bounds(points), want, atol=ATOL_PIECE_M, err_msg=f"{body} collision_{k}")


@pytest.mark.parametrize("case", sorted(CASES))
def test_hand_built_cases_read_back_as_their_structure(tmp_path, case):
    structure, parts = CASES[case]()
    _check_export(structure, parts, SCALE, tmp_path)


@pytest.mark.parametrize("category", sorted(FACTORIES))
def test_every_factory_object_reads_back_as_its_structure(tmp_path, category):
    obj = generate_object(category, 3)
    _check_export(obj.structure, obj.parts, obj.scale_m_per_nu, tmp_path)


@pytest.mark.parametrize("name", PARTNET)
def test_partnet_mobility_objects_read_back_as_their_structure(tmp_path, name):
    from data_pipeline.importers.source import import_object

    obj = import_object(partnet_object(name))
    _check_export(obj.structure, obj.parts, obj.meta["scale"], tmp_path)


def test_articulations_start_at_each_root_fixed_to_the_world(tmp_path):
    structure, parts = CASES["two_roots"]()
    found = _parsed(Usd.Stage.Open(str(export_usd(structure, parts, tmp_path, SCALE))))
    roots = {Sdf.Path("/object/object_1/part_1"): 3, Sdf.Path("/object/object_3/part_3"): 2}  # root -> bodies in its tree
    articulations = found[KIND.Articulation]
    assert {tuple(a.rootPrims) for a in articulations.values()} == {(root,) for root in roots}
    for art in articulations.values():
        (root,) = art.rootPrims
        assert Sdf.Path.emptyPath in art.articulatedBodies  # the world: a fixed base
        assert len([b for b in art.articulatedBodies if not b.isEmpty]) == roots[root]


def test_colliders_are_convex_pieces(tmp_path):
    """A convex or open mesh collides as one hull, a closed concave one as several, and a flat part
    as a plate MIN_PIECE_M thick (a hull of a flat mesh has no volume); ``_check_export`` compares
    each with the MJCF."""
    closed = box([0.5, 0.5, 0.5], [0, 0, 0])
    parts = {
        1: closed,
        2: trimesh.Trimesh([[0, 0, 0.3], [0.1, 0, 0.3], [0, 0.1, 0.3]], [[0, 1, 2]], process=False),
        3: trimesh.Trimesh(closed.vertices + [0, 0, 1], closed.faces[:-2], process=False),  # open box
        4: trimesh.creation.annulus(0.1, 0.2, 0.05),  # closed and concave
        5: box([1e-5, 1e-5, 1e-5], [0.3, 0, 0]),  # a 1 mm box of fabric: moments of 4e-14 kg m^2
    }
    nodes = {1: Node(None, 0), 2: Node(1, 0), 3: Node(1, 0), 4: Node(1, 0), 5: Node(1, 1)}
    structure = Structure({0: Material("Metal"), 1: Material("Fabric")}, nodes)
    _check_export(structure, parts, 1.0, tmp_path / "check")
    stage = Usd.Stage.Open(str(export_usd(structure, parts, tmp_path, 1.0)))
    found = _parsed(stage)
    pieces: dict[str, list[np.ndarray]] = {}
    for desc in found[KIND.MeshShape].values():
        points = np.asarray(UsdGeom.Mesh(stage.GetPrimAtPath(desc.primPath)).GetPointsAttr().Get(), dtype=float)
        pieces.setdefault(str(desc.rigidBody), []).append(points)
    counts = {body: len(p) for body, p in pieces.items()}
    assert counts["/object/part_1"] == counts["/object/part_1/part_3"] == counts["/object/part_1/part_2"] == 1
    assert counts["/object/part_1/part_4"] > 1  # the ring is not its hull
    (plate,) = pieces["/object/part_1/part_2"]
    np.testing.assert_allclose(np.ptp(plate, axis=0), [0.1, 0.1, MIN_PIECE_M], rtol=1e-5)
    (speck,) = pieces["/object/part_1/part_5"]
    np.testing.assert_allclose(np.ptp(speck, axis=0), [MIN_PIECE_M] * 3, rtol=1e-5)


def test_colours_friction_and_gravity_come_from_the_families_and_the_stage(tmp_path):
    structure, parts = CASES["chain"]()
    stage = Usd.Stage.Open(str(export_usd(structure, parts, tmp_path, SCALE)))
    found = _parsed(stage)
    materials = found[KIND.RigidBodyMaterial]
    colliders: dict[Sdf.Path, list] = {}
    for desc in found[KIND.MeshShape].values():
        colliders.setdefault(desc.rigidBody, []).append(desc)
    for pid, node in structure.nodes.items():
        props = MATERIALS[structure.materials[node.material].family]
        path = _body_path(structure, pid)
        mesh = UsdGeom.Mesh(stage.GetPrimAtPath(path.AppendChild("mesh")))
        np.testing.assert_allclose(mesh.GetDisplayColorAttr().Get()[0], props.rgba[:3], atol=1e-6)
        np.testing.assert_allclose(mesh.GetDisplayOpacityAttr().Get()[0], props.rgba[3], atol=1e-6)
        for collider in colliders[path]:
            (material,) = collider.materials
            assert materials[material].dynamicFriction == pytest.approx(props.friction)
            assert materials[material].staticFriction == pytest.approx(props.friction)
            binding = UsdShade.MaterialBindingAPI(stage.GetPrimAtPath(collider.primPath)).GetDirectBinding("physics")
            assert binding.GetMaterialPath() == material
    (scene,) = found[KIND.Scene].values()
    assert tuple(scene.gravityDirection) == (0, 0, -1) and scene.gravityMagnitude == pytest.approx(9.81)
    assert stage.GetDefaultPrim().GetPath() == Sdf.Path("/object")
    assert not str(scene.primPath).startswith("/object/")  # referencing the asset brings no second scene


def test_names_and_relations_from_data_round_trip_and_prim_names_are_identifiers(tmp_path):
    structure, parts = CASES["cabinet"]()
    stage = Usd.Stage.Open(str(export_usd(structure, parts, tmp_path, SCALE, model_name="3-cabinet.v2")))
    root = stage.GetDefaultPrim()
    assert Sdf.Path.IsValidIdentifier(root.GetName())
    assert root.GetCustomDataByKey("jax3dc") == {
        "scale_m_per_nu": SCALE, "relations": {"relation_0": {"type": "symmetric", "a": 2, "b": 3, "plane": "yz"}}}
    door = stage.GetPrimAtPath(root.GetPath().AppendPath("part_1/part_2_a_import_os_name"))
    assert door.GetCustomDataByKey("jax3dc") == {
        "part_id": 2, "name": EVIL_NAME, "material": {"id": 0, "family": "Wood", "desc": "oak"}}
    for prim in stage.Traverse():
        assert Sdf.Path.IsValidIdentifier(prim.GetName()), prim.GetPath()
    assert (tmp_path / "3-cabinet.v2.usda").is_file()
