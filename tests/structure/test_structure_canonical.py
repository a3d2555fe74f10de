"""Canonicalisation (SPEC §2 steps 1-5) on cases worked out by hand."""

import json
import math
import random

import pytest

from jax3dc.errors import StructureError
from jax3dc.structure import Box, Joint, Material, Node, Relation, Structure, canonicalize, parse_structure, to_json

MAT = {0: Material("Wood", "oak")}


def box(volume_side: float) -> Box:
    return Box((0.0, 0.0, 0.0), (volume_side, volume_side, volume_side))


def hinge(axis, rng, pivot=(0.1, 0.2, 0.3)):
    return Joint("hinge", tuple(float(c) for c in axis), pivot, tuple(float(v) for v in rng))


def slide(axis, rng, pivot=(0.0, 0.0, 0.0)):
    return Joint("slide", tuple(float(c) for c in axis), pivot, tuple(float(v) for v in rng))


def test_reroot_reverses_joints_along_the_path():
    # 1 (root, small) <-hinge- 2 <-slide- 3 (largest box), and 4 hangs rigidly off 1
    s = Structure(MAT, {
        1: Node(None, 0),
        2: Node(1, 0, hinge((0, 0, 1), (0.0, 1.5))),
        3: Node(2, 0, slide((1, 0, 0), (0.0, 0.3))),
        4: Node(1, 0, hinge((0, 1, 0), (-0.5, 0.25))),
    })
    boxes = {1: box(0.1), 2: box(0.2), 3: box(0.9), 4: box(0.3)}
    c = canonicalize(s, boxes)
    assert c.roots() == [3]
    assert c.nodes[3] == Node(None, 0)
    # the slide moved from 3 to its old parent 2, range [-hi, -lo]
    assert c.nodes[2].parent == 3
    assert c.nodes[2].joint == Joint("slide", (1.0, 0.0, 0.0), (0.0, 0.0, 0.0), (-0.3, -0.0))
    # the hinge moved from 2 to 1, pivot and axis kept
    assert c.nodes[1].parent == 2
    assert c.nodes[1].joint == Joint("hinge", (0.0, 0.0, 1.0), (0.1, 0.2, 0.3), (-1.5, -0.0))
    # an edge off the path is untouched
    assert c.nodes[4] == s.nodes[4]
    assert json.loads(to_json(c))["nodes"]["2"]["joint"]["range"] == [-0.3, 0.0]


def test_reroot_through_a_rigid_edge_makes_the_old_parent_rigid():
    s = Structure(MAT, {1: Node(None, 0), 2: Node(1, 0), 3: Node(2, 0, hinge((0, 0, 1), (0, 1)))})
    c = canonicalize(s, {1: box(0.1), 2: box(0.5), 3: box(0.2)})
    assert c.roots() == [2]
    assert c.nodes[1] == Node(2, 0, None)
    assert c.nodes[3] == s.nodes[3]


def test_volume_ties_go_to_the_smallest_id_even_with_permuted_extents():
    s = Structure(MAT, {1: Node(None, 0), 2: Node(1, 0), 3: Node(1, 0), 4: Node(3, 0)})
    # parts 3 and 4 have the same volume with extents in different orders (float products would differ)
    boxes = {1: box(0.1), 2: box(0.1), 3: Box((0, 0, 0), (0.7, 0.3, 0.1)), 4: Box((0, 0, 0), (0.1, 0.7, 0.3))}
    assert 0.7 * 0.3 * 0.1 != 0.1 * 0.7 * 0.3  # the case a naive comparison gets wrong
    c = canonicalize(s, boxes)
    assert c.roots() == [3]
    assert c.nodes[1].parent == 3 and c.nodes[4].parent == 3


def test_each_tree_of_a_scene_is_rerooted_on_its_own():
    s = Structure(MAT, {1: Node(None, 0), 2: Node(1, 0), 3: Node(None, 0), 4: Node(3, 0), 5: Node(4, 0)})
    c = canonicalize(s, {1: box(0.2), 2: box(0.1), 3: box(0.1), 4: box(0.1), 5: box(0.5)})
    assert c.roots() == [1, 5]
    assert {i: n.parent for i, n in c.nodes.items()} == {1: None, 2: 1, 3: 4, 4: 5, 5: None}


