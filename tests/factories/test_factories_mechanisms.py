"""The robot-benchmark mechanisms (jax3dc.factories.mechanisms) move as their designs do, and the
`facing` parameter turns joints with the geometry: buttons slide into their face, dials turn about
its normal, sashes and sliding doors run along their frame and stay inside it."""

import functools
import math

import numpy as np
import pytest

from jax3dc.factories import generate_object
from jax3dc.factories.mechanisms import BUILDS, QUARTER_TURNS
from jax3dc.factories.registry import run_parameters
from jax3dc.parameters import Parameters
from tests.factory_samples import sample_parameters

SEEDS = range(8)
DIRECTION = {"-y": (0.0, -1.0, 0.0), "+x": (1.0, 0.0, 0.0), "-x": (-1.0, 0.0, 0.0), "+y": (0.0, 1.0, 0.0)}
UP = np.array([0.0, 0.0, 1.0])


@functools.lru_cache(maxsize=None)
def make(category, seed):
    return generate_object(category, seed)


def facing(obj) -> np.ndarray:
    """The direction the working face looks along, from the record."""
    v = obj.parameters.values
    name = ("+x", "-x", "+y")[v["facing"]] if v["turned"] else "-y"
    return np.array(DIRECTION[name])


def joints_named(obj, *names):
    return [(pid, j) for pid, j in obj.structure.joints().items() if obj.names[pid] in names]


def centre(obj, pid) -> np.ndarray:
    return obj.parts[pid].bounds.mean(axis=0)


def rotated(point, joint, angle) -> np.ndarray:
    a = np.asarray(joint.axis)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    r = np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * (k @ k)
    return (np.asarray(point) - joint.pivot) @ r.T + joint.pivot


def inside(inner_lo, inner_hi, outer, tol=1e-3) -> bool:
    return bool(np.all(inner_lo >= outer[0] - tol) and np.all(inner_hi <= outer[1] + tol))


def test_facings_are_drawn_mostly_front_on():
    counts = {name: 0 for name in DIRECTION}
    for seed in range(200):
        v = sample_parameters("lever", seed).values
        counts[("+x", "-x", "+y")[v["facing"]] if v["turned"] else "-y"] += 1
    assert 70 < counts["-y"] < 130 and all(counts[f] > 15 for f in ("+x", "-x", "+y")), counts


@pytest.mark.parametrize("category", sorted(BUILDS))
def test_facing_turns_geometry_and_joints_together(category):
    """The same record turned to +X, +Y and -X: every part's vertices and every joint's axis and
    pivot are those of the -Y object turned by the same quarter turns about +Z."""
    for seed in range(3):
        values = dict(make(category, seed).parameters.values)
        front = run_parameters(Parameters(category, {**values, "turned": 0}))
        for index, name in enumerate(("+x", "-x", "+y")):
            turned = run_parameters(Parameters(category, {**values, "turned": 1, "facing": index}))
            k = QUARTER_TURNS[name]
            c, s = round(math.cos(k * math.pi / 2)), round(math.sin(k * math.pi / 2))
            r = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]], dtype=float)
            assert turned.scale_m_per_nu == pytest.approx(front.scale_m_per_nu)
            for pid, mesh in front.parts.items():
                assert np.allclose(mesh.vertices @ r.T, turned.parts[pid].vertices, atol=2e-4), (category, name, pid)
            joints = front.structure.joints()
            assert joints and joints.keys() == turned.structure.joints().keys()
            for pid, j in joints.items():
                t = turned.structure.nodes[pid].joint
                assert t.type == j.type and t.range == j.range
                assert np.allclose(r @ j.axis, t.axis, atol=1e-9) and np.allclose(r @ j.pivot, t.pivot, atol=2e-4)


def test_buttons_slide_into_their_face():
    seen = {"top": 0, "front": 0}
    for seed in SEEDS:
        obj = make("button_panel", seed)
        (body,) = [p for p, n in obj.names.items() if n == "body"]
        buttons = joints_named(obj, "button")
        assert 1 <= len(buttons) <= 6
        for pid, j in buttons:
            axis = np.asarray(j.axis)
            assert j.type == "slide"
            travel_m = j.range[1] * obj.scale_m_per_nu
            assert j.range[0] == 0 and 0.001 < travel_m <= 0.022
            top = abs(axis @ UP) > 0.99
            if top:
                assert axis == pytest.approx(-UP)
            else:  # a front button moves against the facing: into the body
                assert axis == pytest.approx(-facing(obj))
            seen["top" if top else "front"] += 1
            # pressed fully, the cap still stands proud of the face and its stem stays in the body
            lo, hi = obj.parts[pid].bounds + axis * j.range[1]
            face_level = np.asarray(j.pivot) @ -axis
            assert max(lo @ -axis, hi @ -axis) > face_level + 1e-4
            b = obj.parts[body].bounds
            assert inside(np.minimum(lo, hi), np.maximum(lo, hi), (b[0] - 0.03, b[1] + 0.03))
    assert seen["top"] and seen["front"], seen


def test_dials_turn_about_their_face_normal():
    for seed in SEEDS:
        obj = make("dial_panel", seed)
        dials = joints_named(obj, "dial")
        assert 1 <= len(dials) <= 6
        for pid, j in dials:
            axis = np.asarray(j.axis)
            assert j.type == "hinge"
            assert abs(axis @ UP) > 0.99 or axis == pytest.approx(facing(obj))
            span = j.range[1] - j.range[0]
            assert math.pi / 2 - 0.01 <= span <= 2 * math.pi + 0.01
            # the dial turns in place: its centre lies on its own axis, in front of the pivot on the face
            offset = centre(obj, pid) - np.asarray(j.pivot)
            assert np.linalg.norm(offset - (offset @ axis) * axis) < 2e-3 and offset @ axis > 0


