"""The simulation MJCF of an object: what ``jax3dc export --format mjcf`` writes and what the
physics checks (``jax3dc.physics``) run on, from one builder.

The object, in metres, with one body per part nested as the structure (frames and names from
``assembly``):

* Collision: the part's convex pieces (``jax3dc.geometry.convex_pieces``: a concave carcass or
  bucket is not its hull), inline meshes in geom group 3 with the family's friction. Visual: the
  part mesh (``meshes/<id>.obj``, group 1, the family's material), or the 1 mm box of a flat part;
  visual geoms never collide (contype = conaffinity = 0), which is also how importers tell them apart.
* Mass: an explicit inertial per body from the part's solid and family density
  (``jax3dc.geometry.mass``), the same figures as the URDF and USD exports.
* Joints: the structure's hinges and slides, limited, with per-family damping, dry friction and
  armature (``jax3dc.materials``) scaled by the joint's effective inertia.
* Contacts: every pair of parts collides (a part with its parent too), except the pairs that touch
  at rest or while one joint travels between its limits (``travel_contacts``): the structure's
  limits are a joint's stops, and approximate pieces that interlock or graze would push the parts
  apart or stop the joint short. What remains collides with the world (a floor, a robot, another
  object) and where several joints move at once.
* Base: roots fixed to the world, or a free joint each (``free_root``: an object that stands on a
  floor, falls or is pushed). A mounted object (``jax3dc.mounted``: fixed to a wall, counter or
  floor in use) keeps a fixed base; the exporter decides that, this builder only obeys ``free_root``.
* Optional position servos (``actuators``), critically damped at ``SERVO_OMEGA`` for each joint's
  inertia.

The physics checks ask for extras through the same options: a floor, contacts with the floor only,
an explicit set of excluded pairs instead of ``travel_contacts`` (none: they measure the contacts), frictionless contacts or only
chosen contact pairs, and a contact margin for proximity queries.
"""

from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import mujoco
import numpy as np
import trimesh
from scipy.spatial import ConvexHull

from jax3dc.errors import Jax3dcError
from jax3dc.export.assembly import ExportPart, assemble, check_nesting, unit_axis, vec
from jax3dc.geometry.convex_pieces import convex_pieces
from jax3dc.geometry.parts import obj_text
from jax3dc.materials import MATERIALS
from jax3dc.structure.schema import Structure

MESH_DIR = "meshes"
TIMESTEP_S = 0.002
MIN_PIECE_M = 2e-3  # collision pieces are at least this thick (metres)
ARENA_MEMORY = "64M"  # room for the contacts of many convex pieces within a proximity margin
SERVO_OMEGA = 60.0  # natural frequency (rad/s) of the critically damped joint servos
FLOOR_FRICTION = "1 0.005 0.0001"
MAX_SWEEP_SAMPLES = 2000  # poses per joint when looking for the pairs its travel brings into contact


@dataclass(frozen=True)
class ModelOptions:
    """What the model carries. The defaults are the exported file's; the physics checks change the rest."""

    free_root: bool = False  # a free joint on each root
    actuators: bool = False  # a position servo on every joint
    visual: bool = True  # visual geoms (the checks need only collision)
    exclude: frozenset[tuple[int, int]] | None = None  # part pairs (a < b) never in contact; None: ``travel_contacts``
    floor: bool = False  # a plane under the lowest point of the rest pose
    floor_contacts_only: bool = False  # parts touch the floor (one hull each) and other objects, not their own object's
    frictionless: bool = False  # condim 1: only collisions block motion
    margin_m: float = 0.0  # contacts of moving parts are reported up to this distance apart
    # only these collision geom pairs (names) collide, through explicit frictionless pairs (requires
    # ``frictionless``): MJX compiles one collision function per distinct mesh pair it may test
    contact_pairs: frozenset[tuple[str, str]] | None = None


@dataclass(frozen=True)
class SimulationMJCF:
    """The model's XML, its mesh files ({path relative to the XML: bytes}), the assembled parts and
    their collision pieces (part frame, metres: reusable for another build of the same parts)."""

    xml: str
    files: dict[str, bytes]
    parts: list[ExportPart]
    pieces: dict[int, list[np.ndarray]]

    def compile(self) -> mujoco.MjModel:
        return compile_mjcf(self.xml, self.files)


