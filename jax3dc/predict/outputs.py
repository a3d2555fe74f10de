"""Writing a predicted object: the exports of SPEC §1 and the physics verdict of SPEC §8.

Each writer returns the paths it wrote, so the pipeline can list every output even when a later
step fails. URDF and MJCF share ``meshes/<id>.obj`` (the same part meshes in the same link frames);
the URDF's collision hulls are ``meshes/<id>_collision_<k>.obj``, the MJCF's pieces inline.
"""

from __future__ import annotations

import json
from pathlib import Path

import trimesh

from jax3dc.export.blender import export_blender
from jax3dc.export.gltf import export_gltf
from jax3dc.export.mjcf import export_mjcf
from jax3dc.export.urdf import export_urdf
from jax3dc.geometry.mesh_size import PHYSICS_MAX_FACES, check_object_faces
from jax3dc.physics.findings import Verdict
from jax3dc.export.usd import export_usd
from jax3dc.structure.schema import Structure
from jax3dc.viewer import ViewerInputs, write_viewer

MODEL_NAME = "object"


def write_exports(structure: Structure, parts: dict[int, trimesh.Trimesh], out: Path, scale: float,
                  mounted: bool = False) -> dict[str, Path]:
    """object.glb, object_blender.py, object.urdf, object.usda and object.xml (MJCF) in ``out``, in metres.

    object.xml is the model the physics check (``write_physics`` with the same ``mounted``) judges:
    its root is free, as the check stands the object on a floor, unless ``mounted``, whose base
    stays fixed, as the check holds it.

    URDF, USD and MJCF collide through the physics check's convex pieces (decomposed once, see
    ``jax3dc.geometry.convex_pieces``), whose cost grows with the triangles: an object over
    PHYSICS_MAX_FACES is refused after the GLB and the Blender script are written."""
    files = {
        "glb": export_gltf(structure, parts, out, scale, model_name=MODEL_NAME),
        "blender": export_blender(structure, parts, out, scale, model_name=MODEL_NAME),
    }
    check_object_faces(parts, PHYSICS_MAX_FACES, "the URDF, USD and MJCF exports and the physics check",
                       flag="`--max-faces` of `jax3dc export` and `jax3dc physics check` on the parts")
    files["urdf"] = export_urdf(structure, parts, out, scale, model_name=MODEL_NAME)
    files["usd"] = export_usd(structure, parts, out, scale, model_name=MODEL_NAME)
    files["mjcf"] = export_mjcf(structure, parts, out, scale, model_name=MODEL_NAME, free=True, mounted=mounted)
    return files


def write_physics(verdict: Verdict, out: Path) -> Path:
    """physics.json: the object's plausibility verdict as JSON (``Verdict.to_json``: ok, per-joint
    reasons, checks, findings), computed by the caller's VerdictCache (``write_exports`` has refused
    an object too large for it)."""
    path = out / "physics.json"
    path.write_text(json.dumps(verdict.to_json(), indent=1, sort_keys=True) + "\n", encoding="utf-8")
    return path


def write_viewer_page(out: Path, glb: Path, verdict: Verdict | None, image_png: bytes, seg_png: bytes) -> Path:
    """viewer.html (+ viewer_files/): the exported GLB in 3D with joint sliders, the verdict, I and S."""
    return write_viewer(ViewerInputs(glb.read_bytes(), out.resolve().name, str(glb), verdict, image_png, seg_png),
                        out / "viewer.html")
