"""Small builders of canonical-looking Structures for the eval tests (imported by test files)."""

from __future__ import annotations

from jax3dc.structure.schema import Joint, Material, Node, Relation, Structure


def hinge(axis=(0.0, 0.0, 1.0), pivot=(0.0, 0.0, 0.0), rng=(0.0, 1.5)) -> Joint:
    return Joint("hinge", tuple(axis), tuple(pivot), tuple(rng))


def slide(axis=(0.0, 1.0, 0.0), pivot=(0.0, 0.0, 0.0), rng=(0.0, 0.4)) -> Joint:
    return Joint("slide", tuple(axis), tuple(pivot), tuple(rng))


def structure(parents: dict[int, int | None], joints: dict[int, Joint] | None = None,
              relations: tuple[Relation, ...] = ()) -> Structure:
    """Nodes from a part id -> parent map, with joints on some children; one material."""
    joints = joints or {}
    nodes = {i: Node(p, 0, joints.get(i)) for i, p in sorted(parents.items())}
    return Structure({0: Material("Wood")}, nodes, tuple(relations))
