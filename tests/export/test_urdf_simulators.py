"""The URDF export loads in PyBullet and in yourdfpy with the joints, axes, limits, link tree,
masses and inertias that the MJCF export has in MuJoCo, and collides through the MJCF's convex
pieces: as many collision shapes per link as the MJCF has collision geoms per body, each where the
MJCF's is and of its extents.

Objects: every factory category, the PartNet-Mobility samples (through the project's importer)
and the hand-built cases (a flat part that collides as a box, a scene with two roots, a slanted
axis). Each object is exported and loaded once (module-scoped fixture); each loader's view is
reduced to the same plain summary, and the tests compare the summaries.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np
import pybullet
import pytest
import trimesh
import yourdfpy
from scipy.spatial.transform import Rotation

from data_pipeline.importers.source import import_object
from export_cases import CASES
from jax3dc.export.mjcf import export_mjcf
from jax3dc.export.urdf import SCENE_ROOT, export_urdf
from jax3dc.factories.registry import FACTORIES, generate_object
from jax3dc.structure.schema import Structure
from tests.shared_fixtures import PARTNET_MOBILITY, partnet_object

SEED = 7
CASE_SCALE = 0.8
PARTNET = sorted(p.name for p in PARTNET_MOBILITY.iterdir() if (p / "mobility.urdf").is_file())
OBJECTS = ([f"factory-{c}" for c in sorted(FACTORIES)] + [f"partnet-{n}" for n in PARTNET]
           + [f"case-{c}" for c in sorted(CASES)])
ATOL_M = 1e-6  # the exports write 9 significant digits
# MuJoCo's hull of a piece may drop a vertex that lies within qhull's tolerance of a face, which
# the written hull keeps: 1.8e-6 m on PartNet-Mobility's switch (a piece thickened to 2 mm)
ATOL_PIECE_M = 1e-5
# MuJoCo computes mass properties from float32 mesh vertices: ~2e-6 relative off on thin parts
RTOL_MUJOCO_MASS = 1e-5
# yourdfpy's own call into trimesh, when it builds the collision scene
pytestmark = pytest.mark.filterwarnings("ignore:.*Scene.dump:DeprecationWarning")


@dataclass
class Joint:
    """A joint as one loader sees it at rest, in the world frame."""

    type: str  # "hinge", "slide" or "fixed"
    parent: str  # parent link / body name
    child: str
    axis: np.ndarray | None = None
    anchor: np.ndarray | None = None
    limits: tuple[float, float] | None = None


@dataclass
class Link:
    """A link (MuJoCo: body) as one loader sees it at rest, in the world frame."""

    parent: str | None  # None for a base link / a body of the world
    mass: float
    com: np.ndarray  # world
    inertia: np.ndarray  # [3, 3] about the centre of mass, world axes
    pieces: int = 0  # collision shapes
    piece_bounds: list[np.ndarray] | None = None  # [2, 3] world bounds of each shape, in order
    bounds: np.ndarray | None = None  # [2, 3] world bounds of all the link's collision geometry


@dataclass
class Summary:
    """What one loader made of one export, in plain values the tests can compare."""

    joints: dict[str, Joint] = field(default_factory=dict)
    links: dict[str, Link] = field(default_factory=dict)
    bounds: np.ndarray | None = None  # [2, 3] world bounds of all collision geometry (yourdfpy)


@dataclass
class Loaded:
    """One object, its exports' summaries in the three loaders, and its source for expectations."""

    structure: Structure
    parts: dict[int, trimesh.Trimesh]
    scale: float
    mujoco: Summary
    pybullet: Summary
    yourdfpy: Summary


def _source(name: str) -> tuple[Structure, dict[int, trimesh.Trimesh], float]:
    """Structure, part meshes (nu) and metres per nu of an ``OBJECTS`` entry."""
    kind, key = name.split("-", 1)
    if kind == "factory":
        obj = generate_object(key, SEED)
        return obj.structure, obj.parts, obj.scale_m_per_nu
    if kind == "partnet":
        imported = import_object(partnet_object(key))
        return imported.structure, imported.parts, imported.meta["scale"]
    structure, parts = CASES[key]()
    return structure, parts, CASE_SCALE