def simulation_mjcf(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float,
                    options: ModelOptions = ModelOptions(), *, model_name: str = "object",
                    pieces: dict[int, list[np.ndarray]] | None = None) -> SimulationMJCF:
    """Build the model; ``pieces`` (from an earlier build of the same parts) skips the decomposition."""
    if options.contact_pairs is not None and not options.frictionless:
        raise ValueError("the options' contact_pairs are frictionless pairs: set frictionless=True as well")
    check_nesting(structure)
    export = assemble(structure, parts, scale)
    if pieces is None:
        pieces = _pieces(export, scale)
    exclude = options.exclude
    if exclude is None:
        bare = ModelOptions(visual=False, exclude=frozenset())
        exclude = travel_contacts(SimulationMJCF(*_mjcf(export, pieces, scale, bare, model_name), export, pieces))
    xml, files = _mjcf(export, pieces, scale, dataclasses.replace(options, exclude=exclude), model_name)
    return SimulationMJCF(xml, files, export, pieces)


def collision_pieces(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float) -> dict[int, list[np.ndarray]]:
    """Each part's convex collision pieces (part frame, metres), as ``simulation_mjcf`` decomposes them."""
    return _pieces(assemble(structure, parts, scale), scale)


def _pieces(export: list, scale: float) -> dict[int, list[np.ndarray]]:
    return {p.part_id: convex_pieces(p.mesh, MIN_PIECE_M, scale) for p in export}


def compile_mjcf(xml: str, files: dict[str, bytes]) -> mujoco.MjModel:
    """MuJoCo's model; its compiler errors ("Caught an unknown exception!" among them) become Jax3dcError."""
    try:
        return mujoco.MjModel.from_xml_string(xml, files)
    except ValueError as error:
        first = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
        raise Jax3dcError(f"MuJoCo could not compile the simulation model of these parts: {first[:300]}") from None


def travel_contacts(model: SimulationMJCF) -> frozenset[tuple[int, int]]:
    """Part pairs (a < b) whose collision pieces touch at rest or while any one joint travels between
    its limits (the others at rest), sampled so that no point moves more than ``MIN_PIECE_M``
    between samples: interlocking meshes at rest, and pieces that graze where the real parts slide
    past each other (hulls of voxel boxes, 32-vertex caps), would stop a joint short of the limits
    the structure gives it. Only pairs within one object: in a scene, a part that a joint swings
    into another object (a lid opened into the table its box stands on) meets it, as in the world."""
    compiled = model.compile()
    data = mujoco.MjData(compiled)
    part_of = {mujoco.mj_name2id(compiled, mujoco.mjtObj.mjOBJ_BODY, p.label): p.part_id for p in model.parts}
    root_of = _roots(model.parts)
    pairs: set[tuple[int, int]] = set()

    def touching(qpos: np.ndarray) -> None:
        data.qpos[:] = qpos
        mujoco.mj_kinematics(compiled, data)
        mujoco.mj_collision(compiled, data)
        for g1, g2 in zip(data.contact.geom1[:data.ncon], data.contact.geom2[:data.ncon]):
            a, b = part_of.get(int(compiled.geom_bodyid[g1])), part_of.get(int(compiled.geom_bodyid[g2]))
            if a is not None and b is not None and a != b and root_of[a] == root_of[b]:
                pairs.add((min(a, b), max(a, b)))

    touching(compiled.qpos0)
    for j in range(compiled.njnt):  # the structure's hinges and slides (the model has no free joint)
        lo, hi = compiled.jnt_range[j]
        travel = (hi - lo) * (hinge_reach(compiled, data, j) if int(compiled.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_HINGE) else 1.0)
        for value in np.linspace(lo, hi, min(MAX_SWEEP_SAMPLES, max(2, int(np.ceil(travel / MIN_PIECE_M)) + 1))):
            qpos = compiled.qpos0.copy()
            qpos[compiled.jnt_qposadr[j]] = value
            touching(qpos)
    return frozenset(pairs)


def _roots(export: list[ExportPart]) -> dict[int, int]:
    """Part id -> the root of its tree (its object, in a scene)."""
    root_of: dict[int, int] = {}
    for part in export:  # tree order: parents first
        root_of[part.part_id] = part.part_id if part.parent is None else root_of[part.parent]
    return root_of


def _object_bits(export: list[ExportPart]) -> dict[int, dict[str, str]]:
    """Contact bits of each part's collision pieces in a floor-contacts-only model of a scene: the
    pieces of one object do not touch each other, those of different objects do (a box on a table
    stands on it). Object k owns bit k + 2 (bits 0 and 1 are the floor's); past 30 objects the bits
    repeat, so objects sharing one do not touch."""
    roots = sorted({p.part_id for p in export if p.parent is None})
    if len(roots) < 2:
        return {}
    bit = {root: 1 << (2 + k % 30) for k, root in enumerate(roots)}
    every = sum(set(bit.values()))
    root_of = _roots(export)
    return {pid: {"contype": str(bit[r]), "conaffinity": str(every & ~bit[r])} for pid, r in root_of.items()}


