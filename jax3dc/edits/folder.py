"""An edit applied to a `jax3dc predict` output folder (SPEC §9): the structure changes, the physics
check runs again, and every file made from the structure is rewritten, so the files on disk always
agree with the verdict.

The files are rewritten by predict's own writers (``jax3dc.predict.outputs.write_checked`` and
``write_pages``) from what prediction.json keeps, into a stage that replaces them only when all
are written (``jax3dc.edits.staging``): structure.json, object.glb / .urdf / .xml / .usda,
object_blender.py, meshes/, physics.json, report.html / .png, viewer.html (+ viewer_files/) and
edits.jsonl, the history, one line per edit: the patch, the structure it replaced (so any edit
can be undone) and whether the physics check passes after it. What the prediction read and
decided (image.png, seg.png, parts/, prompt.txt, candidates.json, ...) stays as predict left it.
"""

from __future__ import annotations

import io
import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import trimesh
from PIL import Image

from jax3dc.edits.lines import AXES, LETTERS, axis_name, box_direction, hinge_lines, line_at
from jax3dc.edits.patch import Patch, edit_structure
from jax3dc.edits.staging import folder_lock, staged
from jax3dc.errors import InputFileError
from jax3dc.geometry.parts import load_parts, part_boxes
from jax3dc.physics.findings import Verdict
from jax3dc.predict.outputs import ObjectContext, OutputListener, write_checked, write_pages
from jax3dc.predict.report import ReportInputs
from jax3dc.render import png_array
from jax3dc.structure import Structure, parse_structure, to_dict
from jax3dc.verify.verdicts import Physics

EDITS_FILE = "edits.jsonl"
STRUCTURE_FILE = "structure.json"


@dataclass(frozen=True)
class PredictedObject:
    """What an edit reads from a predict folder."""

    folder: Path
    structure: Structure
    parts: dict[int, trimesh.Trimesh]
    context: ObjectContext


@dataclass(frozen=True)
class EditResult:
    """An applied edit: the patch as read, the structure and verdict now on disk, and the files
    rewritten (name -> path, as predict names them)."""

    patch: Patch
    structure: Structure
    verdict: Verdict
    files: dict[str, Path]


def _read(path: Path) -> bytes:
    try:
        return path.read_bytes()
    except OSError as e:
        raise InputFileError(path, f"cannot read: {e.strerror or e}") from None


def load_object(folder: str | Path) -> PredictedObject:
    """The structure, parts and context of a predict folder; an InputFileError names what is
    missing (a prediction whose structure model failed has no structure.json to edit)."""
    folder = Path(folder)
    if not folder.is_dir():
        raise InputFileError(folder, "not found: expected a `jax3dc predict` output folder")
    context = ObjectContext.read(folder)
    parts = load_parts(folder / "parts")
    path = folder / STRUCTURE_FILE
    if not path.is_file():
        raise InputFileError(path, "not found: the prediction has no structure to edit (see report.html for why)")
    return PredictedObject(folder, parse_structure(_read(path), part_ids=parts), parts, context)


@dataclass(frozen=True)
class JointRow:
    """One part's joint as a person edits it (`jax3dc edit DIR` prints these; `jax3dc serve`'s
    form shows them): ``type`` is hinge, slide, fixed (to its parent) or root; ``axis_name`` and
    ``line`` name the axis and the hinge line when they are named ones (``jax3dc.edits.lines``),
    and ``lines`` lists the named lines of the part's box along each box direction (x, y, z)."""

    part: int
    name: str | None
    parent: int | None
    type: str
    axis: tuple[float, float, float] | None
    axis_name: str | None
    pivot: tuple[float, float, float] | None
    line: str | None
    range: tuple[float, float] | None
    lines: dict[str, list[str]]

    def lines_along_axis(self) -> list[str]:
        """The named lines along the joint's axis (none for a free axis or no joint)."""
        k = box_direction(self.axis) if self.axis is not None else None
        return [] if k is None else self.lines[LETTERS[k]]


def joint_rows(obj: PredictedObject) -> list[JointRow]:
    """Every part's ``JointRow``, by part id."""
    boxes = part_boxes(obj.parts)
    rows = []
    for pid, node in sorted(obj.structure.nodes.items()):
        lines = {letter: list(hinge_lines(boxes[pid], AXES["+" + letter])) for letter in LETTERS}
        joint = node.joint
        kind = "root" if node.parent is None else ("fixed" if joint is None else joint.type)
        rows.append(JointRow(
            pid, obj.context.names.get(pid), node.parent, kind,
            None if joint is None else tuple(joint.axis), None if joint is None else axis_name(joint.axis),
            None if joint is None else tuple(joint.pivot),
            None if joint is None else line_at(boxes[pid], joint.axis, joint.pivot),
            None if joint is None else tuple(joint.range), lines))
    return rows


def _write_files(obj: PredictedObject, structure: Structure, entry: dict, out: Path, wrote: OutputListener) -> Verdict:
    """Every file of the edited object into ``out`` through predict's writers, and the history
    with ``entry`` appended, told whether the check passes."""
    folder, context = obj.folder, obj.context
    check = Physics(obj.parts, context.scale, context.mounted).verdict
    verdict = write_checked(structure, obj.parts, context, out, check, wrote)
    image_png, seg_png = _read(folder / "image.png"), _read(folder / "seg.png")
    report = ReportInputs(Image.open(io.BytesIO(image_png)).convert("RGB"), png_array(seg_png), context.palette(),
                          context.names, part_boxes(obj.parts), context.camera, context.camera_given, structure,
                          verdict, None)
    write_pages(report, out / "object.glb", image_png, seg_png, out, folder.resolve().name, wrote)
    history = folder / EDITS_FILE
    line = json.dumps({**entry, "physics_ok": verdict.ok}, separators=(",", ":")) + "\n"
    (out / EDITS_FILE).write_bytes((_read(history) if history.is_file() else b"") + line.encode("utf-8"))
    wrote("edits", out / EDITS_FILE)
    return verdict


def edit_folder(folder: str | Path, patch: str | bytes | Mapping,
                on_output: OutputListener | None = None) -> EditResult:
    """Applies ``patch`` (JSON text or data, ``jax3dc.edits.patch``) to the predict folder and
    rewrites its files (module docstring). A bad patch raises an EditError, a file the edit cannot
    write another error, and the folder is then as it was; another edit of the folder at the same
    time raises FolderBusyError. ``on_output`` is told each rewritten file's final path."""
    folder = Path(folder)
    if not folder.is_dir():
        raise InputFileError(folder, "not found: expected a `jax3dc predict` output folder")
    with folder_lock(folder):
        obj = load_object(folder)
        structure, read = edit_structure(obj.structure, patch, part_boxes(obj.parts))
        entry = {"patch": read.to_dict(), "before": to_dict(obj.structure)}
        written: dict[str, Path] = {}
        with staged(folder) as stage:
            verdict = _write_files(obj, structure, entry, stage,
                                   lambda name, path: written.update({name: folder / path.relative_to(stage)}))
    if on_output is not None:
        for name, path in written.items():
            on_output(name, path)
    return EditResult(read, structure, verdict, written)