def _bounds(points: np.ndarray) -> np.ndarray:
    return np.stack([points.min(axis=0), points.max(axis=0)])


def _world_inertia(rotation: np.ndarray, diagonal: np.ndarray) -> np.ndarray:
    return rotation @ np.diag(diagonal) @ rotation.T


def _mujoco(path: Path) -> Summary:
    """The MJCF in MuJoCo: the reference the URDF loaders are compared with."""
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    out = Summary()
    kinds = {int(mujoco.mjtJoint.mjJNT_HINGE): "hinge", int(mujoco.mjtJoint.mjJNT_SLIDE): "slide"}
    for j in range(model.njnt):
        body = model.jnt_bodyid[j]
        out.joints[model.joint(j).name] = Joint(
            kinds[int(model.jnt_type[j])], model.body(model.body_parentid[body]).name, model.body(body).name,
            data.xaxis[j].copy(), data.xanchor[j].copy(), tuple(model.jnt_range[j]))
    for b in range(1, model.nbody):
        parent = model.body_parentid[b]
        link = Link(model.body(parent).name if parent else None, model.body_mass[b], data.xipos[b].copy(),
                    _world_inertia(data.ximat[b].reshape(3, 3), model.body_inertia[b]))
        link.piece_bounds = []
        for g in range(model.ngeom):  # the convex pieces, in the order of their names' k
            if model.geom_bodyid[g] == b and model.geom(g).name.startswith("collision_"):
                mesh = model.geom_dataid[g]
                local = model.mesh_vert[model.mesh_vertadr[mesh]:model.mesh_vertadr[mesh] + model.mesh_vertnum[mesh]]
                link.piece_bounds.append(_bounds(local @ data.geom_xmat[g].reshape(3, 3).T + data.geom_xpos[g]))
        link.pieces = len(link.piece_bounds)
        link.bounds = _bounds(np.concatenate(link.piece_bounds)) if link.pieces else None
        out.links[model.body(b).name] = link
    return out


def _pybullet(path: Path, client: int) -> Summary:
    """loadURDF with the file's inertias (PyBullet otherwise recomputes them from the collision shapes)."""
    body = pybullet.loadURDF(str(path), useFixedBase=False, flags=pybullet.URDF_USE_INERTIA_FROM_FILE,
                             physicsClientId=client)
    try:
        names = {-1: pybullet.getBodyInfo(body, physicsClientId=client)[0].decode()}
        poses = {-1: pybullet.getBasePositionAndOrientation(body, physicsClientId=client)}
        parents: dict[int, str | None] = {-1: None}
        kinds = {pybullet.JOINT_REVOLUTE: "hinge", pybullet.JOINT_PRISMATIC: "slide", pybullet.JOINT_FIXED: "fixed"}
        out = Summary()
        for i in range(pybullet.getNumJoints(body, physicsClientId=client)):
            info = pybullet.getJointInfo(body, i, physicsClientId=client)
            names[i] = info[12].decode()
            state = pybullet.getLinkState(body, i, computeForwardKinematics=True, physicsClientId=client)
            poses[i] = state[0], state[1]
            parents[i] = names[info[16]]
            joint = Joint(kinds[info[2]], parents[i], names[i])
            if joint.type != "fixed":
                com_rotation = Rotation.from_quat(state[1]).as_matrix()  # the axis is given in the COM frame
                joint.axis, joint.anchor = com_rotation @ np.asarray(info[13]), np.asarray(state[4])
                joint.limits = (info[8], info[9])
            out.joints[info[1].decode()] = joint
        for i, name in names.items():
            dynamics = pybullet.getDynamicsInfo(body, i, physicsClientId=client)
            position, orientation = poses[i]
            link = Link(parents[i], dynamics[0], np.asarray(position),
                        _world_inertia(Rotation.from_quat(orientation).as_matrix(), dynamics[2]))
            link.piece_bounds = []
            for _, _, geometry, _, file_name, local_position, local_orientation in pybullet.getCollisionShapeData(
                    body, i, physicsClientId=client):
                assert geometry == pybullet.GEOM_MESH, name
                # the shape's frame is relative to the link's COM frame; PyBullet collides through the
                # hull of the file's vertices, so the file placed there is what it collides with
                place, turn = pybullet.multiplyTransforms(position, orientation, local_position, local_orientation)
                vertices = np.asarray(trimesh.load(file_name.decode(), process=False).vertices)
                link.piece_bounds.append(_bounds(vertices @ Rotation.from_quat(turn).as_matrix().T + place))
            link.pieces = len(link.piece_bounds)
            link.bounds = _bounds(np.concatenate(link.piece_bounds)) if link.pieces else None
            # the broad phase agrees: PyBullet's own box of the link holds every piece
            low, high = pybullet.getAABB(body, i, physicsClientId=client)
            assert link.bounds is None or (np.all(low <= link.bounds[0]) and np.all(high >= link.bounds[1])), name
            out.links[name] = link
        return out
    finally:
        pybullet.removeBody(body, physicsClientId=client)


