"""The device factories (jax3dc.factories.devices) follow the joint conventions measured on the
PartNet-Mobility training pool: buttons slide into their face along its normal by a few mm, dials
and caps turn about their own axis, knife blades slide along the handle or hinge at its end, pen
caps and buttons move along the pen, scissors hinge about the normal of their blades."""

import functools
import math

import numpy as np
import pytest

from jax3dc.factories import generate_object

SEEDS = range(6)
BUTTON_MAX_M = 0.01  # a button's travel: a few mm, always under 1 cm


@functools.lru_cache(maxsize=None)
def make(category, seed):
    return generate_object(category, seed)


def parts_named(obj, *names):
    return [(pid, obj.structure.nodes[pid].joint) for pid, name in obj.names.items() if name in names]


def outward_normal(obj, pid):
    """The normal of the parent's face that part `pid` stands on: the direction in which it sticks
    out of its parent's bounding box the most."""
    child, parent = obj.parts[pid].bounds, obj.parts[obj.structure.nodes[pid].parent].bounds
    beyond = np.concatenate([child[1] - parent[1], parent[0] - child[0]])  # +x +y +z, then -x -y -z
    k = int(np.argmax(beyond))
    normal = np.zeros(3)
    normal[k % 3] = 1.0 if k < 3 else -1.0
    return normal


def rotated(points, joint, angle):
    a = np.asarray(joint.axis) / np.linalg.norm(joint.axis)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    r = np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * (k @ k)
    return (np.asarray(points) - joint.pivot) @ r.T + joint.pivot


def parallel(axis, direction, tol=1e-3):
    d = np.asarray(direction, dtype=float)
    return abs(abs(np.dot(axis, d / np.linalg.norm(d))) - 1.0) < tol


def check_press_buttons(obj, names=("button", "shutter_button", "power_button")):
    """Every button slides into the face it sits on, along the face's normal, by under 1 cm."""
    found = 0
    for pid, joint in parts_named(obj, *names):
        assert joint is not None and joint.type == "slide", (obj.object_id, pid, joint)
        normal = outward_normal(obj, pid)
        assert np.allclose(joint.axis, -normal, atol=1e-6), (obj.object_id, pid, joint.axis, normal)
        lo, hi = joint.range
        assert lo == 0.0 and 0.0005 < hi * obj.scale_m_per_nu < BUTTON_MAX_M, (obj.object_id, pid, joint.range)
        found += 1
    return found


@pytest.mark.parametrize("category", ["camera", "coffee_machine", "remote"])
def test_buttons_slide_into_their_face(category):
    found = sum(check_press_buttons(make(category, seed)) for seed in SEEDS)
    assert found >= 2 * len(SEEDS)


def test_camera_conventions():
    lens_kinds = set()
    faces = set()
    for seed in SEEDS:
        obj = make("camera", seed)
        for pid, _ in parts_named(obj, "button", "shutter_button"):
            faces.add(tuple(outward_normal(obj, pid)))
        assert len(parts_named(obj, "shutter_button")) == 1
        ((_, dial),) = parts_named(obj, "mode_dial")
        assert dial.type == "hinge" and parallel(dial.axis, (0, 0, 1)) and dial.range[1] - dial.range[0] > 6.0
        for pid, joint in parts_named(obj, "lens", "lens_ring"):
            assert parallel(joint.axis, (0, 1, 0)), "the lens moves about or along its optical axis"
            assert joint.type == "hinge" or obj.names[pid] == "lens", (pid, joint)
            lens_kinds.add((obj.names[pid], joint.type))
        for pid, joint in parts_named(obj, "flash_lid", "screen"):
            if joint is None:
                continue
            body = obj.parts[obj.structure.nodes[pid].parent]
            before = obj.parts[pid].bounds.mean(axis=0)
            after = rotated([before], joint, joint.range[1])[0]
            assert np.linalg.norm(after - body.bounds.mean(axis=0)) > np.linalg.norm(before - body.bounds.mean(axis=0))
    assert faces == {(0.0, 0.0, 1.0), (0.0, 1.0, 0.0)}, "buttons on the top and the back"
    assert lens_kinds == {("lens", "hinge"), ("lens", "slide"), ("lens_ring", "hinge")}


def test_coffee_machine_conventions():
    for seed in SEEDS:
        obj = make("coffee_machine", seed)
        for pid, joint in parts_named(obj, "knob"):
            assert joint.type == "hinge" and np.allclose(joint.axis, outward_normal(obj, pid))
        ((pid, lid),) = parts_named(obj, "lid")
        before = obj.parts[pid].bounds.mean(axis=0)
        assert lid.type == "hinge" and rotated([before], lid, lid.range[1])[0][2] > before[2] + 0.02
        assert lid.pivot[1] > before[1], "hinged at its back edge"
        for pid, joint in parts_named(obj, "drip_tray", "water_tank"):
            assert joint.type == "slide" and joint.range[1] > 0.02
        for _, joint in parts_named(obj, "portafilter"):
            assert joint.type == "hinge" and parallel(joint.axis, (0, 0, 1))


