"""The simulation MJCF of one object: what the physics checks run on.

Differs from the plain exporter (``jax3dc.export.mjcf``, whose frames and names it reuses): metric
scale, collision from convex pieces (``collision_shapes``) with the material's density and
friction, visual meshes without collision (optional: the checks compile without them), parent–child
collisions enabled (``filterparent="disable"``), body pairs that already interpenetrate at rest
excluded from contact in dynamics, and optionally a floor plane under the object, a free joint on
each root (gravity test) and a position actuator on every joint.

When parts touch only the floor (the gravity test), each part meets it through one massless
convex hull of all its pieces: against a plane, the hull of a union has the same lowest points and
the same support polygon as the union, and one plane pair per part instead of one per piece keeps
MJX's compiled step small (a PartNet-Mobility safe has 213 pieces).
"""

from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

import mujoco
import numpy as np
import trimesh
from scipy.spatial import ConvexHull

from eval.physics.collision_shapes import convex_pieces
from jax3dc.errors import Jax3dcError
from jax3dc.export.assembly import ExportPart, assemble, check_nesting, unit_axis, vec
from jax3dc.geometry.parts import obj_text
from jax3dc.structure.schema import Structure

TIMESTEP_S = 0.002
MIN_PIECE_M = 2e-3  # collision pieces are at least this thick (metres)
ARENA_MEMORY = "64M"  # room for the contacts of many convex pieces within the proximity margin
SERVO_OMEGA = 60.0  # natural frequency (rad/s) of the critically damped joint servos


@dataclass(frozen=True)
class SimOptions:
    """Which extras the model carries; each check asks only for what it needs."""

    floor: bool = False
    free_root: bool = False
    actuators: bool = False
    visual: bool = False
    exclude: frozenset[tuple[int, int]] = frozenset()  # part pairs (a < b) never in contact
    frictionless: bool = False  # condim 1: only collisions block motion (reachability)
    floor_contacts_only: bool = False  # parts touch the floor (one hull each) but not each other (gravity test)
    margin_m: float = 0.0  # contacts of moving parts are reported up to this distance apart (proximity)
    # only these collision geom pairs (names) collide, through explicit frictionless pairs (requires
    # ``frictionless``): MJX compiles one collision function per distinct mesh pair it may test
    contact_pairs: frozenset[tuple[str, str]] | None = None


@dataclass
class SimModel:
    """A compiled model and the maps between parts, bodies, geoms and joints."""

    xml: str
    assets: dict[str, bytes]
    model: mujoco.MjModel
    scale: float  # metres per nu
    part_body: dict[int, int]  # part id -> body id
    joint_parts: list[int]  # jointed parts in tree order; joint k moves part joint_parts[k]
    joint_qpos: np.ndarray  # [J] qpos address of each structure joint
    joint_type: list[str]  # "hinge" / "slide"
    joint_range: np.ndarray  # [J, 2] model units (rad / m)
    group_of_body: np.ndarray  # [nbody] rigid group: bodies welded together share one id (world: -1)
    moved_by: np.ndarray  # [J, nbody] bool: body moves when joint k moves (the child's subtree)
    parent_body: np.ndarray  # [J] body id of the moving part's parent
    pieces: dict[int, list[np.ndarray]] = field(default_factory=dict)  # part -> hull vertices (part frame, m)

    def to_model_units(self, k: int, value_nu_or_rad: float) -> float:
        return value_nu_or_rad * (self.scale if self.joint_type[k] == "slide" else 1.0)


def build_sim_model(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float,
                    options: SimOptions = SimOptions(), pieces: dict[int, list[np.ndarray]] | None = None) -> SimModel:
    """Compile the simulation model. ``pieces`` (from an earlier build) skips the decomposition."""
    if options.contact_pairs is not None and not options.frictionless:
        raise ValueError("SimOptions.contact_pairs are frictionless pairs: set frictionless=True as well")
    check_nesting(structure)
    export = assemble(structure, parts, scale)
    if pieces is None:
        pieces = {p.part_id: convex_pieces(p.mesh, MIN_PIECE_M, scale) for p in export}
    gains = None
    if options.actuators:  # servo gains scale with each joint's effective inertia: compile once without
        bare = _compile(export, pieces, scale, dataclasses.replace(options, actuators=False, visual=False))
        gains = _servo_gains(bare[0])
    (model, part_body, xml, assets) = _compile(export, pieces, scale, options, gains)
    return _sim_model(structure, export, model, part_body, xml, assets, scale, pieces)


