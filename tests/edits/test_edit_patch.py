"""Edit patches on a structure (no folder, no physics): what each op does, the named lines, and
one clear error naming its place in the patch for each bad patch, raised before anything is
written (the folder tests check that nothing is)."""

from __future__ import annotations

import json
import math

import pytest

from jax3dc.edits.lines import hinge_lines, line_at
from jax3dc.edits.patch import apply_patch, edit_structure, read_patch
from jax3dc.errors import EditError
from jax3dc.geometry.parts import part_boxes
from jax3dc.structure import Box, parse_structure, to_json
from tests.predict.predict_cases import factory_object, target_json

DOOR, BODY, SHELF, HANDLE = 3, 1, 2, 4  # the cabinet's left door (hinged on 1), its handle (fixed to it)


@pytest.fixture(scope="module")
def cabinet():
    return parse_structure(target_json()), part_boxes(factory_object().parts)


def edit(cabinet, part: int, *ops: tuple[str, object]):
    structure, boxes = cabinet
    return edit_structure(structure, {"part": part, "ops": [{"op": o, "value": v} for o, v in ops]}, boxes)[0]


def test_the_nine_lines_of_a_box_are_named_by_its_faces():
    box = Box((0.0, 0.0, 0.0), (2.0, 4.0, 6.0))
    lines = hinge_lines(box, (0.0, 0.0, 1.0))
    assert list(lines) == ["edge -x -y", "face -x", "edge -x +y", "face -y", "centre", "face +y",
                           "edge +x -y", "face +x", "edge +x +y"]
    assert lines["edge +x -y"] == (1.0, -2.0, 0.0) and lines["centre"] == (0.0, 0.0, 0.0)
    assert list(hinge_lines(box, (1.0, 0.0, 0.0)))[0] == "edge -y -z"  # across x: the y and z faces
    assert hinge_lines(box, (1.0, 1.0, 0.0)) == {}  # a free axis has no named lines
    assert line_at(box, (0.0, 0.0, -1.0), (0.995, -2.004, 3.0)) == "edge +x -y"
    assert line_at(box, (0.0, 0.0, 1.0), (0.5, 0.0, 0.0)) is None


def test_moving_a_hinge_to_the_opposite_edge_turns_it_to_open_outward(cabinet):
    structure, boxes = cabinet
    before = structure.nodes[DOOR].joint
    assert line_at(boxes[DOOR], before.axis, before.pivot) == "edge -x +y"  # the door's back left edge
    after = edit(cabinet, DOOR, ("set_line", "edge +x +y")).nodes[DOOR].joint
    assert line_at(boxes[DOOR], after.axis, after.pivot) == "edge +x +y"
    assert after.range == (-before.range[1], -before.range[0])  # same span, swinging out, not into the body
    kept = edit(cabinet, DOOR, ("set_line", "edge +x +y"), ("set_range", [-1.0, 0.0])).nodes[DOOR].joint
    assert kept.range == (-1.0, 0.0)  # a range the patch sets is kept as written


def test_type_axis_range_and_parent_ops(cabinet):
    slide = edit(cabinet, DOOR, ("set_type", "slide"), ("set_axis", "-y")).nodes[DOOR].joint
    assert slide.type == "slide" and slide.axis == (0.0, -1.0, 0.0)
    assert slide.range[0] <= 0 < slide.range[1] or slide.range[1] <= 0  # a default travel, pulled out of the body
    assert 0.02 <= max(abs(v) for v in slide.range) <= 0.6
    assert edit(cabinet, DOOR, ("set_type", "fixed")).nodes[DOOR].joint is None
    new = edit(cabinet, SHELF, ("set_type", "hinge"), ("set_axis", [1, 0, 1]), ("set_line", [0.1, 0.2, 0.3])).nodes[SHELF]
    assert new.joint.type == "hinge" and new.joint.pivot == (0.1, 0.2, 0.3)
    assert new.joint.axis == pytest.approx((math.sqrt(0.5), 0.0, math.sqrt(0.5)), abs=1e-3)
    assert new.joint.range in ((0.0, 1.571), (-1.571, 0.0))  # a quarter turn (rounded as structure.json is), outward
    moved = edit(cabinet, HANDLE, ("set_parent", BODY))
    assert moved.nodes[HANDLE].parent == BODY
    assert to_json(edit(cabinet, DOOR, ("set_range", [0, 1]))) != target_json()


