"""Scoring a structure predicted on stage 1's own parts: parts paired by box overlap, the structure
renamed onto the reference's ids (eval.metrics.relabel), then the usual Table 1."""

from __future__ import annotations

import numpy as np
import pytest

from eval.metrics.cases import Reference, build_cases
from eval.metrics.part_matching import box_bounds, match_bounds
from eval.metrics.relabel import relabel
from eval.metrics.score import evaluate
from jax3dc.structure import Box, canonicalize, to_dict
from jax3dc.structure.schema import Relation
from tests.eval.eval_structures import hinge, structure


def _boxes(*centres) -> dict[int, Box]:
    return {i + 1: Box(tuple(c), (0.2, 0.2, 0.2)) for i, c in enumerate(centres)}


def test_boxes_pair_whatever_their_ids_and_a_far_box_has_no_partner():
    ref = box_bounds(_boxes((0, 0, 0), (0.5, 0, 0)))
    pred = box_bounds({7: Box((0.5, 0, 0), (0.2, 0.2, 0.2)), 3: Box((0.05, 0, 0), (0.2, 0.2, 0.2)),
                       9: Box((3, 3, 3), (0.2, 0.2, 0.2))})
    assert np.allclose(ref[1], [[-0.1, -0.1, -0.1], [0.1, 0.1, 0.1]])
    pairs = sorted(match_bounds(ref, pred))
    assert [(r, p) for r, p, _ in pairs] == [(1, 3), (2, 7)]
    assert pairs[0][2] == pytest.approx(0.15 / 0.25) and pairs[1][2] == pytest.approx(1.0)


def test_renamed_parts_keep_their_parents_joints_and_relations():
    door = hinge(pivot=(0.1, -0.3, 0.0))
    pred = structure({1: None, 2: 1, 3: 1}, {3: door}, (Relation("symmetric", 2, 3, "yz"),))
    renamed = relabel(pred, {1: 5, 2: 4, 3: 6}, [4, 5, 6])
    assert {i: n.parent for i, n in renamed.nodes.items()} == {4: 5, 5: None, 6: 5}
    assert renamed.nodes[6].joint == door and renamed.nodes[4].joint is None
    assert renamed.relations == (Relation("symmetric", 4, 6, "yz"),)


def test_an_extra_part_is_dropped_and_its_children_move_up():
    pred = structure({1: None, 2: 1, 3: 2, 4: 3}, {3: hinge(), 4: hinge()}, (Relation("instance", 2, 3),))
    renamed = relabel(pred, {1: 1, 3: 2, 4: 3}, [1, 2, 3])  # predicted part 2 has no reference partner
    assert {i: n.parent for i, n in renamed.nodes.items()} == {1: None, 2: 1, 3: 2}
    assert renamed.nodes[2].joint == hinge() and renamed.relations == ()


def test_a_part_left_without_a_matched_ancestor_becomes_a_rigid_root():
    pred = structure({1: None, 2: 1}, {2: hinge()})
    renamed = relabel(pred, {2: 1}, [1])
    assert renamed.nodes[1].parent is None and renamed.nodes[1].joint is None


def test_a_missing_reference_part_is_a_rigid_root_and_scores_as_a_miss():
    ref_structure = structure({1: None, 2: 1, 3: 1}, {2: hinge(), 3: hinge(pivot=(0.4, 0, 0))})
    boxes = _boxes((0, 0, 0), (0.1, -0.3, 0), (0.4, -0.3, 0))
    boxes[1] = Box((0, 0, 0), (1.0, 0.6, 0.8))
    reference = Reference("k", canonicalize(ref_structure, boxes), boxes)
    # stage 1 made parts 1 and 2 only, under other ids; stage 2 got them right
    pred = structure({8: None, 9: 8}, {9: hinge()})
    renamed = relabel(pred, {8: 1, 9: 2}, boxes)
    assert renamed.nodes[3].parent is None and renamed.nodes[3].joint is None
    assert renamed.materials[renamed.nodes[3].material].family == "Other"
    metrics = evaluate(build_cases([reference], {"k": to_dict(renamed)})).metrics
    assert metrics["parse"] == 100.0
    assert metrics["parent_acc"] == pytest.approx(200 / 3)  # the missing part's parent is wrong
    assert metrics["presence_f1"] == pytest.approx(200 / 3) and metrics["success"] == 100.0


def test_pairs_that_are_not_one_to_one_onto_the_reference_are_refused():
    pred = structure({1: None, 2: 1})
    with pytest.raises(ValueError, match="not in the structure \\[7\\]"):
        relabel(pred, {7: 1}, [1, 2])
    with pytest.raises(ValueError, match="not among the reference parts \\[9\\]"):
        relabel(pred, {1: 9}, [1, 2])
    with pytest.raises(ValueError, match="one-to-one"):
        relabel(pred, {1: 1, 2: 1}, [1, 2])
