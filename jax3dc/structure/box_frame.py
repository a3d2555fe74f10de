"""Joint pivots written in the frame of the moving part's own box, and read back.

A model that writes a pivot as absolute numbers must add a legend's centroid and half extent in
digits to say "the hinge is on the door's left edge"; a small model learns the numbers of the
objects it saw instead, and misplaces hinges on new shapes (SPEC §7, "Joints from geometry"). In the
box frame the same hinge is ``-0.5`` whatever the door's size or place: component ``k`` of a pivot
``p`` of the part with box (centroid ``c``, extent ``e``) is written ``(p_k - c_k) / max(e_k, FLOOR)``,
so the box's faces are at ±0.5, its centre line at 0, and the part's edges — where the hinges of
real doors and lids lie — are pairs of ±0.5.

Before writing, the pivot is slid along its own axis to the plane through the box centre: any point
of the axis is the same joint (the metrics and the exports read the line), and the component along
the axis, which carries no information, becomes 0 instead of a number the model would have to learn.

Reading back is ``c_k + f_k * max(e_k, FLOOR)``, so a structure survives the round trip up to the
3-decimal rounding of the written fractions. ``FLOOR`` keeps a thin part (a door's thickness) from
turning a small offset into a large fraction; it is part of the format, written beside the model.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path

from jax3dc.errors import InputFileError
from jax3dc.structure.rewrite import rewrite_json
from jax3dc.structure.schema import Box, Joint, Structure, Vec3
from jax3dc.structure.serialize import to_json
from jax3dc.structure.validate import parse_structure

FRAMES = ("absolute", "box")
FORMAT_FILE = "structure_format.json"
"""Written beside a model's weights: how that model writes pivots (absent: absolute)."""


@dataclass(frozen=True)
class PivotFrame:
    """How a model writes joint pivots: ``absolute`` (SPEC §2 as is) or ``box`` (this module)."""

    name: str = "absolute"
    floor: float = 0.02  # nu: the smallest box side a fraction is measured against (a thin door's faces stay ±0.5)

    def __post_init__(self):
        if self.name not in FRAMES:
            raise ValueError(f"pivot frame must be one of {FRAMES}, got {self.name!r}")
        if not (math.isfinite(self.floor) and self.floor > 0):
            raise ValueError(f"pivot frame floor must be a positive number, got {self.floor!r}")

    def save(self, directory: str | Path) -> None:
        Path(directory, FORMAT_FILE).write_text(json.dumps({"pivot_frame": self.name, "floor": self.floor}) + "\n")

    @classmethod
    def load(cls, directory: str | Path) -> "PivotFrame":
        """The frame a model folder declares; absolute when it declares none (every older model)."""
        path = Path(directory, FORMAT_FILE)
        if not path.is_file():
            return cls()
        try:
            doc = json.loads(path.read_text())
            return cls(str(doc["pivot_frame"]), float(doc.get("floor", cls.floor)))
        except (OSError, ValueError, KeyError, TypeError) as e:
            raise InputFileError(path, f"not a valid structure format file: {e}") from None


def _sides(box: Box, floor: float) -> Vec3:
    return tuple(max(float(e), floor) for e in box.extent)  # type: ignore[return-value]


def pivot_to_box(pivot: Vec3, axis: Vec3, box: Box, floor: float) -> Vec3:
    """The pivot slid along ``axis`` to the box centre's plane, as fractions of the box sides."""
    c = box.centroid
    norm = math.sqrt(sum(a * a for a in axis)) or 1.0
    a = [x / norm for x in axis]
    along = sum((p - ci) * ai for p, ci, ai in zip(pivot, c, a))
    on_plane = [p - along * ai for p, ai in zip(pivot, a)]
    return tuple((p - ci) / s for p, ci, s in zip(on_plane, c, _sides(box, floor)))  # type: ignore[return-value]


def pivot_from_box(fractions: Vec3, box: Box, floor: float) -> Vec3:
    """Absolute pivot (nu) of fractions of the box sides."""
    return tuple(ci + f * s for f, ci, s in zip(fractions, box.centroid, _sides(box, floor)))  # type: ignore[return-value]


def _map_joints(structure: Structure, boxes: Mapping[int, Box], move) -> Structure:
    nodes = {}
    for pid, node in structure.nodes.items():
        j = node.joint
        if j is not None and pid in boxes:
            node = replace(node, joint=Joint(j.type, j.axis, move(j, boxes[pid]), j.range))
        nodes[pid] = node
    return replace(structure, nodes=nodes)


def to_box_frame(structure: Structure, boxes: Mapping[int, Box], frame: PivotFrame) -> Structure:
    """``structure`` with every joint's pivot written in its part's box frame (for a training target)."""
    if frame.name == "absolute":
        return structure
    return _map_joints(structure, boxes, lambda j, box: pivot_to_box(j.pivot, j.axis, box, frame.floor))


def target_in_frame(target: str, boxes: Mapping[int, Box], frame: PivotFrame) -> str:
    """A canonical SPEC §2 target as the model of ``frame`` is taught to write it."""
    if frame.name == "absolute":
        return target
    return to_json(to_box_frame(parse_structure(target), boxes, frame))


def text_to_absolute(text: str, boxes: Mapping[int, Box], frame: PivotFrame) -> str:
    """A generated document with box-frame pivots rewritten as SPEC §2 absolute pivots.

    Works on the JSON as written, before validation, so that what the validator and the metrics
    judge is the model's own document: a text that is not JSON, or a pivot that is not three
    numbers of a part with a box, is left as it is (and fails validation there, as it should).
    """
    if frame.name == "absolute":
        return text

    def absolute(doc: object) -> object | None:
        nodes = doc.get("nodes") if isinstance(doc, dict) else None
        if not isinstance(nodes, dict):
            return None
        changed = False
        for key, node in nodes.items():
            joint = node.get("joint") if isinstance(node, dict) else None
            pivot = joint.get("pivot") if isinstance(joint, dict) else None
            box = boxes.get(int(key)) if isinstance(key, str) and key.isdigit() else None
            if box is None or not (isinstance(pivot, list) and len(pivot) == 3
                                   and all(isinstance(v, int | float) and not isinstance(v, bool) for v in pivot)):
                continue
            joint["pivot"] = [round(v, 4) + 0.0 for v in pivot_from_box(tuple(pivot), box, frame.floor)]
            changed = True
        return doc if changed else None

    return rewrite_json(text, absolute)
