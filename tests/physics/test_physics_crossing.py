"""Thin boards driven through each other (jax3dc.physics.crossing), on hand-built plates."""

from __future__ import annotations

import numpy as np
import trimesh

from jax3dc.physics.crossing import crossings
from jax3dc.structure.schema import Joint, Node, Structure


def _plate(extents, centre) -> trimesh.Trimesh:
    box = trimesh.creation.box(extents=extents)
    box.apply_translation(centre)
    return box


def _box_with_lid(pin: trimesh.Trimesh | None = None):
    """A 0.02-thick base plate (part 1) and a lid plate (part 2) lying on it, hinged on the x axis at
    the base's back edge (y = 0.4); opening is a positive turn about -x."""
    base = _plate([0.8, 0.8, 0.02], [0.0, 0.0, 0.0])
    lid = _plate([0.8, 0.8, 0.02], [0.0, 0.0, 0.03])
    if pin is not None:
        lid = trimesh.util.concatenate([lid, pin])
    nodes = {1: Node(parent=None, material=0),
             2: Node(parent=1, material=0, joint=Joint("hinge", (-1.0, 0.0, 0.0), (0.0, 0.4, 0.02), (0.0, 1.5)))}
    return Structure(materials={}, nodes=nodes), {1: base, 2: lid}


def test_lid_swung_the_wrong_way_passes_through_its_base():
    structure, parts = _box_with_lid()
    # the wrong way, the lid's front edge dives through the base: at most 0.02 deep as a contact
    wrong = -np.linspace(0.0, 1.5, 9)
    hit = crossings(structure, parts, {2: wrong})
    assert 2 in hit and hit[2][0] == 1
    # it crosses once the lid's far edge is more than the margin below the base: sin(q) * 0.8 > 0.05
    assert 0.05 < -hit[2][1] < 0.3
    assert crossings(structure, parts, {2: np.linspace(0.0, 1.5, 9)}) == {}  # opening: never crosses


def test_part_that_crosses_at_rest_is_left_alone():
    # a pin through the base at rest (it turns with the lid): interlocked by design, not a new crossing
    pin = _plate([0.03, 0.03, 0.3], [0.0, 0.37, 0.0])
    structure, parts = _box_with_lid(pin)
    assert crossings(structure, parts, {2: np.linspace(0.0, 0.3, 5)}) == {}
