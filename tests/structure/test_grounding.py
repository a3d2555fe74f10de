"""Joint grounding (jax3dc.grounding): snapping, the type-and-axis choice, the outward range, and
that a valid structure stays valid whatever the boxes — all on hand-made boxes, in well under a second."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from jax3dc.errors import InputFileError
from jax3dc.grounding import CLASSES, Grounding, JointPrior, ground_joint, ground_structure, ground_text, shipped_prior
from jax3dc.grounding.features import JOINT_FEATURES, LINE_FEATURES, joint_features, line_features
from jax3dc.structure import Box, Joint, Material, Node, Structure, parse_structure, to_json, validate

CABINET = Box((0.0, 0.0, 0.0), (1.0, 0.6, 1.0))
DOOR = Box((0.0, -0.31, 0.0), (0.8, 0.02, 0.9))  # a thin slab on the cabinet's front face
HANDLE = Box((0.35, -0.33, 0.0), (0.03, 0.02, 0.2))  # near the door's +x edge


def flat_prior(favourite: tuple[str, int] | None = None, **kw) -> JointPrior:
    """A prior with no opinion about lines, and none about classes unless it has a ``favourite``."""
    weights = np.zeros((JOINT_FEATURES + 1, len(CLASSES)))
    if favourite is not None:
        weights[-1, CLASSES.index(favourite)] = 10.0
    return JointPrior(np.zeros(JOINT_FEATURES), np.ones(JOINT_FEATURES), weights, np.zeros(LINE_FEATURES), **kw)


def structure(joint: Joint | None) -> Structure:
    nodes = {1: Node(None, 0), 2: Node(1, 0, joint), 3: Node(2, 0)}
    return Structure({0: Material("Wood")}, nodes)


BOXES = {1: CABINET, 2: DOOR, 3: HANDLE}


def test_tilted_axis_near_a_box_direction_is_snapped_and_a_far_one_kept():
    g = Grounding(type_axis=False, line_snap=False, prior=flat_prior())
    near = Joint("hinge", (0.1, 0.0, -0.995), (-0.4, -0.31, 0.0), (0.0, 1.5))
    assert ground_joint(near, DOOR, CABINET, [], g).axis == (0.0, 0.0, -1.0)
    far = Joint("hinge", (0.7, 0.0, 0.714), (-0.4, -0.31, 0.0), (0.0, 1.5))
    np.testing.assert_allclose(ground_joint(far, DOOR, CABINET, [], g).axis, np.array(far.axis) / np.linalg.norm(far.axis))


def test_hinge_written_near_an_edge_lands_on_it():
    g = Grounding(type_axis=False, line_snap=True, prior=flat_prior())
    written = Joint("hinge", (0.0, 0.0, 1.0), (-0.37, -0.33, 0.2), (0.0, 1.5))
    out = ground_joint(written, DOOR, CABINET, [HANDLE], g)
    np.testing.assert_allclose(out.pivot, (-0.4, -0.32, 0.0), atol=1e-9)  # the left front edge, at the door's mid height
    assert out.range == written.range  # moved less than line_sigma: the model's opening is kept


def test_hinge_written_off_every_box_line_is_kept():
    g = Grounding(type_axis=False, line_snap=True, prior=flat_prior())
    written = Joint("hinge", (0.0, 0.0, 1.0), (-0.7, -0.5, 0.0), (0.0, 1.5))  # far outside the door's box
    assert ground_joint(written, DOOR, CABINET, [], g).pivot == written.pivot


def test_the_prior_overrules_the_written_class_only_when_keep_ratio_allows():
    hinge = Joint("hinge", (0.0, 0.0, 1.0), (-0.4, -0.31, 0.0), (0.0, 1.5))
    sure = Grounding(axis_dim_kept=False, prior=flat_prior(("slide", 1), keep_ratio=4.0))
    out = ground_joint(hinge, DOOR, CABINET, [], sure)
    assert out.type == "slide" and out.axis == (0.0, -1.0, 0.0)  # out of the cabinet's front face (-Y)
    assert 0.0 < out.range[1] <= 0.6 and out.range[0] == 0.0
    stubborn = Grounding(axis_dim_kept=False, prior=flat_prior(("slide", 1), keep_ratio=1e6))
    assert ground_joint(hinge, DOOR, CABINET, [], stubborn).type == "hinge"


def test_a_slide_turned_into_a_hinge_gets_a_line_of_its_box_and_a_hinge_range():
    slide = Joint("slide", (0.0, 1.0, 0.0), (0.0, -0.31, 0.0), (0.0, 0.3))
    free = Grounding(axis_dim_kept=False, line_snap=True, prior=flat_prior(("hinge", 2)))
    out = ground_joint(slide, DOOR, CABINET, [HANDLE], free)
    assert out.type == "hinge" and out.axis == (0.0, 0.0, 1.0)
    assert abs(out.range[1] - out.range[0] - math.pi / 2) < 1e-9
    # it opens outward: positive angles of the range it spans move the door away from the cabinet's centre
    swing = np.cross(out.axis, np.subtract(DOOR.centroid, out.pivot))
    assert (swing @ np.subtract(DOOR.centroid, CABINET.centroid)) * (out.range[0] + out.range[1]) > 0
    assert validate(to_json(ground_structure(structure(slide), BOXES, free))) == []


@pytest.mark.parametrize("child", [Box((0.0, 0.0, 0.0), (0.0, 0.0, 0.0)), Box((0.1, 0.2, 0.3), (0.5, 0.0, 0.0))])
def test_degenerate_boxes_give_finite_features_and_a_valid_joint(child):
    assert np.all(np.isfinite(joint_features(child, Box((0, 0, 0), (0, 0, 0)))))
    assert np.all(np.isfinite(line_features(child, None, 2)))
    joint = Joint("hinge", (0.0, 1.0, 0.0), (0.0, 0.0, 0.0), (-1.0, 1.0))
    every_step = Grounding(axis_dim_kept=False, line_snap=True)
    grounded = ground_structure(structure(joint), {1: Box((0, 0, 0), (0, 0, 0)), 2: child, 3: child}, every_step)
    assert validate(to_json(grounded), part_ids=[1, 2, 3]) == []


def test_missing_boxes_and_no_joints_leave_the_structure_alone():
    joint = Joint("hinge", (0.0, 0.0, 1.0), (-0.37, -0.30, 0.2), (0.0, 1.5))
    assert ground_structure(structure(joint), {1: CABINET, 3: HANDLE}, Grounding()) == structure(joint)
    rigid = structure(None)
    assert ground_structure(rigid, BOXES, Grounding()) == rigid
    # a parent without a box: grounded against the child's box alone
    assert validate(to_json(ground_structure(structure(joint), {2: DOOR, 3: HANDLE}, Grounding()))) == []


def test_ground_text_leaves_what_does_not_validate_and_keeps_what_surrounds_the_json():
    assert ground_text("not json at all", BOXES, Grounding()) == "not json at all"
    wrong_ids = to_json(structure(None)).replace('"3"', '"9"')
    assert ground_text(wrong_ids, BOXES, Grounding()) == wrong_ids
    joint = Joint("hinge", (0.0, 0.0, 1.0), (-0.37, -0.30, 0.2), (0.0, 1.5))
    text = "```json\n" + to_json(structure(joint)) + "\n```<|im_end|>"
    out = ground_text(text, BOXES, Grounding(type_axis=False, line_snap=True, prior=flat_prior()))
    assert out.startswith("```json\n{") and out.endswith("}\n```<|im_end|>")
    assert parse_structure(out[out.find("{"):out.rfind("}") + 1]).nodes[2].joint.pivot == (-0.4, -0.3, 0.0)


def test_grounding_never_makes_a_valid_structure_invalid():
    """Random trees, joints and boxes (thin, flat, empty, far apart), grounded with the shipped prior."""
    rng = np.random.default_rng(0)
    prior = shipped_prior()
    for _ in range(200):
        n = int(rng.integers(2, 7))
        boxes = {i: Box(tuple(rng.uniform(-0.5, 0.5, 3)), tuple(rng.choice([0.0, 0.01, 0.3, 1.0], 3))) for i in range(1, n + 1)}
        nodes = {1: Node(None, 0)}
        for i in range(2, n + 1):
            joint = None
            if rng.random() < 0.8:
                axis = rng.normal(size=3)
                axis = axis if rng.random() < 0.5 else np.eye(3)[rng.integers(3)] * rng.choice([-1, 1])
                kind = str(rng.choice(["hinge", "slide"]))
                lo = float(rng.uniform(-3, 0))
                joint = Joint(kind, tuple(axis), tuple(rng.uniform(-1, 1, 3)), (lo, lo + float(rng.uniform(0.01, 3))))
            nodes[i] = Node(int(rng.integers(1, i)), 0, joint)
        text = to_json(Structure({0: Material("Metal")}, nodes))
        assert validate(text, part_ids=boxes) == []
        for g in (Grounding(prior=prior), Grounding(axis_dim_kept=False, line_snap=True,
                                                    prior=replace(prior, keep_ratio=1.0, line_sigma=1e3))):
            out = ground_text(text, boxes, g)
            assert validate(out, part_ids=boxes) == [], out
            grounded = parse_structure(out)
            assert {i: x.parent for i, x in grounded.nodes.items()} == {i: x.parent for i, x in nodes.items()}
            assert {i for i, x in grounded.nodes.items() if x.joint} == {i for i, x in nodes.items() if x.joint}


def test_prior_files_load_and_a_bad_one_is_named(tmp_path):
    prior = shipped_prior()
    assert prior.class_logprobs(joint_features(DOOR, CABINET)).shape == (len(CLASSES),)
    path = tmp_path / "prior.json"
    prior.save(path)
    np.testing.assert_allclose(JointPrior.load(path).class_weights, prior.class_weights)
    doc = json.loads(path.read_text())
    doc["line_weights"] = doc["line_weights"][:-1]
    path.write_text(json.dumps(doc))
    with pytest.raises(InputFileError, match="prior.json.*line_weights"):
        JointPrior.load(path)


def test_with_the_axis_dimension_kept_only_the_type_changes():
    hinge = Joint("hinge", (0.0, 0.0, 1.0), (-0.4, -0.31, 0.0), (0.0, 1.5))
    likes_y_slides = flat_prior(("slide", 1))
    assert ground_joint(hinge, DOOR, CABINET, [], Grounding(prior=likes_y_slides, axis_dim_kept=True)).type == "hinge"
    out = ground_joint(hinge, DOOR, CABINET, [], Grounding(prior=flat_prior(("slide", 2)), axis_dim_kept=True))
    assert out.type == "slide" and out.axis == (0.0, 0.0, 1.0)  # level with the cabinet's centre: +z by convention
