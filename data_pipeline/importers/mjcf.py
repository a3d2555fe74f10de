"""MJCF reader (MuJoCo XML, e.g. Infinigen-Sim exports), through MuJoCo's own compiler.

MJCF has many ways to state a frame (quat, euler with any sequence and angle unit, axisangle,
xyaxes, zaxis, default classes, frames, includes); compiling the file with MuJoCo and reading
the world-frame poses at the reference configuration gets all of them right. Textures and
materials are removed before compiling: only geometry is needed, and exports often name texture
images that are not shipped.

Geometry: in a body with visual-only geoms (contype = conaffinity = 0, the Infinigen-Sim and
MuJoCo Menagerie convention for render meshes) only those are used, so that collision hulls do
not double the surface; in other bodies every geom. Planes and height fields (floors) are skipped.
A mesh file that cannot be a piece (see ``meshes``: missing, empty, unreadable, or one MuJoCo
refuses) is dropped before compiling, with the geoms that use it and one warning naming it; a body
whose every geom is dropped is an error naming the body.

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
from data_pipeline.importers.limits import FaceBudget, ImportLimits, inside_folder
from data_pipeline.importers.safe_xml import parse_xml
from jax3dc.errors import InputFileError, shorten

HINGE_LIMIT = 2 * math.pi
_G = mujoco.mjtGeom
_J = mujoco.mjtJoint
SKIPPED_GEOMS = {int(_G.mjGEOM_PLANE), int(_G.mjGEOM_HFIELD), int(_G.mjGEOM_SDF)}
_COUNTED = ("body", "geom")


def _check_xml(path: Path, root, limits: ImportLimits) -> None:
    """Refuse, before MuJoCo reads the file, what would cost it minutes or gigabytes: bodies and geoms
    multiplied by nested ``<replicate>``, huge height fields, and included files outside the folder."""
    total = 0
    stack = [(root, 1)]
    while stack:  # iterative: a 100,000-deep nesting must not recurse
        element, times = stack.pop()
        for child in element:
            tag = child.tag if isinstance(child.tag, str) else ""
            factor = times
            if tag == "replicate":
                count = child.get("count", "1")
                factor = times * (int(count) if count.isdigit() else 1)
            elif tag in _COUNTED:
                total += times
                if total > limits.max_bodies:
                    raise InputFileError(path, f"the model has more than {limits.max_bodies} bodies and geoms once "
                                               "<replicate> is expanded; the cap is "
                                               f"{limits.max_bodies} (raise it with --max-bodies)")
            elif tag == "hfield":
                _check_hfield(path, child, limits)
            elif tag == "include" and child.get("file"):
                inside_folder(path.parent / child.get("file"), path.parent, path, "<include>", limits, "file")
            stack.append((child, factor))


def _check_hfield(path: Path, element, limits: ImportLimits) -> None:
    rows, cols = element.get("nrow", "0"), element.get("ncol", "0")
    samples = int(rows) * int(cols) if rows.isdigit() and cols.isdigit() else 0
    # MuJoCo allocates the samples while reading the file (100000 x 100000 is 40 GB) although the
    # importer skips height fields; each sample is about two triangles, so --max-faces caps them.
    if 2 * samples > limits.max_faces:
        raise InputFileError(path, f"<hfield name={element.get('name', '')!r:.40}> has {samples} samples "
                                   f"({rows:.12} x {cols:.12}), about {2 * samples} triangles; the cap is "
                                   f"{limits.max_faces} (raise it with --max-faces)")
    if element.get("file"):
        inside_folder(path.parent / element.get("file"), path.parent, path, "<hfield>", limits, "file")


def _mesh_files(path: Path, spec: mujoco.MjSpec, limits: ImportLimits, warnings: list[str]) -> None:
    """Check each mesh file before MuJoCo loads it: inside the object's folder, faces within the cap.
    One that cannot be a piece is dropped with the geoms that use it and a warning naming it, so
    that MuJoCo's refusal of one file does not refuse the object; a body left without geometry is
    an InputFileError naming it."""
    budget = FaceBudget(limits)
    folder = path.parent
    bodies = list(spec.bodies)  # in model order: unnamed bodies are named by index as read_mjcf names them
    dropped: dict[int, list[str]] = {}  # index in ``bodies`` -> reasons
    for mesh in list(spec.meshes):
        if not mesh.file:
            continue
        where = f"<mesh name={mesh.name!r:.60}>"
        file = inside_folder(folder / (spec.meshdir or "") / mesh.file, folder, path, where, limits)
        users = [g for g in spec.geoms if g.meshname == mesh.name]
        try:
            _check_mesh(file, np.asarray(mesh.scale, float), any(g.contype or g.conaffinity for g in users),
                        path, where, budget)
        except meshes.UnusableMesh as e:
            owners = sorted({bodies.index(g.parent) for g in users})
            names = ", ".join(repr(_body_name(bodies, b)) for b in owners)
            warnings.append(f"{where}: {e}; it and the geoms using it are dropped"
                            + (f" (in {'body' if len(owners) == 1 else 'bodies'} {names})" if owners else ""))
            for geom in users:
                spec.delete(geom)
            spec.delete(mesh)
            for b in owners:
                dropped.setdefault(b, []).append(str(e))
    for b, reasons in dropped.items():
        if all(int(g.type) in SKIPPED_GEOMS for g in bodies[b].geoms):
            raise InputFileError(path, f"body {_body_name(bodies, b)!r} has no geometry left: every geom was "
                                       f"dropped ({'; '.join(reasons)})")


def _body_name(bodies: list, index: int) -> str:
    return bodies[index].name or f"body_{index}"


def _check_mesh(file: Path, scale: np.ndarray, colliding: bool, path: Path, where: str, budget: FaceBudget) -> None:
    """meshes.UnusableMesh when MuJoCo would refuse ``file`` (scaled as the <mesh> says) or cannot
    read it; formats trimesh does not read (MuJoCo's .msh) are left to MuJoCo after the file checks."""
    meshes.check_mesh_file(file)
    if file.suffix.lower() not in meshes.MESH_SUFFIXES:
        return  # the model's total faces are still capped once it is compiled
    loaded = meshes.load_mesh_file(file, path, where, budget)
    reason = meshes.refusal(np.asarray(loaded.vertices) * scale, colliding)
    if reason is not None:
        raise meshes.UnusableMesh(f"mesh file {file} {reason}")


def _compile(path: Path, limits: ImportLimits,
             warnings: list[str]) -> tuple[mujoco.MjModel, dict[str, tuple[list[str], list[str]]]]:
    """Compiled model without textures/materials, and each named body's geom and material names."""
    try:
        spec = mujoco.MjSpec.from_file(str(path))
    except Exception as e:
        raise InputFileError(path, f"MuJoCo cannot read it: {_one_line(e)}") from None
    _mesh_files(path, spec, limits, warnings)
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
    text = " ".join(str(error).split())
    if "unknown exception" in text.lower():
        # MuJoCo's C++ layer lost the reason; say what usually causes it instead of passing it on
        return ("MuJoCo failed without giving a reason (usually a mesh, height field or texture file it "
                "cannot decode, or a model too large for memory)")
    return shorten(text, 300)


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


def read_mjcf(path: Path, progress: bool = False, limits: ImportLimits = ImportLimits()) -> KinematicTree:
    """Parse an MJCF file into a :class:`KinematicTree` in metres."""
    path = Path(path)
    root = parse_xml(path, "mujoco")  # refuses DOCTYPE/ENTITY and names malformed lines before MuJoCo sees it
    _check_xml(path, root, limits)
    warnings: list[str] = []
    model, names = _compile(path, limits, warnings)
    if model.nmeshface > limits.max_faces:  # inline meshes (vertex= / face= attributes) are counted here
        raise InputFileError(path, f"the model's meshes have {model.nmeshface} faces; the cap is {limits.max_faces} "
                                   "(raise it with --max-faces)")
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)  # data.qpos starts at qpos0: the pose written in the file

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
