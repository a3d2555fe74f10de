"""USD export (one text ``.usda`` layer) with UsdPhysics, for USD simulators (Isaac Sim, Newton, ...).

Stage: Z up, 1 metre and 1 kg per unit, a ``/physicsScene`` with gravity, and the object under the
default prim, outside the scene so that referencing the asset does not bring a second scene.
Each part is an Xform nested as in the structure, at its part frame (see ``assembly``), holding:

* ``RigidBodyAPI`` and ``MassAPI``: the same mass as MJCF and URDF (solid × family density), its
  centre of mass and principal inertia;
* ``mesh``: the part mesh in the part frame, display colour and opacity of the family (visual only);
* ``collision_<k>``: the colliders, the part's convex pieces as in the MJCF and the URDF
  (``jax3dc.geometry.convex_pieces``: a concave carcass is not its hull, a flat part is a 2 mm
  plate), each a hull mesh with the ``convexHull`` approximation (exact for a convex mesh, and at
  most 32 vertices, within PhysX's hull limit) and the ``guide`` purpose, so it is not rendered;
* ``joint_<id>``: revolute (limits in degrees, as UsdPhysics wants) or prismatic (metres) joint
  to the parent body, a fixed joint for a rigid part, and a fixed joint to the world for a root
  (the object stays where it is, as in MJCF and URDF; disable it to let the object move).

UsdPhysics joints turn about or slide along a coordinate axis of their joint frames: each joint
uses the coordinate axis nearest to the structure's axis and rotates both joint frames onto it.
Bodies below another body reset the transform stack and carry their world translation, since
PhysX drops a rigid body nested in another one without that reset. Roots carry the articulation
root; physics materials (friction) bind to the colliders with the ``physics`` purpose. The
structure's part ids, names, materials and relations go into ``customData["jax3dc"]``.

A scene of several objects (several roots, SPEC §2) holds each object under its own Xform
``object_<root>`` (``customData["jax3dc"]``: ``object``, its root, and ``parts``, its part ids)
beneath the default prim, so each object is one subtree; a single object's root part sits
directly under the default prim.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from pathlib import Path

import numpy as np
import trimesh
from pxr import Gf, Sdf, Tf, Usd, UsdGeom, UsdPhysics, UsdShade, Vt
from scipy.optimize import linear_sum_assignment
from scipy.spatial.transform import Rotation

from jax3dc.export.assembly import ExportPart, assemble, object_label, objects, unit_axis
from jax3dc.export.files import write_files
from jax3dc.export.gltf import relation_extras
from jax3dc.export.simulation import MIN_PIECE_M
from jax3dc.geometry.convex_pieces import convex_pieces, hull_mesh
from jax3dc.materials import MATERIALS
from jax3dc.structure.schema import Structure

SCENE_PATH = "/physicsScene"
GRAVITY_M_S2 = 9.81
AXES = ("X", "Y", "Z")


def _clean(values: Iterable[float]) -> list[float]:
    """Positions and quaternion parts without negative zeros or round-off specks (below 1e-12), so
    equal inputs print the same. Not for inertias: a millimetre part has moments near 1e-12."""
    return [0.0 if abs(v) < 1e-12 else float(v) + 0.0 for v in values]


def _quat(rotation: Rotation) -> Gf.Quatf:
    x, y, z, w = _clean(rotation.as_quat(canonical=True))
    return Gf.Quatf(w, x, y, z)


def _joint_axis_frame(axis: np.ndarray) -> tuple[str, Rotation]:
    """UsdPhysics axis token and the joint-frame rotation that carries that axis onto ``axis``."""
    k = int(np.argmax(np.abs(axis)))
    rotation, _ = Rotation.align_vectors(axis[None], np.eye(3)[k][None])
    return AXES[k], rotation


def _principal_inertia(inertia: np.ndarray) -> tuple[np.ndarray, Rotation]:
    """Principal moments and axes of a symmetric tensor, axes ordered and signed to lie nearest the
    frame's own (the identity when the tensor is already diagonal), as a proper rotation."""
    moments, vectors = np.linalg.eigh(inertia)
    _, order = linear_sum_assignment(-np.abs(vectors))  # row i (frame axis) <- column order[i]
    moments, vectors = moments[order], vectors[:, order]
    vectors = vectors * np.where(np.diag(vectors) < 0, -1.0, 1.0)
    if np.linalg.det(vectors) < 0:
        vectors[:, 2] *= -1
    return moments, Rotation.from_matrix(vectors)