def hinge_reach(model: mujoco.MjModel, data: mujoco.MjData, j: int) -> float:
    """Farthest distance (m) of a collision vertex that hinge ``j`` moves from its axis line, at rest:
    how far a turn of the hinge carries a point, so a sweep can be sampled densely enough."""
    data.qpos[:] = model.qpos0
    mujoco.mj_kinematics(model, data)
    anchor, axis = data.xanchor[j], data.xaxis[j]
    body = model.jnt_bodyid[j]
    radius = 0.0
    for g in range(model.ngeom):
        b = model.geom_bodyid[g]
        while b > body:  # bodies are numbered parents first: walk up to see whether the joint moves it
            b = model.body_parentid[b]
        if b != body or model.geom_type[g] != mujoco.mjtGeom.mjGEOM_MESH:
            continue
        adr, n = model.mesh_vertadr[model.geom_dataid[g]], model.mesh_vertnum[model.geom_dataid[g]]
        points = model.mesh_vert[adr:adr + n] @ data.geom_xmat[g].reshape(3, 3).T + data.geom_xpos[g] - anchor
        radius = max(radius, float(np.max(np.linalg.norm(points - np.outer(points @ axis, axis), axis=1))))
    return radius


def joint_inertia(export: list[ExportPart]) -> dict[int, float]:
    """Per jointed part: the effective inertia of its joint at rest (kg·m² about a hinge's axis,
    kg along a slide): the moved subtree's, which is MuJoCo's joint-space inertia without armature."""
    children: dict[int | None, list[ExportPart]] = {}
    for part in export:
        children.setdefault(part.parent, []).append(part)
    origin = {}  # part frame origin in the object frame, metres
    for part in export:  # tree order: parents first
        origin[part.part_id] = part.offset_m + (origin[part.parent] if part.parent is not None else 0.0)
    out = {}
    for part in (p for p in export if p.joint is not None):
        axis, pivot = unit_axis(part.joint), origin[part.part_id]
        total, stack = 0.0, [part]
        while stack:
            body = stack.pop()
            stack.extend(children.get(body.part_id, []))
            if part.joint.type == "slide":
                total += body.mass.mass
            else:
                arm = np.cross(axis, origin[body.part_id] + body.mass.center_of_mass - pivot)
                total += float(axis @ body.mass.inertia @ axis) + body.mass.mass * float(arm @ arm)
        out[part.part_id] = total
    return out