def _compile(export: list[ExportPart], pieces, scale: float, options: SimOptions, gains=None):
    xml, assets = _mjcf(export, pieces, scale, options, gains)
    try:
        model = mujoco.MjModel.from_xml_string(xml, assets)
    except ValueError as error:  # MuJoCo's compiler errors, "Caught an unknown exception!" among them
        first = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
        raise Jax3dcError(f"MuJoCo could not compile the simulation model of these parts: {first[:300]}") from None
    part_body = {p.part_id: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, p.label) for p in export}
    return model, part_body, xml, assets


def _servo_gains(model: mujoco.MjModel) -> dict[str, tuple[float, float]]:
    """kp, kv per joint name: critically damped at SERVO_OMEGA for the joint's own inertia at rest."""
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)
    gains = {}
    for j in range(model.njnt):
        if int(model.jnt_type[j]) in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)):
            inertia = max(full[model.jnt_dofadr[j], model.jnt_dofadr[j]], 1e-9)
            gains[mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j)] = (SERVO_OMEGA ** 2 * inertia, 2 * SERVO_OMEGA * inertia)
    return gains


def _mjcf(export: list[ExportPart], pieces, scale: float, options: SimOptions, gains) -> tuple[str, dict[str, bytes]]:
    root = ET.Element("mujoco", model="physics_check")
    ET.SubElement(root, "compiler", angle="radian", autolimits="true")
    ET.SubElement(root, "size", memory=ARENA_MEMORY)
    option = ET.SubElement(root, "option", timestep=str(TIMESTEP_S), integrator="implicitfast")
    ET.SubElement(option, "flag", filterparent="disable")
    asset = ET.SubElement(root, "asset")
    assets: dict[str, bytes] = {}
    worldbody = ET.SubElement(root, "worldbody")
    if options.floor:
        lowest = min(float((p.mesh.vertices[:, 2] + p.frame_nu[2] * scale).min()) for p in export)
        ET.SubElement(worldbody, "geom", name="floor", type="plane", size="0 0 1", pos=vec([0, 0, lowest]),
                      friction="1 0.005 0.0001", contype="1", conaffinity="2" if options.floor_contacts_only else "1")
    bodies: dict[int, ET.Element] = {}
    contact_bits = {"condim": "1"} if options.frictionless else {}
    if options.floor_contacts_only or options.contact_pairs is not None:  # pieces collide with the floor hulls' floor or through pairs alone
        contact_bits.update(contype="0", conaffinity="0")
    moving: dict[int, bool] = {}  # the part moves with some joint (only those need the proximity margin)
    for part in export:
        moving[part.part_id] = part.joint is not None or (part.parent is not None and moving[part.parent])
        parent = worldbody if part.parent is None else bodies[part.parent]
        body = ET.SubElement(parent, "body", name=part.label, pos=vec(part.offset_m))
        bodies[part.part_id] = body
        if part.parent is None and options.free_root:
            ET.SubElement(body, "freejoint", name=f"free_{part.part_id}")
        if part.joint is not None:
            ET.SubElement(body, "joint", name=f"joint_{part.part_id}", type=part.joint.type, pos="0 0 0",
                          axis=vec(unit_axis(part.joint)), range=vec(part.range_si), limited="true")
        for i, vertices in enumerate(pieces[part.part_id]):
            mesh_name = f"hull_{part.part_id}_{i}"
            ET.SubElement(asset, "mesh", name=mesh_name, vertex=vec(vertices.ravel()))
            ET.SubElement(body, "geom", name=f"collision_{part.part_id}_{i}", type="mesh", mesh=mesh_name,
                          density=vec([part.props.density_kg_m3]),
                          friction=vec([part.props.friction, 0.005, 0.0001]), group="3",
                          margin=vec([options.margin_m if moving[part.part_id] else 0.0]), **contact_bits)
        if options.floor_contacts_only and pieces[part.part_id]:  # (contype & other's conaffinity): hull-hull 2&1 = 0, hull-floor 2&2
            ET.SubElement(asset, "mesh", name=f"floor_hull_{part.part_id}", vertex=vec(_hull_vertices(pieces[part.part_id]).ravel()))
            ET.SubElement(body, "geom", name=f"floor_contact_{part.part_id}", type="mesh", mesh=f"floor_hull_{part.part_id}",
                          density="0", friction=vec([part.props.friction, 0.005, 0.0001]), group="3",
                          contype="2", conaffinity="1")
        if options.visual and part.solid != "box":
            file_name = f"visual_{part.part_id}.obj"
            assets[file_name] = obj_text(part.mesh).encode()
            ET.SubElement(asset, "mesh", name=f"visual_{part.part_id}", file=file_name)
            ET.SubElement(body, "geom", name=f"visual_{part.part_id}", type="mesh", mesh=f"visual_{part.part_id}",
                          contype="0", conaffinity="0", density="0", group="1",
                          rgba=vec(part.props.rgba))
    labels = {p.part_id: p.label for p in export}
    if options.exclude or options.contact_pairs:
        contact = ET.SubElement(root, "contact")
        for a, b in sorted(options.exclude):
            ET.SubElement(contact, "exclude", body1=labels[a], body2=labels[b])
        for a, b in sorted(options.contact_pairs or ()):
            ET.SubElement(contact, "pair", geom1=a, geom2=b, condim="1")
    if options.actuators:
        actuator = ET.SubElement(root, "actuator")
        for part in (p for p in export if p.joint is not None):
            kp, kv = gains[f"joint_{part.part_id}"]
            ET.SubElement(actuator, "position", name=f"servo_{part.part_id}", joint=f"joint_{part.part_id}",
                          kp=vec([kp]), kv=vec([kv]))
    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="unicode") + "\n", assets



