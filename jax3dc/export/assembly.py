"""What every exporter needs from a structure and its part meshes: the kinematic tree in a fixed
order, one frame per part, safe names and per-part material properties.

Frames: every part gets a frame with the object's axes (the structure is in its rest pose, so no
rotations are needed). A jointed part's frame sits at its joint pivot, so the joint is at the
frame origin in every format; a rigid part shares its parent's frame; a root's frame is the object
origin. Each part's mesh is re-expressed in its own frame and in metres (nu × scale).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
import trimesh

from jax3dc.errors import StructureError
from jax3dc.geometry.mass import MassProperties, mass_properties
from jax3dc.materials import MATERIALS, MaterialProps
from jax3dc.structure.schema import Joint, Structure

MIN_THICKNESS_M = 1e-3  # flat or degenerate parts become boxes at least this thick (metres)


@dataclass(frozen=True)
class ExportPart:
    """One part ready to be written: everything in metres, in the part's own frame."""

    part_id: int
    label: str  # identifier-safe name: part_<id>[_<slug of the semantic name>]
    name: str | None  # the raw semantic name (data: must be escaped wherever it is written)
    parent: int | None
    joint: Joint | None  # as in the structure: axis in the object frame (= the part frame's axes), nu
    range_si: tuple[float, float] | None  # joint range in radians (hinge) or metres (slide)
    material_id: int
    family: str
    props: MaterialProps
    frame_nu: np.ndarray  # [3] frame origin in the object frame, nu
    offset_m: np.ndarray  # [3] frame origin relative to the parent's frame (object frame for roots), m
    mesh: trimesh.Trimesh  # in the part frame, metres
    solid: str  # "mesh", "convex hull" or "box": what stands for the part in mass and collision
    mass: MassProperties

    def box_fallback(self) -> tuple[np.ndarray, np.ndarray]:
        """Centre and full size (metres, part frame) of the box that replaces a flat mesh."""
        lo, hi = np.asarray(self.mesh.bounds, dtype=np.float64)
        return (lo + hi) / 2, np.maximum(hi - lo, MIN_THICKNESS_M)


def label_of(part_id: int, name: str | None) -> str:
    """``part_<id>``, plus the semantic name reduced to [A-Za-z0-9_] (at most 40 characters)."""
    slug = re.sub(r"[^A-Za-z0-9]+", "_", name or "").strip("_")[:40].rstrip("_")
    return f"part_{part_id}_{slug}" if slug else f"part_{part_id}"


MAX_NESTED_BODIES = 400
"""Deepest parent chain that nested-body formats (MJCF, the physics model) take: MuJoCo's XML
reader stops at about 500 nested elements, and a chain this deep is no household object."""


def check_nesting(structure: Structure) -> None:
    """Refuse, by one clear error, a tree whose parent chain MuJoCo could not read as nested bodies."""
    depth: dict[int, int] = {}
    for part_id in tree_order(structure):
        parent = structure.nodes[part_id].parent
        depth[part_id] = 1 if parent is None else depth[parent] + 1
        if depth[part_id] > MAX_NESTED_BODIES:
            raise StructureError("tree_depth", f"node {part_id}",
                                 f"the parent chain is more than {MAX_NESTED_BODIES} parts deep; MJCF nests one body "
                                 f"per part and MuJoCo reads at most about 500 nested elements")


def tree_order(structure: Structure) -> list[int]:
    """Parts parent-first: each tree depth-first from its root, roots and children by id."""
    order: list[int] = []
    stack = list(reversed(structure.roots()))
    while stack:
        part_id = stack.pop()
        order.append(part_id)
        stack.extend(reversed(structure.children(part_id)))
    if len(order) != len(structure.nodes):  # parse_structure rejects cycles; guard direct callers
        raise StructureError("cycle", "nodes", "the parent map has a cycle: nothing to export")
    return order


def objects(structure: Structure) -> dict[int, list[int]]:
    """Each object's parts in tree order, keyed by its root (SPEC §2: one tree per object; a scene
    has several roots and its scene root is implicit, so each exporter writes one of its own)."""
    out: dict[int, list[int]] = {}
    root_of: dict[int, int] = {}
    for part_id in tree_order(structure):
        parent = structure.nodes[part_id].parent
        root_of[part_id] = part_id if parent is None else root_of[parent]
        out.setdefault(root_of[part_id], []).append(part_id)
    return out


def object_label(root: int) -> str:
    """Name of the node, prim, link or collection that holds one object of a scene."""
    return f"object_{root}"


def frames_nu(structure: Structure, order: list[int]) -> dict[int, np.ndarray]:
    """Frame origin of each part in the object frame (see the module docstring)."""
    frames: dict[int, np.ndarray] = {}
    for part_id in order:
        node = structure.nodes[part_id]
        if node.joint is not None:
            frames[part_id] = np.asarray(node.joint.pivot, dtype=np.float64)
        elif node.parent is not None:
            frames[part_id] = frames[node.parent]
        else:
            frames[part_id] = np.zeros(3)
    return frames


def assemble(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float) -> list[ExportPart]:
    """The parts of ``structure`` in tree order, with frames, local meshes and mass properties.

    Raises StructureError when node ids and mesh ids differ, and ValueError on a scale that is
    not a positive finite number.
    """
    if not (np.isfinite(scale) and scale > 0):
        raise ValueError(f"scale must be a positive number of metres per nu, got {scale!r}")
    missing = sorted(set(structure.nodes) - set(parts))
    extra = sorted(set(parts) - set(structure.nodes))
    if missing or extra:
        detail = "; ".join(s for s in (f"no mesh for parts {missing}" if missing else "",
                                       f"meshes without a node: {extra}" if extra else "") if s)
        raise StructureError("part_ids", "nodes", f"node ids must be exactly the part ids: {detail}")
    order = tree_order(structure)
    frames = frames_nu(structure, order)
    out = []
    for part_id in order:
        node = structure.nodes[part_id]
        material = structure.materials[node.material]
        props = MATERIALS[material.family]
        frame = frames[part_id]
        parent_frame = frames[node.parent] if node.parent is not None else np.zeros(3)
        vertices = (np.asarray(parts[part_id].vertices, dtype=np.float64) - frame) * scale
        mesh = trimesh.Trimesh(vertices, np.asarray(parts[part_id].faces, dtype=np.int64), process=False)
        mass = mass_properties(mesh, props.density_kg_m3, 1.0, MIN_THICKNESS_M)
        joint = node.joint
        rng = None
        if joint is not None:
            factor = 1.0 if joint.type == "hinge" else scale
            rng = (float(joint.range[0]) * factor, float(joint.range[1]) * factor)
        out.append(ExportPart(
            part_id=part_id, label=label_of(part_id, node.name), name=node.name, parent=node.parent,
            joint=joint, range_si=rng, material_id=node.material, family=material.family, props=props,
            frame_nu=frame, offset_m=(frame - parent_frame) * scale, mesh=mesh, solid=mass.solid, mass=mass,
        ))
    return out


def unit_axis(joint: Joint) -> np.ndarray:
    axis = np.asarray(joint.axis, dtype=np.float64)
    return axis / np.linalg.norm(axis)


def num(x: float) -> str:
    """A number as text, the same for the same float: 9 significant digits, no negative zero."""
    return "%.9g" % (float(x) + 0.0)


def vec(values) -> str:
    return " ".join(num(v) for v in values)
