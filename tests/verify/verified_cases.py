"""What the select and repair tests do to a record: its checked object and broken copies of its target."""

from __future__ import annotations

from dataclasses import dataclass, replace

import trimesh

from data_pipeline.record import Record
from data_pipeline.record_parts import record_parts
from jax3dc.verify.select import parse_candidate
from jax3dc.structure import Box, Structure, boxes_from_dict
from jax3dc.verify.verdicts import Physics, VerdictCache

IMPORTED = ("door_8877", "microwave_7119")  # PartNet-Mobility fixtures: a mounted door, a free-standing microwave


@dataclass(frozen=True)
class CheckedObject:
    target: Structure  # canonical
    parts: dict[int, trimesh.Trimesh]
    scale: float
    mounted: bool
    boxes: dict[int, Box]

    def check(self) -> VerdictCache:
        """A fresh verdict cache of these parts (C MuJoCo, with the dynamics), as predict makes one."""
        return VerdictCache(Physics(self.parts, self.scale, self.mounted))


def checked_object(record: Record) -> CheckedObject:
    parts, scale, mounted = record_parts(record)
    boxes = boxes_from_dict(record.meta["boxes"])
    return CheckedObject(parse_candidate(record.target, boxes.keys(), boxes), parts, scale, mounted, boxes)


def with_joint(structure: Structure, part: int, **changes) -> Structure:
    """``structure`` with fields of the joint of ``part`` replaced."""
    nodes = dict(structure.nodes)
    nodes[part] = replace(nodes[part], joint=replace(nodes[part].joint, **changes))
    return replace(structure, nodes=nodes)


def pivot_moved_away(structure: Structure, part: int) -> Structure:
    """The hinge of ``part`` turned about a line 0.3 nu off its pivot across the axis (detached)."""
    joint = structure.nodes[part].joint
    offset = (0.0, -0.3, 0.3) if abs(joint.axis[0]) > 0.5 else (0.3, -0.3, 0.0)
    return with_joint(structure, part, pivot=tuple(p + d for p, d in zip(joint.pivot, offset)))


def flipped(structure: Structure, part: int) -> Structure:
    """The joint of ``part`` turning the other way (range mirrored: the axis flipped)."""
    lo, hi = structure.nodes[part].joint.range
    return with_joint(structure, part, range=(-hi, -lo))
