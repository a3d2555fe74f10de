"""Format-neutral kinematic tree of an imported object, and its reduction to parts.

Readers (URDF, MJCF) resolve every frame of their format and hand over a tree of *links* whose
geometry and joint motions are already expressed in one object frame, at the rest pose, in the
source's length units. :func:`reduce_to_parts` then decides which links become parts (those with
geometry) and which single joint, if any, moves each part relative to its parent part.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import trimesh

from jax3dc.errors import InputFileError


@dataclass(frozen=True)
class Motion:
    """One degree of freedom of a source joint, in the object frame at the rest pose.

    ``range`` is measured from the rest pose: radians for hinges, source length units for slides.
    """

    kind: str  # "hinge" | "slide"
    axis: np.ndarray  # unit 3-vector
    pivot: np.ndarray  # a point on the axis
    range: tuple[float, float]
    joint: str  # source joint name

    def reversed(self) -> "Motion":
        """The same motion seen from the other body: the parent moves by -q relative to the child."""
        return Motion(self.kind, self.axis, self.pivot, (-self.range[1], -self.range[0]), self.joint)


@dataclass(frozen=True)
class Link:
    """A rigid body of the source. ``mesh`` is None for links without geometry (frames, helpers)."""

    name: str
    mesh: trimesh.Trimesh | None
    label: str | None = None  # semantic part name, where the source gives one
    shape_names: tuple[str, ...] = ()  # names of its visuals / geoms
    material_names: tuple[str, ...] = ()  # names of the materials its visuals / geoms use


@dataclass(frozen=True)
class Edge:
    """A source joint between two links; ``motions`` is empty for rigid attachments."""

    parent: str
    child: str
    joint: str
    source_type: str
    motions: tuple[Motion, ...] = ()


@dataclass
class KinematicTree:
    source: Path
    format: str  # "urdf" | "mjcf"
    root: str
    links: dict[str, Link]  # in document order
    edges: list[Edge]
    warnings: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class PartAttachment:
    """How a part hangs on its parent part: the motion kept, and the source joints on the path."""

    parent: str | None
    motion: Motion | None
    path_joints: tuple[str, ...]


def _first_geometry_link(tree: KinematicTree, adjacency: dict, fixed_only: bool) -> str | None:
    """Breadth-first from the source root, in document order, to the nearest link with geometry."""
    seen = {tree.root}
    queue = deque([tree.root])
    while queue:
        name = queue.popleft()
        if tree.links[name].mesh is not None:
            return name
        for other, edge in adjacency[name]:
            if other not in seen and (edge.motions == () or not fixed_only):
                seen.add(other)
                queue.append(other)
    return None


def reduce_to_parts(tree: KinematicTree) -> tuple[list[str], dict[str, PartAttachment], list[str]]:
    """Parts (links with geometry, in document order) and the attachment of each to its parent part.

    The tree is re-rooted at the part rigidly attached to the source root (the object body; if
    the body itself moves against a geometry-less world, the first part reached from the root).
    Links without geometry are folded away: a part's parent is its nearest ancestor with
    geometry, and the motions of every joint on the path between them (reversed where the path
    runs against the source direction) are collected. A path with one motion gives that joint;
    with several (PartNet-Mobility ``_helper`` links of screws, MJCF bodies with several joints)
    the first hinge is kept, else the first slide, and the rest are reported. Joints that connect
    only geometry-less links (e.g. the object sliding against the world) move no part relative to
    another and are dropped with a warning.
    """
    adjacency: dict[str, list[tuple[str, Edge]]] = {name: [] for name in tree.links}
    for edge in tree.edges:
        adjacency[edge.parent].append((edge.child, edge))
        adjacency[edge.child].append((edge.parent, edge))
    root = _first_geometry_link(tree, adjacency, fixed_only=True) or _first_geometry_link(
        tree, adjacency, fixed_only=False
    )
    if root is None:
        raise InputFileError(tree.source, "no link has any geometry")

    # Breadth-first from the new root: each link's step towards the root, as (link, motions seen
    # from the side of the root).
    up: dict[str, tuple[str, Edge, tuple[Motion, ...]]] = {}
    seen = {root}
    queue = deque([root])
    while queue:
        name = queue.popleft()
        for other, edge in adjacency[name]:
            if other in seen:
                continue
            seen.add(other)
            forward = edge.parent == name
            motions = edge.motions if forward else tuple(m.reversed() for m in edge.motions)
            up[other] = (name, edge, motions)
            queue.append(other)

    warnings: list[str] = []
    parts = [name for name, link in tree.links.items() if link.mesh is not None]
    attachments: dict[str, PartAttachment] = {root: PartAttachment(None, None, ())}
    used_edges: set[int] = set()
    for part in parts:
        if part == root:
            continue
        path: list[Edge] = []
        motions: list[Motion] = []
        node = part
        while True:
            above, edge, edge_motions = up[node]
            path.append(edge)
            motions[:0] = edge_motions
            node = above
            if tree.links[node].mesh is not None:
                break
        used_edges.update(id(e) for e in path)
        kept = next((m for m in motions if m.kind == "hinge"), motions[0] if motions else None)
        if len(motions) > 1:
            dropped = ", ".join(f"{m.joint} ({m.kind})" for m in motions if m is not kept)
            warnings.append(
                f"part {part!r} moves through several joints; kept {kept.joint} ({kept.kind}), "
                f"dropped {dropped}"
            )
        attachments[part] = PartAttachment(node, kept, tuple(e.joint for e in reversed(path)))
    for edge in tree.edges:
        if edge.motions and id(edge) not in used_edges:
            warnings.append(
                f"joint {edge.joint!r} ({edge.source_type}) moves no part relative to another "
                f"(only links without geometry on one side, e.g. the world); dropped"
            )
    return parts, attachments, warnings
