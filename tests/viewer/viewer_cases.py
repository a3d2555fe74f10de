"""A small cabinet for the viewer tests: a body, two mirrored hinged doors (a symmetric pair), a
drawer on a slide carrying a handle, and a part name that would be markup if a page pasted it."""

from __future__ import annotations

import io

import numpy as np
import trimesh
from PIL import Image

from jax3dc.physics.findings import WARNING as WARNS, Finding, Verdict
from jax3dc.structure.schema import Joint, Material, Node, Relation, Structure

MARKUP_NAME = '<img src=x onerror="window.injected=1">door'
HINGE, SLIDE, FLAGGED = 3, 4, 2  # the right door, the drawer, the left door
MOVES_WITH = {HINGE: [3], SLIDE: [4, 5]}  # what each joint carries
REASON = "penetrates part 1 at q=-1.571"
WARNING = "limit past contact: hi (stops at q=1.420)"  # a ground-truth style warning on the hinge


def box(extents, centre) -> trimesh.Trimesh:
    mesh = trimesh.creation.box(extents=extents)
    mesh.apply_translation(centre)
    return mesh


def cabinet() -> tuple[Structure, dict[int, trimesh.Trimesh]]:
    parts = {
        1: box([0.6, 0.5, 1.0], [0, 0, 0]),
        2: box([0.28, 0.03, 0.55], [-0.145, -0.265, 0.15]),
        3: box([0.28, 0.03, 0.55], [0.145, -0.265, 0.15]),
        4: box([0.56, 0.45, 0.25], [0, -0.03, -0.32]),
        5: box([0.2, 0.06, 0.04], [0, -0.28, -0.32]),
    }
    nodes = {
        1: Node(None, 0),
        2: Node(1, 0, Joint("hinge", (0.0, 0.0, 1.0), (-0.285, -0.265, 0.15), (-1.571, 0.0)), name=MARKUP_NAME),
        3: Node(1, 0, Joint("hinge", (0.0, 0.0, 1.0), (0.285, -0.265, 0.15), (0.0, 1.571)), name="right door"),
        4: Node(1, 1, Joint("slide", (0.0, -1.0, 0.0), (0.0, 0.0, -0.32), (0.0, 0.4)), name="drawer"),
        5: Node(4, 2, name="handle"),
    }
    materials = {0: Material("Wood", "light oak"), 1: Material("Plastic", "red"), 2: Material("Metal", "steel")}
    return Structure(materials, nodes, (Relation("symmetric", 2, 3, "yz"),)), parts


def verdict() -> Verdict:
    """A verdict that flags the left door (REASON) and warns on the right one (WARNING)."""
    return Verdict((FLAGGED, HINGE, SLIDE), (
        Finding("penetration", joints=(FLAGGED,), parts=(1,), depth=0.05, state=((FLAGGED, -1.571),)),
        Finding("limit", WARNS, joints=(HINGE,), reachable=1.42, limit="hi")))


def png(colour: tuple[int, int, int], size: int = 48) -> bytes:
    """A plain PNG standing in for I or S (half of it ``colour``, so it is not blank)."""
    pixels = np.full((size, size, 3), 255, np.uint8)
    pixels[size // 4: 3 * size // 4, size // 4: 3 * size // 4] = colour
    buf = io.BytesIO()
    Image.fromarray(pixels).save(buf, format="PNG")
    return buf.getvalue()