def test_levers_presses_and_sliders():
    kinds = set()
    for seed in range(12):
        obj = make("lever", seed)
        for pid, j in joints_named(obj, "lever_arm", "handle", "slider_knob"):
            kinds.add(obj.names[pid])
            if j.type == "hinge":
                assert abs(np.asarray(j.axis) @ UP) < 1e-9, "a horizontal hinge"
            if obj.names[pid] == "lever_arm":
                assert math.radians(29.9) <= j.range[1] <= math.radians(90.1) and j.range[0] in (0.0, -j.range[1])
            elif obj.names[pid] == "handle":  # pushed down about its back end
                (grip,) = [p for p, n in obj.names.items() if n == "grip" and obj.structure.nodes[p].parent == pid]
                before = centre(obj, grip)
                after = rotated(before, j, j.range[1])
                assert after[2] < before[2] - 0.01
                assert np.asarray(j.axis) @ facing(obj) == pytest.approx(0.0)
                assert (before - np.asarray(j.pivot)) @ facing(obj) > 0, "the grip reaches out of the face"
            else:
                assert j.type == "slide" and j.axis == pytest.approx(UP) and j.range[1] > 0
    assert kinds == {"lever_arm", "handle", "slider_knob"}


def test_sashes_slide_inside_the_frame_or_swing_out():
    styles = set()
    for seed in range(12):
        obj = make("sliding_window", seed)
        (frame,) = [p for p, n in obj.names.items() if n == "frame"]
        fb = obj.parts[frame].bounds
        d = facing(obj)
        for pid, j in joints_named(obj, "sash"):
            axis = np.asarray(j.axis)
            lo, hi = obj.parts[pid].bounds
            if j.type == "slide":
                styles.add("slide")
                assert abs(axis @ d) < 1e-9, "along the frame, not out of it"
                for q in np.linspace(0.0, j.range[1], 5):
                    assert inside(lo + axis * q, hi + axis * q, fb), (obj.object_id, q)
                assert j.range[1] > 0.1
            else:
                styles.add("hinge")
                assert abs(axis @ d) < 1e-9
                before = centre(obj, pid)
                assert (rotated(before, j, j.range[1]) - before) @ d > 0.02, "opens outwards"
    assert styles == {"slide", "hinge"}


def test_sliding_doors_run_sideways_inside_the_cabinet():
    found = 0
    for seed in SEEDS:
        obj = make("sliding_door_cabinet", seed)
        (body,) = [p for p, n in obj.names.items() if n == "body"]
        bb = obj.parts[body].bounds
        d = facing(obj)
        doors = joints_named(obj, "door")
        assert 1 <= len(doors) <= 2
        for pid, j in doors:
            axis = np.asarray(j.axis)
            assert j.type == "slide" and abs(axis @ d) < 1e-9 and abs(axis @ UP) < 1e-9
            lo, hi = obj.parts[pid].bounds
            assert inside(lo + axis * j.range[1], hi + axis * j.range[1], bb)
            assert j.range[1] * obj.scale_m_per_nu > 0.1
            found += 1
        for _, j in joints_named(obj, "drawer"):
            assert j.type == "slide" and j.axis == pytest.approx(d)
    assert found >= len(SEEDS)


def test_desk_drawers_slide_out_of_the_front():
    drawers = doors = 0
    for seed in range(12):
        obj = make("desk_drawers", seed)
        d = facing(obj)
        for pid, j in joints_named(obj, "drawer", "keyboard_tray"):
            assert j.type == "slide" and j.axis == pytest.approx(d) and j.range[1] > 0
            drawers += 1
        for pid, j in joints_named(obj, "door"):
            assert j.type == "hinge" and abs(np.asarray(j.axis) @ UP) == pytest.approx(1.0)
            before = centre(obj, pid)
            assert (rotated(before, j, j.range[1]) - before) @ d > 0.02
            doors += 1
        assert 1 <= len(joints_named(obj, "drawer")) <= 4
    assert drawers >= 12 and doors >= 1


def test_faucet_levers_lift_and_handles_turn_about_the_vertical():
    styles = set()
    for seed in range(10):
        obj = make("toggle_faucet_lever", seed)
        d = facing(obj)
        (spout,) = [p for p, n in obj.names.items() if n == "spout"]
        (body,) = [p for p, n in obj.names.items() if n == "body"]
        assert (centre(obj, spout) - centre(obj, body)) @ d > 0, "the spout reaches out of the front"
        for pid, j in joints_named(obj, "lever", "handle", "spout"):
            axis = np.asarray(j.axis)
            assert j.type == "hinge"
            if obj.names[pid] == "lever":  # the toggle: a horizontal axis across the front, lifting the lever
                styles.add("mixer")
                assert abs(axis @ UP) < 1e-9 and abs(axis @ d) < 1e-9
                before = centre(obj, pid)
                assert rotated(before, j, j.range[1])[2] > before[2] + 0.01
            else:  # handles and a swivelling spout turn about the vertical
                styles.add(obj.names[pid])
                assert abs(axis @ UP) == pytest.approx(1.0)
                if obj.names[pid] == "handle":
                    assert j.range == (0.0, pytest.approx(j.range[1])) and 1.0 < j.range[1] <= math.pi / 2 + 1e-3
    assert styles >= {"mixer", "handle"}
