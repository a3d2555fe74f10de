"""repair: a flagged joint gets a nearby alternative only when the verdict improves; others are untouched."""

import pytest

from jax3dc.verify.repair import ALL_KINDS, FLIPPED, PIVOT, SWAPPED, alternatives, pivot_lines, repair
from tests.verify.verified_cases import checked_object, flipped, pivot_moved_away

BOX = "storage_box/storage_box_000001/0"
MICROWAVE = "microwave/microwave_000001/0"


def run(obj, structure, kinds=ALL_KINDS):
    return repair(structure, obj.boxes, obj.check(), kinds)


@pytest.fixture
def box(checked_records):
    return checked_object(checked_records[BOX])


def test_a_flipped_lid_is_flipped_back(box):
    out = run(box, flipped(box.target, 2))
    assert not out.before.ok and 2 in out.before.failed_joints
    assert out.after.ok and out.structure == box.target
    (fix,) = out.repairs
    assert (fix.part, fix.kind) == (2, FLIPPED)
    assert fix.before == flipped(box.target, 2).nodes[2].joint and fix.after == box.target.nodes[2].joint
    assert fix.reason == "flagged joints 1 -> 0; object passes"


def test_by_default_only_pivots_move(box):
    """Flips and type swaps are measured to undo right joints the verdict flags (repair.DEFAULT_KINDS),
    so the default leaves a flipped lid as it is, and the lid's pivot still gets repaired."""
    out = repair(flipped(box.target, 2), box.boxes, box.check())
    assert all(fix.kind == PIVOT for fix in out.repairs)
    assert out.structure.nodes[2].joint.range == flipped(box.target, 2).nodes[2].joint.range
    moved = repair(pivot_moved_away(box.target, 2), box.boxes, box.check())
    assert moved.after.ok and [fix.kind for fix in moved.repairs] == [PIVOT]


def test_a_detached_pivot_is_moved_onto_the_lid_edge(box):
    broken = pivot_moved_away(box.target, 2)
    out = run(box, broken)
    assert "pivot detached" in out.before.to_json()["joints"]["2"]["reasons"]
    assert out.after.ok
    (fix,) = out.repairs
    assert fix.part == 2 and fix.kind.startswith(PIVOT)
    assert fix.after.axis == box.target.nodes[2].joint.axis and fix.after.pivot != broken.nodes[2].joint.pivot
    assert out.structure.nodes[2].joint == fix.after
    # nothing else changed
    assert {p: n for p, n in out.structure.nodes.items() if p != 2} == {p: n for p, n in box.target.nodes.items() if p != 2}


def test_a_passing_structure_is_left_alone(box):
    out = run(box, box.target)
    assert out.repairs == () and out.structure == box.target and out.before == out.after and out.after.ok


def test_joints_the_verdict_passes_are_never_changed(checked_records):
    microwave = checked_object(checked_records[MICROWAVE])
    out = run(microwave, flipped(microwave.target, 2))  # the door swings into the oven; the turntable is fine
    assert out.after.ok and [fix.part for fix in out.repairs] == [2]
    assert out.structure.nodes[5] == microwave.target.nodes[5]


def test_candidate_hinge_lines_touch_the_parent_and_include_the_true_one(box):
    joint = box.target.nodes[2].joint
    holder = box.parts[1].vertices
    lines = pivot_lines(pivot_moved_away(box.target, 2).nodes[2].joint, box.parts[2], holder)
    assert 1 <= len(lines) <= 5
    # the true hinge line (x is along the axis, so only y, z matter) is one of them, to the lid's box edge
    assert min(abs(p[1] - joint.pivot[1]) + abs(p[2] - joint.pivot[2]) for p in lines) < 0.03
    kinds = [kind for kind, _ in alternatives(box.target, box.parts, box.boxes, 2)]
    assert kinds[0] == FLIPPED and PIVOT in kinds and kinds[-1] == SWAPPED