def _yourdfpy(path: Path) -> Summary:
    """Only the collision scene is built: it is what a simulator reads, and it places every link
    (yourdfpy joins a link's collision meshes into one, so only the link's bounds are compared)."""
    urdf = yourdfpy.URDF.load(str(path), build_scene_graph=False, load_meshes=False,
                              build_collision_scene_graph=True, load_collision_meshes=True)
    assert urdf.validate()
    scene = urdf.collision_scene
    out = Summary(bounds=np.asarray(scene.bounds))
    link_bounds = {}
    for node in scene.graph.nodes_geometry:
        transform, geometry = scene.graph.get(node)
        vertices = np.asarray(scene.geometry[geometry].vertices)
        link_bounds[scene.graph.transforms.parents[node]] = _bounds(vertices @ transform[:3, :3].T + transform[:3, 3])

    def pose(link: str) -> np.ndarray:
        return urdf.get_transform(link, collision_geometry=True)

    kinds = {"revolute": "hinge", "prismatic": "slide", "fixed": "fixed"}
    parents = {j.child: j.parent for j in urdf.robot.joints}
    for j in urdf.robot.joints:
        joint = Joint(kinds[j.type], j.parent, j.child)
        if joint.type != "fixed":
            frame = pose(j.child)
            joint.axis, joint.anchor = frame[:3, :3] @ j.axis, frame[:3, 3]
            joint.limits = (j.limit.lower, j.limit.upper)
        out.joints[j.name] = joint
    for link in urdf.robot.links:
        frame = pose(link.name) @ link.inertial.origin
        entry = Link(parents.get(link.name), link.inertial.mass, frame[:3, 3],
                     frame[:3, :3] @ link.inertial.inertia @ frame[:3, :3].T)
        entry.pieces = len(link.collisions)
        entry.bounds = link_bounds.get(link.name)
        out.links[link.name] = entry
    return out


@pytest.fixture(scope="module")
def bullet_client() -> Iterator[int]:
    """One headless PyBullet server for the module; each object's body is removed once read."""
    client = pybullet.connect(pybullet.DIRECT)
    yield client
    pybullet.disconnect(client)


@pytest.fixture(scope="module", params=OBJECTS)
def loaded(request: pytest.FixtureRequest, bullet_client: int, tmp_path_factory: pytest.TempPathFactory) -> Loaded:
    """Export once per object, load in all three, and share the summaries among the tests."""
    structure, parts, scale = _source(request.param)
    out = tmp_path_factory.mktemp(request.param)
    urdf = export_urdf(structure, parts, out / "urdf", scale)
    mjcf = export_mjcf(structure, parts, out / "mjcf", scale)
    return Loaded(structure, parts, scale, _mujoco(mjcf), _pybullet(urdf, bullet_client), _yourdfpy(urdf))


def _urdf_views(loaded: Loaded) -> dict[str, Summary]:
    return {"pybullet": loaded.pybullet, "yourdfpy": loaded.yourdfpy}


def _moving(summary: Summary) -> dict[str, Joint]:
    return {name: j for name, j in summary.joints.items() if j.type != "fixed"}


