"""Writing a predicted object: the exports of SPEC §1, the physics verdict of SPEC §8 and the pages.

Each writer returns or announces the paths it wrote, so the pipeline can list every output even
when a later step fails. URDF and MJCF share ``meshes/<id>.obj`` (the same part meshes in the same
link frames); the URDF's collision hulls are ``meshes/<id>_collision_<k>.obj``, the MJCF's pieces
inline.

``predict`` and a hand edit (``jax3dc.edits``) write a structure's files through the same two
functions, ``write_checked`` (structure.json, the exports, physics.json) and ``write_pages``
(report and viewer), from what prediction.json keeps (``ObjectContext``), so an edited folder is
the folder predict would have written for that structure.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Callable

import numpy as np
import trimesh

from jax3dc.errors import InputFileError
from jax3dc.export.blender import export_blender
from jax3dc.export.gltf import export_gltf
from jax3dc.export.mjcf import export_mjcf
from jax3dc.export.urdf import export_urdf
from jax3dc.geometry.mesh_size import PHYSICS_MAX_FACES, check_object_faces
from jax3dc.palette import object_palette
from jax3dc.physics.findings import Verdict
from jax3dc.export.usd import export_usd
from jax3dc.predict.report import ReportInputs, write_report
from jax3dc.structure import to_json
from jax3dc.structure.schema import Structure
from jax3dc.viewer import ViewerInputs, write_viewer

MODEL_NAME = "object"
CONTEXT_FILE = "prediction.json"
PALETTE_CATEGORY = "image"  # palette seed: "image/<sha256 of the image>", the same image gets the same colours

OutputListener = Callable[[str, Path], None]
"""Called with (what, path) as each output is written (the CLI prints them)."""


@dataclass(frozen=True)
class ObjectContext:
    """What an object's files are made from besides its structure, parts/, image.png and seg.png,
    kept in prediction.json: an edit rewrites the files from it as predict wrote them."""

    scale: float  # metres per nu of the exports and the physics check
    mounted: bool  # the check holds the root and object.xml keeps its base fixed
    names: dict[int, str]  # stage 1's part names, written into the exports
    camera: dict[str, Any]  # the camera S was rendered from (Camera.to_dict)
    camera_given: bool  # the image's own camera: the report draws the joints over I, not S
    image_sha256: str  # of the input file: seeds the palette of S and the report

    def palette(self) -> np.ndarray:
        return object_palette(PALETTE_CATEGORY, self.image_sha256)

    def write(self, out: Path) -> Path:
        doc = {"scale_m_per_nu": self.scale, "mounted": self.mounted,
               "names": {str(pid): name for pid, name in sorted(self.names.items())}, "camera": self.camera,
               "camera_given": self.camera_given, "image_sha256": self.image_sha256}
        path = out / CONTEXT_FILE
        path.write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
        return path

    @classmethod
    def read(cls, folder: Path) -> "ObjectContext":
        """prediction.json of a predict folder; missing or malformed is an InputFileError."""
        path = folder / CONTEXT_FILE
        if not path.is_file():
            raise InputFileError(path, "not found: not a `jax3dc predict` output folder (or one written before "
                                       "predict kept prediction.json: predict the image again)")
        try:
            doc = json.loads(path.read_text(encoding="utf-8"))
            context = cls(float(doc["scale_m_per_nu"]), bool(doc["mounted"]),
                          {int(pid): str(name) for pid, name in doc["names"].items()}, dict(doc["camera"]),
                          bool(doc["camera_given"]), str(doc["image_sha256"]))
        except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError, AttributeError) as e:
            raise InputFileError(path, f"malformed ({type(e).__name__}: {e})") from None
        if not (math.isfinite(context.scale) and context.scale > 0):
            raise InputFileError(path, f"scale_m_per_nu must be a number > 0, got {context.scale}")
        return context


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


def write_viewer_page(out: Path, title: str, glb: Path, verdict: Verdict | None, image_png: bytes,
                      seg_png: bytes) -> Path:
    """viewer.html (+ viewer_files/): the exported GLB in 3D with joint sliders, the verdict, I and S."""
    return write_viewer(ViewerInputs(glb.read_bytes(), title, str(glb), verdict, image_png, seg_png),
                        out / "viewer.html")


def write_checked(structure: Structure, parts: dict[int, trimesh.Trimesh], context: ObjectContext, out: Path,
                  check: Callable[[Structure], Verdict], wrote: OutputListener,
                  step: Callable[[str], None] = lambda name: None) -> Verdict:
    """structure.json, the exports (with stage 1's part names) and physics.json of ``structure``,
    each announced to ``wrote`` once written; ``check`` gives the verdict (predict's VerdictCache,
    which has judged the candidates and repairs already). ``step("physics")`` is said before the
    check (predict's progress bar). Returns the verdict; raises at the first file that fails."""
    path = out / "structure.json"
    path.write_text(to_json(structure), encoding="utf-8")
    wrote("structure", path)
    named = replace(structure, nodes={pid: replace(n, name=context.names.get(pid, n.name))
                                      for pid, n in structure.nodes.items()})
    for name, path in write_exports(named, parts, out, context.scale, context.mounted).items():
        wrote(name, path)
    step("physics")
    verdict = check(structure)
    wrote("physics", write_physics(verdict, out))
    return verdict


def write_pages(report: ReportInputs, glb: Path | None, image_png: bytes, seg_png: bytes, out: Path, title: str,
                wrote: OutputListener) -> None:
    """report.html and report.png, and viewer.html when there is an exported ``glb`` to show (the
    viewer articulates the exported object); ``title`` names the object on the viewer page."""
    for name, path in write_report(report, out).items():
        wrote(name, path)
    if glb is not None:
        wrote("viewer", write_viewer_page(out, title, glb, report.verdict, image_png, seg_png))
