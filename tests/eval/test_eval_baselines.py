"""No-training baselines on a hand-made cabinet with a drawer, and a separate box beside it."""

import math

import pytest

from eval.baselines import heuristic, star
from jax3dc.structure import canonicalize
from jax3dc.structure.schema import Box, Joint, Relation

BOXES = {
    1: Box((0.0, 0.0, 0.0), (0.8, 0.4, 1.0)),  # body: x [-0.4, 0.4], y [-0.2, 0.2], z [-0.5, 0.5]
    2: Box((-0.2, -0.215, 0.2), (0.39, 0.02, 0.5)),  # left door, 0.005 in front of the body
    3: Box((0.2, -0.215, 0.2), (0.39, 0.02, 0.5)),  # right door
    4: Box((0.0, -0.05, -0.3), (0.7, 0.3, 0.3)),  # drawer inside the body, flush with its front
    5: Box((2.0, 0.0, 0.0), (0.3, 0.3, 0.3)),  # a box standing apart: its own object
    6: Box((-0.05, -0.24, 0.2), (0.01, 0.03, 0.2)),  # handle on the left door
    7: Box((0.05, -0.24, 0.2), (0.01, 0.03, 0.2)),  # handle on the right door
}


def test_star_roots_the_largest_part():
    s = star(BOXES, BOXES.keys())
    assert {i: n.parent for i, n in s.nodes.items()} == {1: None, 2: 1, 3: 1, 4: 1, 5: 1, 6: 1, 7: 1}
    assert s.joints() == {} and s.relations == ()
    # ties on volume go to the smallest id
    tie = {1: Box((0, 0, 0), (1, 1, 1)), 2: Box((2, 0, 0), (1, 1, 1))}
    assert star(tie, [2, 1]).roots() == [1]


def test_heuristic_tree_joints_and_relations_hand_worked():
    s = heuristic(BOXES, BOXES.keys())
    # doors touch the body (gap 0.005 in y), the drawer is inside it, handles touch their door
    # (gap 0) and not the body (gap 0.025 > 0.02), box 5 touches nothing larger.
    assert {i: n.parent for i, n in s.nodes.items()} == {1: None, 2: 1, 3: 1, 4: 1, 5: None, 6: 2, 7: 3}
    j = s.joints()
    assert set(j) == {2, 3, 4}
    # left door: edges x = -0.395 / -0.005, body walls -0.4 / 0.4: the left edge is nearer (0.005);
    # pivot on it at the door's back face y = -0.205; opening towards -Y is a negative angle.
    assert j[2].type == "hinge" and j[2].axis == (0.0, 0.0, 1.0)
    assert j[2].pivot == pytest.approx((-0.395, -0.205, 0.2)) and j[2].range == (-math.pi / 2, 0.0)
    assert j[3].pivot == pytest.approx((0.395, -0.205, 0.2)) and j[3].range == (0.0, math.pi / 2)
    # drawer: box-like (0.3 >= 0.25 * 0.7), contained, front at the body's front: slide along -Y
    # by 0.8 * 0.3 = 0.24
    assert j[4] == Joint("slide", (0.0, -1.0, 0.0), (0.0, -0.05, -0.3), (0.0, pytest.approx(0.24)))
    # doors 2 and 3: same extents, centroids mirror across x = 0 (the body's centre): symmetric yz.
    # The handles have different parents, so they are not compared.
    assert s.relations == (Relation("symmetric", 2, 3, "yz"),)


def test_heuristic_output_canonicalises_cleanly():
    c = canonicalize(heuristic(BOXES, BOXES.keys()), BOXES)
    assert c.roots() == [1, 5]
    # the drawer's axis -Y gets a positive largest component, so its range is negated and swapped
    assert c.joints()[4].axis == (0.0, 1.0, 0.0) and c.joints()[4].range == pytest.approx((-0.24, 0.0))


def test_instances_among_siblings_that_do_not_mirror():
    boxes = {1: Box((0, 0, 0), (1, 1, 1)), 2: Box((0.1, 0, 0.3), (0.1, 0.1, 0.1)), 3: Box((0.3, 0.2, 0.3), (0.1, 0.1, 0.1))}
    assert heuristic(boxes, boxes).relations == (Relation("instance", 2, 3),)