def _mjcf(export: list[ExportPart], pieces: dict[int, list[np.ndarray]], scale: float, options: ModelOptions,
          model_name: str) -> tuple[str, dict[str, bytes]]:
    root = ET.Element("mujoco", model=model_name)
    ET.SubElement(root, "compiler", angle="radian", meshdir=MESH_DIR, autolimits="true")
    ET.SubElement(root, "size", memory=ARENA_MEMORY)
    option = ET.SubElement(root, "option", timestep=str(TIMESTEP_S), integrator="implicitfast")
    ET.SubElement(option, "flag", filterparent="disable")
    asset = ET.SubElement(root, "asset")
    files: dict[str, bytes] = {}
    if options.visual:
        for material_id in sorted({p.material_id for p in export}):
            family = next(p.family for p in export if p.material_id == material_id)
            ET.SubElement(asset, "material", name=f"material_{material_id}", rgba=vec(MATERIALS[family].rgba))
    worldbody = ET.SubElement(root, "worldbody")
    if options.floor:
        lowest = min(float((p.mesh.vertices[:, 2] + p.frame_nu[2] * scale).min()) for p in export)
        ET.SubElement(worldbody, "geom", name="floor", type="plane", size="0 0 1", pos=vec([0, 0, lowest]),
                      friction=FLOOR_FRICTION, contype="1", conaffinity="2" if options.floor_contacts_only else "1")
    inertia = joint_inertia(export)
    contact_bits = {"condim": "1"} if options.frictionless else {}
    if options.floor_contacts_only or options.contact_pairs is not None:  # pieces collide through the floor hulls or the pairs alone
        contact_bits.update(contype="0", conaffinity="0")
    scene_bits = _object_bits(export) if options.floor_contacts_only else {}
    bodies: dict[int, ET.Element] = {}
    moving: dict[int, bool] = {}  # the part moves with some joint (only those need the proximity margin)
    for part in export:
        moving[part.part_id] = part.joint is not None or (part.parent is not None and moving[part.parent])
        parent = worldbody if part.parent is None else bodies[part.parent]
        body = ET.SubElement(parent, "body", name=part.label, pos=vec(part.offset_m))
        bodies[part.part_id] = body
        m = part.mass
        ET.SubElement(body, "inertial", pos=vec(m.center_of_mass), mass=vec([m.mass]), fullinertia=vec(
            [m.inertia[0, 0], m.inertia[1, 1], m.inertia[2, 2], m.inertia[0, 1], m.inertia[0, 2], m.inertia[1, 2]]))
        if part.parent is None and options.free_root:
            ET.SubElement(body, "freejoint", name=f"free_{part.part_id}")
        if part.joint is not None:
            i = inertia[part.part_id]
            ET.SubElement(body, "joint", name=f"joint_{part.part_id}", type=part.joint.type, pos="0 0 0",
                          axis=vec(unit_axis(part.joint)), range=vec(part.range_si), limited="true",
                          damping=vec([i / part.props.joint_decay_s]), frictionloss=vec([i * part.props.joint_friction]),
                          armature=vec([i * part.props.joint_armature]))
        friction = vec([part.props.friction, 0.005, 0.0001])
        margin = {"margin": vec([options.margin_m])} if options.margin_m and moving[part.part_id] else {}
        for k, vertices in enumerate(pieces[part.part_id]):
            mesh_name = f"hull_{part.part_id}_{k}"
            ET.SubElement(asset, "mesh", name=mesh_name, vertex=vec(vertices.ravel()))
            ET.SubElement(body, "geom", name=f"collision_{part.part_id}_{k}", type="mesh", mesh=mesh_name,
                          friction=friction, group="3", **margin, **{**contact_bits, **scene_bits.get(part.part_id, {})})
        if options.floor_contacts_only and pieces[part.part_id]:  # (contype & other's conaffinity): hull-hull 2&1 = 0, hull-floor 2&2
            ET.SubElement(asset, "mesh", name=f"floor_hull_{part.part_id}", vertex=vec(_hull_vertices(pieces[part.part_id]).ravel()))
            ET.SubElement(body, "geom", name=f"floor_contact_{part.part_id}", type="mesh", mesh=f"floor_hull_{part.part_id}",
                          friction=friction, group="3", contype="2", conaffinity="1")
        if options.visual:
            _visual_geom(part, asset, body, files)
    labels = {p.part_id: p.label for p in export}
    if options.exclude or options.contact_pairs:
        contact = ET.SubElement(root, "contact")
        for a, b in sorted(options.exclude or ()):
            ET.SubElement(contact, "exclude", body1=labels[a], body2=labels[b])
        for a, b in sorted(options.contact_pairs or ()):
            ET.SubElement(contact, "pair", geom1=a, geom2=b, condim="1")
    if options.actuators:
        actuator = ET.SubElement(root, "actuator")
        for part in (p for p in export if p.joint is not None):
            servo_inertia = inertia[part.part_id] * (1 + part.props.joint_armature)  # what the joint accelerates
            ET.SubElement(actuator, "position", name=f"servo_{part.part_id}", joint=f"joint_{part.part_id}",
                          kp=vec([SERVO_OMEGA ** 2 * servo_inertia]), kv=vec([2 * SERVO_OMEGA * servo_inertia]))
    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="unicode") + "\n", files


def _visual_geom(part: ExportPart, asset: ET.Element, body: ET.Element, files: dict[str, bytes]) -> None:
    """The part as it looks, never colliding: its mesh, or for a flat part (which MuJoCo refuses as a
    mesh: "coplanar vertices") the 1 mm box of its bounds; the mesh file is written either way."""
    look = {"material": f"material_{part.material_id}", "contype": "0", "conaffinity": "0", "group": "1"}
    files[f"{MESH_DIR}/{part.part_id}.obj"] = obj_text(part.mesh).encode()  # a flat part's too: a check of the file reads it
    if part.solid == "box":
        centre, size = part.box_fallback()
        ET.SubElement(body, "geom", name=f"visual_{part.part_id}", type="box", pos=vec(centre), size=vec(size / 2), **look)
        return
    ET.SubElement(asset, "mesh", name=f"visual_{part.part_id}", file=f"{part.part_id}.obj",
                  inertia="exact" if part.solid == "mesh" else "convex")
    ET.SubElement(body, "geom", name=f"visual_{part.part_id}", type="mesh", mesh=f"visual_{part.part_id}", **look)


def _hull_vertices(pieces: list[np.ndarray]) -> np.ndarray:
    """The vertices of the convex hull of all of a part's collision pieces: against a plane, the hull
    of a union has the union's lowest points and support polygon, and one plane pair per part keeps
    MJX's compiled step small (a PartNet-Mobility safe has 213 pieces)."""
    points = np.concatenate(pieces)
    return points[ConvexHull(points).vertices]