@pytest.mark.parametrize("axis,rng,want_axis,want_range", [
    ((0, -1, 0), (0.2, 1.0), (0, 1, 0), (-1.0, -0.2)),
    ((0, 1, 0), (0.2, 1.0), (0, 1, 0), (0.2, 1.0)),
    ((0.6, -0.8, 0), (0.0, 1.0), (-0.6, 0.8, 0), (-1.0, 0.0)),
    ((-0.8, 0.6, 0), (0.0, 1.0), (0.8, -0.6, 0), (-1.0, 0.0)),
    ((0, 0, -3), (-0.5, 2.0), (0, 0, 1), (-2.0, 0.5)),
    # ties in magnitude: the first of the largest components decides
    ((1, -1, 0), (0.0, 1.0), (1, -1, 0), (0.0, 1.0)),
    ((-1, 1, 0), (0.0, 1.0), (1, -1, 0), (-1.0, 0.0)),
    ((0, -1, 1), (0.0, 1.0), (0, 1, -1), (-1.0, 0.0)),
    # a tie only as written (3 decimals): 0.70711 vs -0.70710 is a tie, first component wins
    ((-0.7071, 0.70711, 0), (0.0, 1.0), (0.7071, -0.70711, 0), (-1.0, 0.0)),
])
def test_axis_sign(axis, rng, want_axis, want_range):
    s = Structure(MAT, {1: Node(None, 0), 2: Node(1, 0, hinge(axis, rng))})
    j = canonicalize(s, {1: box(1), 2: box(0.1)}).nodes[2].joint
    norm = math.sqrt(sum(c * c for c in want_axis))
    assert j.axis == pytest.approx([c / norm for c in want_axis])
    assert j.range == pytest.approx(want_range)
    assert math.isclose(sum(c * c for c in j.axis), 1.0)


@pytest.mark.parametrize("joint", [
    hinge((0, 0, 1), (0.3, 0.3)),
    hinge((0, 0, 1), (0.2, 0.2004)),  # equal as written
    slide((0, 0, 0), (0.0, 1.0)),
    slide((0, math.nan, 1), (0.0, 1.0)),
    slide((math.inf, 0, 1), (0.0, 1.0)),
])
def test_degenerate_joints_become_rigid(joint):
    s = Structure(MAT, {1: Node(None, 0), 2: Node(1, 0, joint)})
    c = canonicalize(s, {1: box(1), 2: box(0.1)})
    assert c.nodes[2] == Node(1, 0, None)


def test_small_but_real_range_is_kept():
    s = Structure(MAT, {1: Node(None, 0), 2: Node(1, 0, hinge((0, 0, 1), (0.2, 0.201)))})
    assert canonicalize(s, {1: box(1), 2: box(0.1)}).nodes[2].joint is not None


def test_relations_instance_star_symmetric_order_support_direction():
    nodes = {i: Node(None if i == 1 else 1, 0) for i in range(1, 11)}
    rels = (
        Relation("instance", 7, 6), Relation("instance", 5, 3), Relation("instance", 3, 7),  # chain 5-3-7-6
        Relation("instance", 10, 9), Relation("instance", 9, 10),  # a second group, twice
        Relation("symmetric", 8, 4, "yz"), Relation("symmetric", 4, 8, "yz"),
        Relation("support", 9, 2),
    )
    c = canonicalize(Structure(MAT, nodes, rels), {i: box(1.0 if i == 1 else 0.1) for i in nodes})
    assert c.relations == (
        Relation("instance", 3, 5), Relation("instance", 3, 6), Relation("instance", 3, 7),
        Relation("instance", 9, 10),
        Relation("support", 9, 2),
        Relation("symmetric", 4, 8, "yz"),
    )


def test_sorted_materials_and_nodes():
    s = Structure({3: Material("Metal"), 0: Material("Wood")}, {2: Node(1, 3), 1: Node(None, 0)})
    c = canonicalize(s, {1: box(1), 2: box(0.1)})
    assert list(c.materials) == [0, 3] and list(c.nodes) == [1, 2]


