"""Hand-built structures with box parts for the exporter tests (normalised frame, nu)."""

from __future__ import annotations

import math

import numpy as np
import trimesh

from jax3dc.structure.schema import Joint, Material, Node, Relation, Structure

EVIL_NAME = 'a"); import os #</name>'
SLANT = (0.6, 0.0, 0.8)  # a unit axis along no coordinate direction


def box(extents, centre) -> trimesh.Trimesh:
    mesh = trimesh.creation.box(extents=extents)
    mesh.apply_translation(centre)
    return mesh


def mirrored(mesh: trimesh.Trimesh, axis: int) -> trimesh.Trimesh:
    """``mesh`` reflected across the plane through the origin normal to ``axis`` (winding kept outward)."""
    flip = np.ones(3)
    flip[axis] = -1
    return trimesh.Trimesh(np.asarray(mesh.vertices) * flip, np.asarray(mesh.faces)[:, ::-1], process=False)


def cabinet() -> tuple[Structure, dict[int, trimesh.Trimesh]]:
    """Body, two mirrored hinged doors, a drawer, a handle on the drawer and a flat label sticker."""
    left = box([0.3, 0.02, 0.6], [-0.15, -0.26, 0.1])
    parts = {
        1: box([0.6, 0.5, 1.0], [0, 0, 0]),
        2: left,
        3: mirrored(left, 0),
        4: box([0.56, 0.45, 0.2], [0, 0, -0.35]),
        5: box([0.1, 0.03, 0.02], [0, -0.25, -0.35]),
        6: trimesh.Trimesh([[-0.05, -0.251, 0.45], [0.05, -0.251, 0.45], [-0.05, -0.251, 0.48], [0.05, -0.251, 0.48]],
                           [[0, 1, 2], [1, 3, 2]], process=False),
    }
    nodes = {
        1: Node(None, 0),
        2: Node(1, 0, Joint("hinge", (0.0, 0.0, 1.0), (-0.3, -0.25, 0.1), (-1.571, 0.0)), name=EVIL_NAME),
        3: Node(1, 0, Joint("hinge", (0.0, 0.0, 1.0), (0.3, -0.25, 0.1), (0.0, 1.571)), name="right door"),
        4: Node(1, 0, Joint("slide", (0.0, -1.0, 0.0), (0.0, 0.0, -0.35), (0.0, 0.4))),
        5: Node(4, 1),
        6: Node(1, 2),
    }
    materials = {0: Material("Wood", "oak"), 1: Material("Metal", 'brushed "steel"'), 2: Material("Plastic")}
    relations = (Relation("symmetric", 2, 3, "yz"),)
    return Structure(materials, nodes, relations), parts


def two_roots() -> tuple[Structure, dict[int, trimesh.Trimesh]]:
    """A table (root 1) with a box (root 3) standing on it; the box has a lid; two equal legs."""
    parts = {
        1: box([1.0, 0.6, 0.05], [0, 0, 0.2]),
        2: box([0.05, 0.05, 0.4], [-0.4, 0, -0.025]),
        3: box([0.2, 0.2, 0.15], [0.2, 0, 0.3]),
        4: box([0.2, 0.2, 0.02], [0.2, 0, 0.385]),
        5: box([0.05, 0.05, 0.4], [0.4, 0, -0.025]),
    }
    nodes = {
        1: Node(None, 0),
        2: Node(1, 0),
        3: Node(None, 1),
        4: Node(3, 1, Joint("hinge", (1.0, 0.0, 0.0), (0.2, 0.1, 0.375), (0.0, 2.0))),
        5: Node(1, 0),
    }
    relations = (Relation("instance", 2, 5), Relation("support", 3, 1))
    return Structure({0: Material("Wood"), 1: Material("Plastic")}, nodes, relations), parts


def chain() -> tuple[Structure, dict[int, trimesh.Trimesh]]:
    """1 -> 2 (hinge z) -> 3 (slide x) -> 4 (hinge on a slanted axis) -> 5 (rigid)."""
    parts = {
        1: box([0.4, 0.4, 0.2], [0, 0, -0.4]),
        2: box([0.1, 0.1, 0.4], [0, 0, -0.1]),
        3: box([0.3, 0.06, 0.06], [0.1, 0, 0.1]),
        4: box([0.1, 0.1, 0.1], [0.3, 0, 0.2]),
        5: box([0.02, 0.02, 0.2], [0.3, 0, 0.35]),
    }
    nodes = {
        1: Node(None, 0),
        2: Node(1, 1, Joint("hinge", (0.0, 0.0, 1.0), (0.0, 0.0, -0.3), (-math.pi, math.pi))),
        3: Node(2, 1, Joint("slide", (1.0, 0.0, 0.0), (0.0, 0.0, 0.1), (-0.05, 0.1))),
        4: Node(3, 2, Joint("hinge", SLANT, (0.25, 0.0, 0.15), (-0.5, 0.7))),
        5: Node(4, 2),
    }
    return Structure({0: Material("Stone"), 1: Material("Metal"), 2: Material("Rubber")}, nodes), parts


CASES = {"cabinet": cabinet, "two_roots": two_roots, "chain": chain}
