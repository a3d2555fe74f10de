"""The structure O of SPEC §2 as typed, immutable values.

Parsing, validation and canonicalisation live beside this module; these types only hold data.
"""

from __future__ import annotations

from dataclasses import dataclass, field

FAMILIES: tuple[str, ...] = (
    "Wood", "Metal", "Plastic", "Glass", "Fabric", "Leather", "Ceramic", "Stone", "Rubber", "Other",
)
JOINT_TYPES: tuple[str, ...] = ("hinge", "slide")
RELATION_TYPES: tuple[str, ...] = ("symmetric", "instance", "support")
PLANES: tuple[str, ...] = ("xy", "yz", "xz")

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class Material:
    family: str
    desc: str = ""


@dataclass(frozen=True)
class Joint:
    """A hinge or slide joint between a node and its parent, in the normalised frame (nu)."""

    type: str
    axis: Vec3
    pivot: Vec3
    range: tuple[float, float]


@dataclass(frozen=True)
class Node:
    parent: int | None
    material: int
    joint: Joint | None = None
    name: str | None = None  # semantic part name; metadata, not in the default target


@dataclass(frozen=True)
class Relation:
    type: str
    a: int
    b: int
    plane: str | None = None  # only for "symmetric"


@dataclass(frozen=True)
class Box:
    """Axis-aligned bounding box of one part in the normalised frame."""

    centroid: Vec3
    extent: Vec3

    @property
    def volume(self) -> float:
        return float(self.extent[0] * self.extent[1] * self.extent[2])


@dataclass(frozen=True)
class Structure:
    """Materials, nodes (part id -> Node) and relations of one object or scene."""

    materials: dict[int, Material]
    nodes: dict[int, Node]
    relations: tuple[Relation, ...] = field(default_factory=tuple)

    @property
    def part_ids(self) -> list[int]:
        return sorted(self.nodes)

    def roots(self) -> list[int]:
        return sorted(i for i, n in self.nodes.items() if n.parent is None)

    def children(self, part_id: int) -> list[int]:
        return sorted(i for i, n in self.nodes.items() if n.parent == part_id)

    def subtree(self, part_id: int) -> set[int]:
        """The part and all its descendants: what moves when its joint moves."""
        out, stack = {part_id}, [part_id]
        while stack:
            for child in self.children(stack.pop()):
                out.add(child)
                stack.append(child)
        return out

    def joints(self) -> dict[int, Joint]:
        """Child part id -> its joint, for every articulated node."""
        return {i: n.joint for i, n in sorted(self.nodes.items()) if n.joint is not None}
