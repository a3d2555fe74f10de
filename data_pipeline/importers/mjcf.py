"""MJCF reader (MuJoCo XML, e.g. Infinigen-Sim exports), through MuJoCo's own compiler.

MJCF has many ways to state a frame (quat, euler with any sequence and angle unit, axisangle,
xyaxes, zaxis, default classes, frames, includes); compiling the file with MuJoCo and reading
the world-frame poses at the reference configuration gets all of them right. Textures and
materials are removed before compiling: only geometry is needed, and exports often name texture
images that are not shipped.

Geometry: in a body with visual-only geoms (contype = conaffinity = 0, the Infinigen-Sim and
MuJoCo Menagerie convention for render meshes) only those are used, so that collision hulls do
not double the surface; in other bodies every geom. Planes and height fields (floors) are skipped.

Joints: hinge and slide keep their range minus the joint's ``ref`` (the file's pose is the pose
at ``ref``, so ranges are measured from it); unlimited hinges get [-pi, pi]; unlimited slides,
ball joints and free joints below the top level are rigid, with a warning. A free joint on a
top-level body only lets the object float in the world and is ignored.
"""

from __future__ import annotations

import math
from pathlib import Path

import mujoco
import numpy as np
import trimesh
from tqdm import tqdm

from data_pipeline.importers import meshes
from data_pipeline.importers.kinematic_tree import Edge, KinematicTree, Link, Motion
from data_pipeline.importers.urdf import parse_xml
from jax3dc.errors import InputFileError

HINGE_LIMIT = 2 * math.pi
_G = mujoco.mjtGeom
_J = mujoco.mjtJoint
SKIPPED_GEOMS = {int(_G.mjGEOM_PLANE), int(_G.mjGEOM_HFIELD), int(_G.mjGEOM_SDF)}


def _compile(path: Path) -> tuple[mujoco.MjModel, dict[str, tuple[list[str], list[str]]]]:
    """Compiled model without textures/materials, and each named body's geom and material names."""
    try:
        spec = mujoco.MjSpec.from_file(str(path))
    except Exception as e:
        raise InputFileError(path, f"MuJoCo cannot read it: {_one_line(e)}") from None
    names = {
        body.name: ([g.name for g in body.geoms if g.name], [g.material for g in body.geoms if g.material])
        for body in spec.bodies
        if body.name
    }
    for texture in list(spec.textures):
        spec.delete(texture)
    for material in list(spec.materials):
        spec.delete(material)
    for geom in spec.geoms:
        geom.material = ""
    for mesh in spec.meshes:
        mesh.inertia = mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL  # open render meshes are fine
    spec.compiler.boundmass = 1e-6  # helper bodies without geoms are fine too
    spec.compiler.boundinertia = 1e-9
    try:
        return spec.compile(), names
    except Exception as e:
        raise InputFileError(path, f"MuJoCo cannot compile it: {_one_line(e)}") from None


def _one_line(error: Exception) -> str:
    return " ".join(str(error).split())


def _geom_mesh(model: mujoco.MjModel, g: int) -> trimesh.Trimesh:
    """Geom ``g`` in its own frame."""
    kind, size = int(model.geom_type[g]), model.geom_size[g]
    if kind == _G.mjGEOM_MESH:
        m = model.geom_dataid[g]
        v0, nv = model.mesh_vertadr[m], model.mesh_vertnum[m]
        f0, nf = model.mesh_faceadr[m], model.mesh_facenum[m]
        return trimesh.Trimesh(model.mesh_vert[v0 : v0 + nv].astype(float), model.mesh_face[f0 : f0 + nf], process=False)
    if kind == _G.mjGEOM_BOX:
        return meshes.box(2 * size)
    if kind == _G.mjGEOM_SPHERE:
        return meshes.sphere(size[0])
    if kind == _G.mjGEOM_CYLINDER:
        return meshes.cylinder(size[0], 2 * size[1])
    if kind == _G.mjGEOM_CAPSULE:
        return meshes.capsule(size[0], 2 * size[1])
    if kind == _G.mjGEOM_ELLIPSOID:
        return meshes.ellipsoid(size)
    raise AssertionError(f"geom type {kind} is filtered before")