def test_switch_conventions():
    kinds = set()
    for seed in range(10):
        obj = make("switch", seed)
        for pid, joint in parts_named(obj, "toggle", "rocker"):
            assert joint.type == "hinge" and parallel(joint.axis, (1, 0, 0))
            assert joint.range[0] == -joint.range[1] and 0 < joint.range[1] < 0.6
            kinds.add(obj.names[pid])
        for _, joint in parts_named(obj, "slider"):
            assert joint.type == "slide" and parallel(joint.axis, (0, 0, 1)), "slides along the plate"
            kinds.add("slider")
        if check_press_buttons(obj):
            kinds.add("button")
    assert kinds == {"toggle", "rocker", "slider", "button"}


def test_knife_blades_slide_along_the_handle_or_hinge_at_its_end():
    kinds = set()
    for seed in range(8):
        obj = make("knife", seed)
        ((pid, joint),) = parts_named(obj, "blade")
        handle = obj.parts[obj.structure.nodes[pid].parent].bounds
        extent = handle[1] - handle[0]
        long_axis, thin_axis = np.eye(3)[np.argmax(extent)], np.eye(3)[np.argmin(extent)]
        if joint.type == "slide":
            assert parallel(joint.axis, long_axis)
        else:
            assert joint.type == "hinge" and parallel(joint.axis, thin_axis), "about the blade's normal"
            k = int(np.argmax(extent))
            to_end = min(abs(joint.pivot[k] - handle[0][k]), abs(joint.pivot[k] - handle[1][k]))
            assert to_end < 0.15 * extent[k], "hinged at one end of the handle"
            assert joint.range[1] - joint.range[0] > 2.5
        kinds.add(joint.type)
    assert kinds == {"slide", "hinge"}


def test_bottle_caps_turn_about_the_vertical():
    turned = 0
    for seed in range(10):
        obj = make("bottle", seed)
        ((body_id, _),) = parts_named(obj, "bottle_body")
        centre = obj.parts[body_id].bounds.mean(axis=0)
        for pid, joint in parts_named(obj, "cap", "pump_head", "lid"):
            if joint is None:  # a flip lid's collar
                continue
            if obj.names[pid] == "lid":
                assert joint.type == "hinge" and parallel(joint.axis, (1, 0, 0))
            elif joint.type == "hinge":
                assert parallel(joint.axis, (0, 0, 1)) and np.allclose(joint.pivot[:2], centre[:2], atol=1e-3)
                assert joint.range[1] - joint.range[0] >= 2 * math.pi - 1e-3, "a full turn"
                turned += 1
            else:
                assert parallel(joint.axis, (0, 0, 1))
    assert turned >= 3


def test_pen_parts_move_along_the_pen():
    for seed in SEEDS:
        obj = make("pen", seed)
        (body,) = [m for pid, m in obj.parts.items() if obj.names[pid] == "pen_body"]
        long_axis = np.eye(3)[np.argmax(body.bounds[1] - body.bounds[0])]
        moving = parts_named(obj, "button", "cap")
        assert len(moving) == 1
        ((_, joint),) = moving
        assert joint.type == "slide" and parallel(joint.axis, long_axis) and parallel(long_axis, (0, 1, 0))
        clips = [m for pid, m in obj.parts.items() if obj.names[pid] == "clip"]
        assert all(m.bounds[1][2] > body.bounds[1][2] for m in clips)  # laid down clip up: it rests on its barrel


def test_scissors_hinge_about_the_normal_of_their_blades():
    for seed in SEEDS:
        obj = make("scissors", seed)
        blades = parts_named(obj, "blade")
        assert len(blades) == 2
        ((pid, joint),) = [(p, j) for p, j in blades if j is not None]
        a, b = (obj.parts[p].bounds for p, _ in blades)
        thin = np.eye(3)[np.argmin(a[1] - a[0])]
        assert joint.type == "hinge" and parallel(joint.axis, thin) and 0.3 < joint.range[1] < 1.6
        # the pivot lies where the two blades overlap, seen along the hinge axis
        lo, hi = np.maximum(a[0], b[0]), np.minimum(a[1], b[1])
        assert np.all(joint.pivot[:2] >= lo[:2] - 1e-3) and np.all(joint.pivot[:2] <= hi[:2] + 1e-3)
        # opening moves the blade tips apart
        tip = obj.parts[pid].vertices[np.argmin(obj.parts[pid].vertices[:, 1])]
        other = obj.parts[blades[0][0]].bounds.mean(axis=0)
        opened = rotated([tip], joint, joint.range[1])[0]
        assert np.linalg.norm(opened[:2] - other[:2]) > np.linalg.norm(tip[:2] - other[:2])
