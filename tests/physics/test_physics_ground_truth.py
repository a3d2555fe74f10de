"""Measuring the physics checks (issue 8): which mutations change the motion, and that specific
mutations are caught with the right reason while specific ground-truth objects pass."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from jax3dc.factories import generate_object
from crossing_cases import crossings
from jax3dc.physics.findings import FAILURE, WARNING, Finding, describe
from eval.verdict_accuracy.ground_truth import changes_motion, imported_objects
from jax3dc.physics.kinematics import SAME_MOTION_TOL_NU, symmetric_about, sweep_distance
from eval.verdict_accuracy.mutations import mutations_of
from jax3dc.physics.tolerances import LIMIT_PAST_CONTACT_HINGE_RAD, LIMIT_TOL_HINGE_RAD
from jax3dc.physics.verdict import check_object, verdict_with_curves
from jax3dc.structure.schema import Joint
from tests.shared_fixtures import PARTNET_MOBILITY, partnet_object


def _mutation(obj, kind, part):
    return next(m for m in mutations_of(obj.structure, obj.parts) if m.kind == kind and m.part == part)


def _part_named(obj, name):
    return next(p for p, n in obj.structure.nodes.items() if n.name == name)


# --- the same motion or not: pose sets, against closed-form distances -------------------------

POINTS = np.array([[0.5, 0.0, 0.0], [0.3, 0.2, 0.1], [0.1, -0.2, 0.3]])


def test_flipped_symmetric_hinge_sweeps_the_same_poses():
    hinge = Joint("hinge", (0.0, 0.0, 1.0), (0.0, 0.0, 0.0), (-0.7, 0.7))
    flipped = dataclasses.replace(hinge, axis=(0.0, 0.0, -1.0))
    assert sweep_distance(hinge, flipped, POINTS) < SAME_MOTION_TOL_NU
    # not symmetric about rest: the flipped sweep reaches poses up to 2 * R * sin(0.7) from the original
    lopsided = dataclasses.replace(hinge, range=(0.0, 0.7))
    expect = 2 * 0.5 * np.sin(0.7 / 2)  # the farthest pose (q=-0.7) against the nearest original one (q=0)
    got = sweep_distance(lopsided, dataclasses.replace(lopsided, axis=(0.0, 0.0, -1.0)), POINTS)
    assert got == pytest.approx(expect, abs=SAME_MOTION_TOL_NU)


def test_full_turn_reaches_the_same_poses_either_way_and_when_doubled():
    turn = Joint("hinge", (1.0, 0.0, 0.0), (0.0, 0.1, 0.0), (0.0, 2 * np.pi))
    assert sweep_distance(turn, dataclasses.replace(turn, axis=(-1.0, 0.0, 0.0)), POINTS) < SAME_MOTION_TOL_NU
    half = dataclasses.replace(turn, range=(-np.pi, np.pi))
    assert sweep_distance(half, dataclasses.replace(half, range=(-np.pi, 2 * np.pi)), POINTS) < SAME_MOTION_TOL_NU


def test_longer_slide_is_a_different_motion_by_the_extra_travel():
    slide = Joint("slide", (0.0, -1.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.3))
    assert sweep_distance(slide, dataclasses.replace(slide, range=(0.0, 0.6)), POINTS) == pytest.approx(0.3, abs=SAME_MOTION_TOL_NU)


def test_round_part_is_symmetric_about_its_axis_only():
    angles = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    ring = np.stack([0.05 * np.cos(angles), 0.05 * np.sin(angles), np.zeros_like(angles)], axis=1)
    on_axis = Joint("hinge", (0.0, 0.0, 1.0), (0.0, 0.0, 0.0), (0.0, 1.0))
    assert symmetric_about(ring, on_axis)
    assert not symmetric_about(ring, dataclasses.replace(on_axis, pivot=(0.2, 0.0, 0.0)))
    assert not symmetric_about(ring + [0.1, 0.0, 0.0], on_axis)


def test_mutations_that_keep_the_motion_are_told_apart():
    oven = generate_object("oven", 0)
    knob = next(p for p, n in oven.structure.nodes.items() if n.name == "knob")
    assert not changes_motion(oven.structure, _mutation(oven, "flipped axis", knob), oven.parts)  # a round knob
    assert not changes_motion(oven.structure, _mutation(oven, "range doubled", knob), oven.parts)
    assert changes_motion(oven.structure, _mutation(oven, "pivot moved", knob), oven.parts)
    fan = generate_object("desk_fan", 0)
    head = _part_named(fan, "head")  # swings ±0.8 rad about rest: flipping it reaches the same poses
    assert not changes_motion(fan.structure, _mutation(fan, "flipped axis", head), fan.parts)
    lamp = generate_object("lamp", 0)
    arm = _part_named(lamp, "lower_arm")  # stops short of the desk forward, not backward: flipping it changes the poses
    assert changes_motion(lamp.structure, _mutation(lamp, "flipped axis", arm), lamp.parts)
    cabinet = generate_object("cabinet", 0)
    door = next(p for p, n in cabinet.structure.nodes.items() if n.joint is not None)
    for kind in ("flipped axis", "range doubled", "hinge-slide swapped", "pivot moved"):
        assert changes_motion(cabinet.structure, _mutation(cabinet, kind, door), cabinet.parts), kind


def test_reparenting_onto_a_part_welded_to_the_old_parent_keeps_the_motion():
    desk = generate_object("desk", 0)
    drawer = next(p for p, n in desk.structure.nodes.items() if n.joint is not None)
    far = _mutation(desk, "attached to a far part", drawer)
    assert desk.structure.nodes[far.structure.nodes[drawer].parent].joint is None
    assert not changes_motion(desk.structure, far, desk.parts)


# --- specific mutations are caught with the right reason ---------------------------------------

def _failures(obj, mutation, dynamics=False) -> tuple[Finding, ...]:
    verdict = verdict_with_curves(mutation.structure, obj.parts, obj.scale_m_per_nu, dynamics=dynamics)[0]
    return verdict.joint_findings(mutation.part, FAILURE)


def _reasons(obj, mutation, dynamics=False) -> list[str]:
    return [describe(f) for f in _failures(obj, mutation, dynamics)]


@pytest.mark.parametrize("category, name", [("safe", "handle"), ("toilet", "lid")])
def test_part_left_behind_by_its_moving_parent_is_run_into(category, name):
    # the safe's handle (or the toilet lid) hung on a far static part: its old parent swings through it
    obj = generate_object(category, 0)
    part = _part_named(obj, name)
    mutation = _mutation(obj, "attached to a far part", part)
    assert changes_motion(obj.structure, mutation, obj.parts)
    failures = _failures(obj, mutation)
    reasons = [describe(f) for f in failures]
    old_parent = obj.structure.nodes[part].parent
    assert any(r.startswith("penetrates part") and f"while joint {old_parent} moves" in r for r in reasons), reasons
    assert mutation.caught(failures)


def test_door_swapped_to_a_slide_is_caught():
    cabinet = generate_object("cabinet", 0)
    door = next(p for p, n in cabinet.structure.nodes.items() if n.joint is not None)
    mutation = _mutation(cabinet, "hinge-slide swapped", door)
    failures = _failures(cabinet, mutation, dynamics=True)
    assert mutation.caught(failures), failures


@pytest.mark.parametrize("category, name", [("dishwasher", "rack"), ("washing_machine", "detergent_drawer")])
def test_rack_pulled_out_of_its_guide_is_detached(category, name):
    # still within DETACH_TOL_NU of its parent when fully out, but no longer overlapping it along the slide
    obj = generate_object(category, 0)
    part = _part_named(obj, name)
    mutation = _mutation(obj, "range doubled", part)
    reasons = _reasons(obj, mutation)
    assert any(r.startswith("detached from parent (slides out of its guide)") for r in reasons), reasons
    truth = check_object(obj.structure, obj.parts, obj.scale_m_per_nu, dynamics=False)["joints"][str(part)]
    assert truth["ok"], truth


@pytest.mark.parametrize("seed", [0, 1])
def test_lid_lifted_off_its_pot_passes_but_not_far_away(seed):
    # PartNet-Mobility models a pot lid as a slide that lifts it off: parting is its motion
    pot = generate_object("kitchen_pot", seed)
    lid = _part_named(pot, "lid")
    truth = check_object(pot.structure, pot.parts, pot.scale_m_per_nu, dynamics=False)["joints"][str(lid)]
    assert truth["ok"], truth
    reasons = _reasons(pot, _mutation(pot, "range doubled", lid))
    assert any(r.startswith("detached from parent (lifted off too far)") for r in reasons), reasons


@pytest.mark.parametrize("category, name", [("eyeglasses", "temple"), ("laptop", "screen_lid")])
def test_thin_part_swung_too_far_passes_through_a_board(category, name):
    # a temple folded on through the frame, a screen opened on round into the base
    obj = generate_object(category, 0)
    part = _part_named(obj, name)
    mutation = _mutation(obj, "range doubled", part)
    assert changes_motion(obj.structure, mutation, obj.parts)
    lo, hi = mutation.structure.nodes[part].joint.range
    assert part in crossings(mutation.structure, obj.parts, {part: np.linspace(lo, hi, 9)})
    assert part not in crossings(obj.structure, obj.parts, {part: np.linspace(*obj.structure.nodes[part].joint.range, 9)})
    assert any(r.startswith("penetrates part") for r in _reasons(obj, mutation))


# --- specific ground-truth objects pass ---------------------------------------------------------

# the ground truth's warnings, by check and severity: the safe's door limit (2.967 rad) runs 0.195 rad past
# where the door meets the carcass (it stops at 2.772)
FIXTURE_WARNINGS = {"safe_rotate_101593": [("limit", "hi")]}
MOUNTED_FIXTURES = {"door_8877", "switch_100952", "window_rotate_103135"}  # a door, a wall switch, a window


@pytest.mark.parametrize("name", sorted(p.name for p in PARTNET_MOBILITY.iterdir() if (p / "mobility.urdf").is_file()))
def test_partnet_mobility_fixture_passes(name):
    # every fixture, mounted where its category is (jax3dc.mounted): warnings allowed, no failure
    obj = next(imported_objects([partnet_object(name)]))
    assert obj.mounted == (name in MOUNTED_FIXTURES)
    verdict = check_object(obj.structure, obj.parts, obj.scale, mounted=obj.mounted)
    # the toaster's one slide moves its base against the world: the importer drops it
    assert verdict["ok"] and bool(verdict["joints"]) == (name != "toaster_move_103482"), json.dumps(verdict)
    findings = [Finding.from_json(f) for f in verdict["findings"]]
    assert all(f.severity == WARNING for f in findings), json.dumps(verdict)
    assert [(f.check, f.limit) for f in findings] == FIXTURE_WARNINGS.get(name, []), json.dumps(verdict)
    for f in findings:  # a limit warning carries where the joint stops, short of its limit
        lo, hi = obj.structure.nodes[f.joints[0]].joint.range
        limit = hi if f.limit == "hi" else lo
        assert LIMIT_TOL_HINGE_RAD < abs(limit - f.reachable) <= LIMIT_PAST_CONTACT_HINGE_RAD, f
        assert verdict["joints"][str(f.joints[0])]["warnings"] == [describe(f)]


@pytest.mark.parametrize("category", ["door", "oven"])
def test_factory_object_with_dependent_joints_passes(category):
    obj = generate_object(category, 0)  # handles and knobs on moving doors: no false "while joint" blame
    verdict = check_object(obj.structure, obj.parts, obj.scale_m_per_nu)
    assert all(j["ok"] for j in verdict["joints"].values()), json.dumps(verdict)