def test_moving_joints_agree_with_mujoco(loaded: Loaded) -> None:
    reference = loaded.mujoco.joints
    assert sorted(reference) == sorted(f"joint_{pid}" for pid in loaded.structure.joints())
    for loader, summary in _urdf_views(loaded).items():
        joints = _moving(summary)
        assert sorted(joints) == sorted(reference), loader
        for name, want in reference.items():
            got = joints[name]
            assert (got.type, got.parent, got.child) == (want.type, want.parent, want.child), (loader, name)
            np.testing.assert_allclose(got.axis, want.axis, atol=ATOL_M, err_msg=f"{loader} {name} axis")
            np.testing.assert_allclose(got.anchor, want.anchor, atol=ATOL_M, err_msg=f"{loader} {name} anchor")
            np.testing.assert_allclose(got.limits, want.limits, atol=ATOL_M, err_msg=f"{loader} {name} limits")


def test_link_tree_agrees_with_mujoco(loaded: Loaded) -> None:
    """Rigid parts hang from their parents by fixed joints; several roots from ``scene_root``."""
    world = SCENE_ROOT if len(loaded.structure.roots()) > 1 else None
    nodes = loaded.structure.nodes
    fixed = sorted(f"fix_{pid}" if node.parent is None else f"joint_{pid}" for pid, node in nodes.items()
                   if node.joint is None and (node.parent is not None or world))
    for loader, summary in _urdf_views(loaded).items():
        assert sorted(summary.links) == sorted(loaded.mujoco.links) + ([SCENE_ROOT] if world else []), loader
        assert sorted(name for name, j in summary.joints.items() if j.type == "fixed") == fixed, loader
        for name, want in loaded.mujoco.links.items():
            assert summary.links[name].parent == (want.parent or world), (loader, name)


def test_masses_and_inertias_agree_with_mujoco(loaded: Loaded) -> None:
    total = sum(link.mass for link in loaded.mujoco.links.values())
    for loader, summary in _urdf_views(loaded).items():
        assert sum(link.mass for link in summary.links.values()) == pytest.approx(total, rel=RTOL_MUJOCO_MASS), loader
        if SCENE_ROOT in summary.links:
            assert summary.links[SCENE_ROOT].mass == 0.0, loader
        for name, want in loaded.mujoco.links.items():
            got = summary.links[name]
            assert got.mass == pytest.approx(want.mass, rel=RTOL_MUJOCO_MASS), (loader, name)
            np.testing.assert_allclose(got.com, want.com, atol=ATOL_M, err_msg=f"{loader} {name} centre of mass")
            np.testing.assert_allclose(got.inertia, want.inertia, rtol=0, atol=RTOL_MUJOCO_MASS * np.trace(want.inertia),
                                       err_msg=f"{loader} {name} inertia")


def test_collision_pieces_agree_with_mujoco(loaded: Loaded) -> None:
    """Each link collides through the MJCF body's convex pieces: as many shapes, each where the
    MJCF's is and of its extents (PyBullet), and the same bounds per link (yourdfpy)."""
    for loader, summary in _urdf_views(loaded).items():
        for name, want in loaded.mujoco.links.items():
            got = summary.links[name]
            assert got.pieces == want.pieces > 0, (loader, name)
            np.testing.assert_allclose(got.bounds, want.bounds, atol=ATOL_PIECE_M, err_msg=f"{loader} {name}")
            if got.piece_bounds is not None:
                np.testing.assert_allclose(np.stack(got.piece_bounds), np.stack(want.piece_bounds), atol=ATOL_PIECE_M,
                                           err_msg=f"{loader} {name}")
    if SCENE_ROOT in loaded.pybullet.links:
        assert loaded.pybullet.links[SCENE_ROOT].pieces == loaded.yourdfpy.links[SCENE_ROOT].pieces == 0


def test_yourdfpy_collision_scene_is_the_mujoco_pieces(loaded: Loaded) -> None:
    """The whole collision scene loads and spans what the MJCF's pieces span."""
    pieces = np.concatenate([link.bounds for link in loaded.mujoco.links.values()])
    np.testing.assert_allclose(loaded.yourdfpy.bounds, _bounds(pieces), atol=ATOL_PIECE_M)