def _physics_materials(stage: Usd.Stage, root: Sdf.Path, structure: Structure) -> dict[int, UsdShade.Material]:
    scope = UsdGeom.Scope.Define(stage, root.AppendChild("materials"))
    out = {}
    for material_id, material in sorted(structure.materials.items()):
        shade = UsdShade.Material.Define(stage, scope.GetPath().AppendChild(f"material_{material_id}"))
        physics = UsdPhysics.MaterialAPI.Apply(shade.GetPrim())
        friction = MATERIALS[material.family].friction
        physics.CreateStaticFrictionAttr(friction)
        physics.CreateDynamicFrictionAttr(friction)
        physics.CreateRestitutionAttr(0.0)
        out[material_id] = shade
    return out


def _colliders(stage: Usd.Stage, path: Sdf.Path, part: ExportPart, scale: float,
               material: UsdShade.Material) -> None:
    """One ``collision_<k>`` hull per convex piece of the part (the MJCF's collision geoms)."""
    for k, vertices in enumerate(convex_pieces(part.mesh, MIN_PIECE_M, scale)):
        hull = hull_mesh(vertices)
        mesh = _triangles(stage, path.AppendChild(f"collision_{k}"), hull.vertices, hull.faces)
        mesh.CreatePurposeAttr(UsdGeom.Tokens.guide)
        prim = mesh.GetPrim()
        UsdPhysics.CollisionAPI.Apply(prim)
        UsdPhysics.MeshCollisionAPI.Apply(prim).CreateApproximationAttr(UsdPhysics.Tokens.convexHull)
        UsdShade.MaterialBindingAPI.Apply(prim).Bind(material, UsdShade.Tokens.fallbackStrength, "physics")


def _triangles(stage: Usd.Stage, path: Sdf.Path, vertices: np.ndarray, faces: np.ndarray) -> UsdGeom.Mesh:
    """A Mesh prim of triangles as they are (float32 points, not a subdivision cage)."""
    mesh = UsdGeom.Mesh.Define(stage, path)
    points = np.asarray(vertices, dtype=np.float32) + np.float32(0.0)
    faces = np.asarray(faces, dtype=np.int32)
    mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(points))
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(len(faces), 3, dtype=np.int32)))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(faces.reshape(-1)))
    mesh.CreateExtentAttr(Vt.Vec3fArray.FromNumpy(np.stack([points.min(axis=0), points.max(axis=0)])))
    mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
    return mesh


def _mesh(stage: Usd.Stage, path: Sdf.Path, part: ExportPart) -> UsdGeom.Mesh:
    mesh = _triangles(stage, path.AppendChild("mesh"), part.mesh.vertices, part.mesh.faces)
    mesh.CreateDoubleSidedAttr(True)  # open part meshes are seen from both sides
    r, g, b, a = part.props.rgba
    mesh.CreateDisplayColorAttr(Vt.Vec3fArray([Gf.Vec3f(r, g, b)]))
    mesh.CreateDisplayOpacityAttr(Vt.FloatArray([a]))
    return mesh


def _mass(prim: Usd.Prim, part: ExportPart) -> None:
    mass = UsdPhysics.MassAPI.Apply(prim)
    mass.CreateMassAttr(part.mass.mass)
    mass.CreateCenterOfMassAttr(Gf.Vec3f(*_clean(part.mass.center_of_mass)))
    moments, axes = _principal_inertia(part.mass.inertia)
    mass.CreateDiagonalInertiaAttr(Gf.Vec3f(*(float(m) for m in moments)))
    mass.CreatePrincipalAxesAttr(_quat(axes))


def _joint(stage: Usd.Stage, path: Sdf.Path, part: ExportPart, parent: Sdf.Path | None) -> None:
    """The joint from the parent body (the world for a root) to the part, at the part frame origin."""
    joint_path = path.AppendChild(f"joint_{part.part_id}")
    if part.joint is None:
        joint = UsdPhysics.FixedJoint.Define(stage, joint_path)
        rotation = Rotation.identity()
    else:
        token, rotation = _joint_axis_frame(unit_axis(part.joint))
        hinge = part.joint.type == "hinge"
        joint = (UsdPhysics.RevoluteJoint if hinge else UsdPhysics.PrismaticJoint).Define(stage, joint_path)
        joint.CreateAxisAttr(token)
        lower, upper = (math.degrees(v) for v in part.range_si) if hinge else part.range_si
        joint.CreateLowerLimitAttr(lower)
        joint.CreateUpperLimitAttr(upper)
    if parent is not None:
        joint.CreateBody0Rel().SetTargets([parent])
    joint.CreateBody1Rel().SetTargets([path])
    joint.CreateLocalPos0Attr(Gf.Vec3f(*_clean(part.offset_m)))
    joint.CreateLocalRot0Attr(_quat(rotation))
    joint.CreateLocalPos1Attr(Gf.Vec3f(0.0, 0.0, 0.0))
    joint.CreateLocalRot1Attr(_quat(rotation))