NAN_AXIS = '{"part": 3, "ops": [{"op": "set_axis", "value": [NaN, 0, 1]}]}'
BAD = [  # (patch, rule, where)
    ({"part": 9, "ops": [{"op": "set_type", "value": "fixed"}]}, "part_exists", "part"),
    (NAN_AXIS, "axis_finite", "ops[0].value"),
    ({"part": 3, "ops": [{"op": "set_axis", "value": [0, 0, 0]}]}, "axis_zero", "ops[0].value"),
    ({"part": 3, "ops": [{"op": "set_axis", "value": "up"}]}, "axis_name", "ops[0].value"),
    ({"part": 3, "ops": [{"op": "set_colour", "value": "red"}]}, "unknown_op", "ops[0].op"),
    ({"part": 3, "ops": [{"op": "set_range", "value": [1.0, 0.0]}]}, "range_order", "ops[0].value"),
    ({"part": 3, "ops": [{"op": "set_range", "value": [0.0, 7.0]}]}, "hinge_range", "ops[0] set_range"),
    ({"part": 3, "ops": [{"op": "set_line", "value": "edge +z"}]}, "line_name", "ops[0] set_line.value"),
    ({"part": 3, "ops": [{"op": "set_axis", "value": [1, 1, 0]}, {"op": "set_line", "value": "centre"}]},
     "line_axis", "ops[1] set_line.value"),
    ({"part": 3, "ops": [{"op": "set_range", "value": [0, 1]}, {"op": "set_range", "value": [0, 2]}]}, "op_twice", "ops[1]"),
    ({"part": 3, "ops": [{"op": "set_type", "value": "ball"}]}, "joint_type", "ops[0].value"),
    ({"part": 2, "ops": [{"op": "set_type", "value": "hinge"}]}, "axis_needed", "ops[0] set_type"),
    ({"part": 2, "ops": [{"op": "set_range", "value": [0, 1]}]}, "no_joint", "ops[0] set_range"),
    ({"part": 3, "ops": [{"op": "set_type", "value": "fixed"}, {"op": "set_axis", "value": "+x"}]}, "no_joint",
     "ops[1] set_axis"),
    ({"part": 1, "ops": [{"op": "set_parent", "value": 3}]}, "cycle", "ops[0] set_parent"),
    ({"part": 1, "ops": [{"op": "set_type", "value": "hinge"}, {"op": "set_axis", "value": "+z"}]},
     "joint_without_parent", "ops[0] set_type"),
    ({"part": 3, "ops": [{"op": "set_parent", "value": 42}]}, "parent_exists", "ops[0] set_parent"),
    ({"part": 3, "ops": []}, "no_ops", "ops"),
    ({"part": "3", "ops": [{"op": "set_type", "value": "fixed"}]}, "value_type", "part"),
    ({"part": 3, "ops": [{"op": "set_type", "value": "fixed"}], "why": "x"}, "unknown_key", "patch"),
    ('{"part": 3, "ops": [', "json", "patch line 1 column 21"),
    ('{"part": 3, "part": 4, "ops": []}', "duplicate_key", "patch key \"part\""),
]


@pytest.mark.parametrize("patch, rule, where", BAD, ids=[case[1] + str(k) for k, case in enumerate(BAD)])
def test_a_bad_patch_is_one_error_naming_its_place(cabinet, patch, rule, where):
    structure, boxes = cabinet
    with pytest.raises(EditError) as caught:
        edit_structure(structure, patch if isinstance(patch, str) else json.dumps(patch), boxes)
    assert (caught.value.rule, caught.value.where) == (rule, where), str(caught.value)
    assert str(caught.value).startswith(where)


def test_a_read_patch_round_trips_as_data(cabinet):
    patch = read_patch({"part": 3, "ops": [{"op": "set_axis", "value": [0, 0, 2]}, {"op": "set_line", "value": "centre"}]})
    assert patch.to_dict() == {"part": 3, "ops": [{"op": "set_axis", "value": (0.0, 0.0, 1.0)},
                                                  {"op": "set_line", "value": "centre"}]}
    assert apply_patch(cabinet[0], patch, cabinet[1]) == apply_patch(cabinet[0], read_patch(patch.to_dict()), cabinet[1])