def _motion(model, data, j: int, name: str, where: str, warnings: list[str]) -> Motion | None:
    kind = int(model.jnt_type[j])
    ref = float(model.qpos0[model.jnt_qposadr[j]]) if kind in (_J.mjJNT_HINGE, _J.mjJNT_SLIDE) else 0.0
    limited = bool(model.jnt_limited[j])
    lo, hi = (float(v) - ref for v in model.jnt_range[j])
    if kind == _J.mjJNT_HINGE:
        if not limited:
            lo, hi = -math.pi, math.pi
        elif lo < -HINGE_LIMIT or hi > HINGE_LIMIT:
            warnings.append(f"{where}: range [{lo:.3f}, {hi:.3f}] rad clipped to [-2pi, 2pi]")
            lo, hi = max(lo, -HINGE_LIMIT), min(hi, HINGE_LIMIT)
    elif kind == _J.mjJNT_SLIDE:
        if not limited:
            warnings.append(f"{where} is an unlimited slide; imported as rigid")
            return None
    else:
        return None
    axis = np.array(data.xaxis[j], dtype=float)
    return Motion("hinge" if kind == _J.mjJNT_HINGE else "slide", axis / np.linalg.norm(axis),
                  np.array(data.xanchor[j], dtype=float), (lo, hi), name)


def read_mjcf(path: Path, progress: bool = False) -> KinematicTree:
    """Parse an MJCF file into a :class:`KinematicTree` in metres."""
    path = Path(path)
    parse_xml(path, "mujoco")  # refuses DOCTYPE/ENTITY and names malformed lines before MuJoCo sees it
    model, names = _compile(path)
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)  # data.qpos starts at qpos0: the pose written in the file
    warnings: list[str] = []

    body_names = []
    for b in range(model.nbody):
        name = model.body(b).name or f"body_{b}"
        body_names.append(name if name not in body_names else f"{name}_{b}")
    visual_only = (model.geom_contype == 0) & (model.geom_conaffinity == 0)
    bodies_with_visuals = set(model.geom_bodyid[visual_only].tolist())
    use = visual_only | ~np.isin(model.geom_bodyid, list(bodies_with_visuals))
    pieces: list[list[trimesh.Trimesh]] = [[] for _ in range(model.nbody)]
    for g in tqdm(range(model.ngeom), desc="geoms", unit="geom", disable=not progress):
        if not use[g] or int(model.geom_type[g]) in SKIPPED_GEOMS:
            continue
        matrix = np.eye(4)
        matrix[:3, :3] = data.geom_xmat[g].reshape(3, 3)
        matrix[:3, 3] = data.geom_xpos[g]
        pieces[model.geom_bodyid[g]].append(meshes.transformed(_geom_mesh(model, g), matrix))

    links = {}
    for b in range(model.nbody):
        geom_names, material_names = names.get(model.body(b).name, ([], []))
        links[body_names[b]] = Link(body_names[b], meshes.merged(pieces[b]), None,
                                    tuple(geom_names), tuple(dict.fromkeys(material_names)))
    edges = []
    for b in range(1, model.nbody):
        parent = int(model.body_parentid[b])
        joints = range(model.body_jntadr[b], model.body_jntadr[b] + model.body_jntnum[b])
        motions, joint_names, kinds = [], [], []
        for j in joints:
            name = model.joint(j).name or f"joint_{j}"
            kind = int(model.jnt_type[j])
            where = f"joint {name!r} of body {body_names[b]!r}"
            joint_names.append(name)
            kinds.append(_J(kind).name.removeprefix("mjJNT_").lower())
            if kind == _J.mjJNT_BALL or (kind == _J.mjJNT_FREE and parent != 0):
                warnings.append(f"{where} is a {kinds[-1]} joint, which a structure cannot express; imported as rigid")
            motion = _motion(model, data, j, name, where, warnings)
            if motion is not None:
                motions.append(motion)
        edges.append(Edge(body_names[parent], body_names[b], "+".join(joint_names) or "(none)",
                          "+".join(kinds) or "fixed", tuple(motions)))
    return KinematicTree(path, "mjcf", body_names[0], links, edges, warnings)