def _hull_vertices(pieces: list[np.ndarray]) -> np.ndarray:
    """The vertices of the convex hull of all of a part's collision pieces."""
    points = np.concatenate(pieces)
    return points[ConvexHull(points).vertices]


def _sim_model(structure: Structure, export: list[ExportPart], model: mujoco.MjModel, part_body: dict[int, int],
               xml: str, assets: dict[str, bytes], scale: float, pieces) -> SimModel:
    jointed = [p for p in export if p.joint is not None]
    joint_ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, f"joint_{p.part_id}") for p in jointed]
    # rigid groups: a body without a joint of its own is welded to its parent (a free root starts a group)
    group = np.full(model.nbody, -1)
    for b in range(1, model.nbody):
        has_dof = model.body_jntnum[b] > 0
        group[b] = b if (has_dof or model.body_parentid[b] == 0) else group[model.body_parentid[b]]
    moved = np.zeros((len(jointed), model.nbody), dtype=bool)
    for k, part in enumerate(jointed):
        child = part_body[part.part_id]
        for b in range(1, model.nbody):
            a = b
            while a > 0 and a != child:
                a = model.body_parentid[a]
            moved[k, b] = a == child
    return SimModel(
        xml=xml, assets=assets, model=model, scale=scale, part_body=part_body,
        joint_parts=[p.part_id for p in jointed],
        joint_qpos=np.array([model.jnt_qposadr[j] for j in joint_ids], dtype=np.int64),
        joint_type=[p.joint.type for p in jointed],
        joint_range=np.array([p.range_si for p in jointed], dtype=np.float64).reshape(-1, 2),
        group_of_body=group, moved_by=moved,
        parent_body=np.array([part_body[p.parent] for p in jointed], dtype=np.int64),
        pieces=pieces,
    )
