"""The mirror augmentation: an object reflected left to right (x → −x in the object frame).

Real training objects are few, and a small model learns each one's look and answer by heart; its
mirror image is a new shape with a known answer — a door hinged on the left becomes one hinged on
the right — so the model has to read the hinge side from the image and legend instead of
recalling it. Up (+Z) and front (−Y) stay where the project's frame puts them.

A reflection M = diag(−1, 1, 1) turns a rotation by θ about axis a into a rotation by θ about
−M·a (M R(θ, a) M = R(−θ, M a)), so a hinge keeps its range with its axis reflected and negated; a
slide moves along M·a; pivots are reflected. trimesh reverses the faces of a mirrored mesh, so
normals still point out.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from data_pipeline.samples import SourceObject
from jax3dc.structure import Joint

AUGMENTATION = "mirror"
_M = np.diag([-1.0, 1.0, 1.0])


def _mirrored_joint(j: Joint) -> Joint:
    axis = _M @ np.asarray(j.axis, dtype=np.float64)
    if j.type != "slide":
        axis = -axis
    pivot = _M @ np.asarray(j.pivot, dtype=np.float64)
    return replace(j, axis=tuple(float(v) + 0.0 for v in axis), pivot=tuple(float(v) + 0.0 for v in pivot))


def mirrored(obj: SourceObject) -> SourceObject:
    """``obj`` reflected across its x = 0 plane; its symmetric and instance relations are found
    again from the mirrored parts when its records are made (``object_records``)."""
    transform = np.eye(4)
    transform[:3, :3] = _M
    parts = {}
    for pid, mesh in obj.parts.items():
        parts[pid] = mesh.copy()
        parts[pid].apply_transform(transform)
    nodes = {pid: replace(node, joint=None if node.joint is None else _mirrored_joint(node.joint))
             for pid, node in obj.structure.nodes.items()}
    return replace(obj, structure=replace(obj.structure, nodes=nodes), parts=parts, program=None, parameters=None, augmentation=AUGMENTATION)