def test_key_order_and_json_permutation_make_no_difference():
    doc = {
        "materials": {"0": {"family": "Wood", "desc": "a"}, "1": {"family": "Metal", "desc": "b"}},
        "nodes": {
            "1": {"parent": None, "material": 0},
            "2": {"parent": 1, "material": 1, "joint": {"type": "hinge", "axis": [0, 0, -1], "pivot": [0.4, -0.3, 0], "range": [0, 1.571]}},
            "3": {"parent": 1, "material": 1, "joint": {"type": "slide", "axis": [0, -1, 0], "pivot": [0, 0, 0], "range": [0, 0.4]}},
            "4": {"parent": 3, "material": 0},
            "5": {"parent": 1, "material": 0},
            "6": {"parent": 1, "material": 0},
        },
        "relations": [{"type": "instance", "a": 6, "b": 5}, {"type": "symmetric", "a": 3, "b": 2, "plane": "yz"},
                      {"type": "instance", "a": 5, "b": 4}],
    }
    boxes = {1: box(0.5), 2: box(0.6), 3: box(0.2), 4: box(0.2), 5: box(0.2), 6: box(0.2)}
    want = to_json(canonicalize(parse_structure(doc), boxes))
    rng = random.Random(0)
    for _ in range(20):
        def shuffled(obj):
            if isinstance(obj, dict):
                items = list(obj.items())
                rng.shuffle(items)
                return {k: shuffled(v) for k, v in items}
            if isinstance(obj, list) and obj and isinstance(obj[0], dict):
                return rng.sample([shuffled(v) for v in obj], len(obj))
            return obj
        text = json.dumps(shuffled(doc), indent=rng.choice([None, 1, 4]))
        assert to_json(canonicalize(parse_structure(text), boxes)) == want
    c = json.loads(want)
    assert c["nodes"]["2"]["parent"] is None  # largest part became the root
    # the hinge (-z, [0, 1.571]) moved from 2 to 1: reversed to [-1.571, 0], then the axis flipped to +z
    # which mirrors the range back to [0, 1.571]
    assert c["nodes"]["1"]["joint"]["axis"] == [0.0, 0.0, 1.0]
    assert c["nodes"]["1"]["joint"]["range"] == [0.0, 1.571]
    assert c["relations"] == [{"type": "instance", "a": 4, "b": 5}, {"type": "instance", "a": 4, "b": 6},
                              {"type": "symmetric", "a": 2, "b": 3, "plane": "yz"}]


def test_idempotent_and_stable_through_json():
    s = Structure(MAT, {
        1: Node(None, 0), 2: Node(1, 0, hinge((0.577, -0.5775, 0.577), (-0.25, 1.0))),
        3: Node(2, 0, slide((-0.3, 0.1, -0.3), (0.1, 0.5))), 4: Node(3, 0),
    }, (Relation("instance", 4, 2), Relation("instance", 3, 4)))
    boxes = {1: box(0.2), 2: box(0.3), 3: box(0.4), 4: box(0.3)}
    c = canonicalize(s, boxes)
    assert canonicalize(c, boxes) == c
    text = to_json(c)
    again = canonicalize(parse_structure(text), boxes)
    assert to_json(again) == text


def test_missing_box_and_cycle_are_structure_errors():
    s = Structure(MAT, {1: Node(None, 0), 2: Node(1, 0)})
    with pytest.raises(StructureError) as info:
        canonicalize(s, {1: box(1)})
    assert info.value.rule == "box_missing" and "2" in str(info.value)
    cyclic = Structure(MAT, {1: Node(None, 0), 2: Node(3, 0), 3: Node(2, 0)})
    with pytest.raises(StructureError) as info:
        canonicalize(cyclic, {i: box(1) for i in (1, 2, 3)})
    assert info.value.rule == "cycle"


def test_numpy_scalars_serialise_like_python_numbers():
    import numpy as np

    plain = Structure(MAT, {1: Node(None, 0), 2: Node(1, 0, hinge((0, 0, 1), (0, 1)))}, (Relation("instance", 1, 2),))
    numpy = Structure({np.int64(0): Material("Wood", "oak")},
                      {np.int64(1): Node(None, np.int64(0)),
                       np.int64(2): Node(np.int64(1), np.int64(0),
                                         Joint("hinge", tuple(np.array([0.0, 0.0, 1.0])), tuple(np.array([0.1, 0.2, 0.3])),
                                               (np.float32(0.0), np.float64(1.0))))},
                      (Relation("instance", np.int64(1), np.int64(2)),))
    assert to_json(numpy) == to_json(plain)