def _part_data(part: ExportPart, structure: Structure) -> dict:
    material = structure.materials[part.material_id]
    data = {"part_id": part.part_id, "material": {"id": part.material_id, "family": material.family}}
    if part.name is not None:
        data["name"] = part.name
    if material.desc is not None:
        data["material"]["desc"] = material.desc
    return data


def _object_prims(stage: Usd.Stage, root: Sdf.Path, trees: dict[int, list[int]]) -> dict[int, Sdf.Path]:
    """The prim each root part goes under: the default prim for one object; for a scene, an
    ``object_<root>`` Xform per object (see the module docstring)."""
    if len(trees) == 1:
        return {r: root for r in trees}
    out = {}
    for r, members in trees.items():
        holder = UsdGeom.Xform.Define(stage, root.AppendChild(object_label(r)))
        holder.GetPrim().SetCustomDataByKey("jax3dc", {"object": r, "parts": Vt.IntArray(members)})
        out[r] = holder.GetPath()
    return out


def usd_stage(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float = 1.0, *,
              model_name: str = "object") -> Usd.Stage:
    """The export as an in-memory stage (see the module docstring for its layout)."""
    export = assemble(structure, parts, scale)
    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    UsdPhysics.SetStageKilogramsPerUnit(stage, 1.0)
    root = UsdGeom.Xform.Define(stage, Sdf.Path.absoluteRootPath.AppendChild(Tf.MakeValidIdentifier(model_name)))
    stage.SetDefaultPrim(root.GetPrim())
    root.GetPrim().SetCustomDataByKey("jax3dc", {
        "scale_m_per_nu": float(scale),
        "relations": {f"relation_{i}": relation_extras(r) for i, r in enumerate(structure.relations)},
    })
    materials = _physics_materials(stage, root.GetPath(), structure)
    top = _object_prims(stage, root.GetPath(), objects(structure))
    paths: dict[int, Sdf.Path] = {}
    for part in export:
        parent = paths[part.parent] if part.parent is not None else None
        path = (top[part.part_id] if parent is None else parent).AppendChild(part.label)
        paths[part.part_id] = path
        body = UsdGeom.Xform.Define(stage, path)
        if parent is not None:
            body.SetResetXformStack(True)
        body.AddTranslateOp().Set(Gf.Vec3d(*_clean(part.frame_nu * scale)))
        prim = body.GetPrim()
        prim.SetCustomDataByKey("jax3dc", _part_data(part, structure))
        UsdPhysics.RigidBodyAPI.Apply(prim)
        if parent is None:
            UsdPhysics.ArticulationRootAPI.Apply(prim)
        _mass(prim, part)
        _mesh(stage, path, part)
        _colliders(stage, path, part, scale, materials[part.material_id])
        _joint(stage, path, part, parent)
    scene = UsdPhysics.Scene.Define(stage, SCENE_PATH)
    scene.CreateGravityDirectionAttr(Gf.Vec3f(0.0, 0.0, -1.0))
    scene.CreateGravityMagnitudeAttr(GRAVITY_M_S2)
    return stage


def usd_model(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float = 1.0, *,
              model_name: str = "object") -> str:
    """The ``.usda`` text; the same structure and parts give the same text."""
    stage = usd_stage(structure, parts, scale, model_name=model_name)  # held: the layer lives while it does
    return stage.GetRootLayer().ExportToString()


def export_usd(structure: Structure, parts: dict[int, trimesh.Trimesh], out_dir: str | Path, scale: float = 1.0, *,
               model_name: str = "object") -> Path:
    """Write ``<out_dir>/<model_name>.usda``; returns its path."""
    text = usd_model(structure, parts, scale, model_name=model_name)
    return write_files(Path(out_dir), f"{model_name}.usda", text, {})
