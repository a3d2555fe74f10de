"""Household objects: storage box, laptop, toilet, trash can, door, window, faucet, lamp, suitcase."""

from __future__ import annotations

import math

import numpy as np

from data_pipeline.factories import kit
from data_pipeline.factories.kit import u
from data_pipeline.factories.writer import JointSpec, ProgramWriter


def storage_box(w: ProgramWriter, rng: np.random.Generator) -> None:
    width, depth, height = u(rng, 0.25, 0.6), u(rng, 0.18, 0.4), u(rng, 0.12, 0.35)
    mat = kit.wood(w, rng) if rng.random() < 0.5 else kit.plastic(w, rng)
    t = 0.012
    body = w.part("body", kit.open_top_tray(w, (width, depth, height), (0.0, 0.0, height / 2), t), mat)
    lid_t = 0.015
    lid = w.box((width + 0.01, depth + 0.01, lid_t), (0.0, 0.0, height + lid_t / 2))
    lid_id = w.part("lid", lid, mat, parent=body,
                    joint=JointSpec("hinge", (-1.0, 0.0, 0.0), (0.0, depth / 2 + 0.005, height), (0.0, u(rng, 1.6, 2.0))))
    latch_mat = kit.metal(w, rng)
    w.part("latch", w.box((0.03, 0.008, 0.03), (0.0, -depth / 2 - 0.009, height - 0.005)), latch_mat, parent=lid_id)
    if rng.random() < 0.6:
        for x in (-width / 2 - 0.012, width / 2 + 0.012):
            grip = w.box((0.024, min(0.1, depth * 0.5), 0.02), (x, 0.0, height * 0.7))
            w.part("side_handle", grip, latch_mat, parent=body, twin="side_handle")


def laptop(w: ProgramWriter, rng: np.random.Generator) -> None:
    width, depth, base_h = u(rng, 0.28, 0.4), u(rng, 0.19, 0.27), u(rng, 0.012, 0.02)
    shell, keys, screen = (w.material("Metal", kit.pick(rng, ("silver aluminium", "space grey aluminium"))),
                           w.material("Plastic", "black keycaps"), w.material("Glass", "glossy display"))
    base = w.part("base", w.bevel((width, depth, base_h), 0.003, (0.0, 0.0, base_h / 2)), shell)
    w.part("keyboard", w.box((width * 0.85, depth * 0.4, 0.002), (0.0, depth * 0.08, base_h + 0.001)), keys,
           parent=base)
    w.part("touchpad", w.box((width * 0.3, depth * 0.25, 0.001), (0.0, -depth * 0.3, base_h + 0.0005)), keys,
           parent=base)
    opened = u(rng, 95.0, 130.0)
    lid_t, keys_h = 0.006, 0.002
    rest = base_h + keys_h  # closed, the lid rests on the keyboard
    hinge = (0.0, depth / 2, rest)
    shell_box = w.box((width, depth, lid_t), (0.0, 0.0, rest + lid_t / 2))
    recess = w.box((width * 0.9, depth * 0.85, 0.0025), (0.0, 0.0, rest + 0.00025))  # open towards the keys
    lid = w.rotate(w.difference(shell_box, recess), -opened, "x", hinge)
    lid_range = (-round(math.radians(170.0 - opened), 3), round(math.radians(opened), 3))
    lid_id = w.part("screen_lid", lid, shell, parent=base,
                    joint=JointSpec("hinge", (1.0, 0.0, 0.0), hinge, lid_range))
    # the display lies in the recess, 0.2 mm clear of its faces so rounding never makes them overlap
    panel = w.box((width * 0.9 - 0.0004, depth * 0.85 - 0.0004, 0.001), (0.0, 0.0, rest + 0.0008))
    w.part("display", w.rotate(panel, -opened, "x", hinge), screen, parent=lid_id)


def toilet(w: ProgramWriter, rng: np.random.Generator) -> None:
    porcelain = w.material("Ceramic", "white porcelain")
    seat_mat = kit.plastic(w, rng)
    bowl_r, bowl_h = u(rng, 0.17, 0.2), u(rng, 0.36, 0.42)
    stretch = u(rng, 1.2, 1.4)
    profile = [(0.0, 0.0), (bowl_r * 0.6, 0.0), (bowl_r * 0.55, bowl_h * 0.45), (bowl_r, bowl_h * 0.85),
               (bowl_r, bowl_h), (0.0, bowl_h)]
    bowl = w.scale(w.lathe(profile, (0.0, 0.0, 0.0), segments=32), (1.0, stretch, 1.0), (0.0, 0.0, 0.0))
    bowl_id = w.part("bowl", bowl, porcelain)
    back = bowl_r * stretch
    tank_w, tank_d, tank_h = u(rng, 0.36, 0.45), u(rng, 0.15, 0.2), u(rng, 0.3, 0.4)
    tank_y = back + tank_d / 2 + 0.005  # behind the seat and lid, which reach y = back
    tank = w.bevel((tank_w, tank_d, tank_h), 0.01, (0.0, tank_y, bowl_h + tank_h / 2 - 0.05))
    tank_id = w.part("tank", tank, porcelain, parent=bowl_id)
    seat_half = bowl_r * 0.2 * 0.35  # the torus tube flattened to 35 %
    seat = w.scale(w.torus(bowl_r * 0.8, bowl_r * 0.2, (0.0, 0.0, bowl_h + seat_half), major_segments=32,
                           minor_segments=8), (1.0, stretch, 0.35), (0.0, 0.0, bowl_h + seat_half))
    seat_top = bowl_h + 2 * seat_half
    # up to 83 degrees: the raised seat and lid stay clear of the tank and its lever
    seat_id = w.part("seat", seat, seat_mat, parent=bowl_id,
                     joint=JointSpec("hinge", (-1.0, 0.0, 0.0), (0.0, back - 0.02, seat_top), (0.0, 1.45)))
    lid_t = 0.015
    lid = w.scale(w.cylinder(bowl_r, lid_t, (0.0, 0.0, seat_top + lid_t / 2), segments=32), (1.0, stretch, 1.0),
                  (0.0, 0.0, seat_top))
    w.part("lid", lid, seat_mat, parent=seat_id,  # lies on the seat: raising the seat raises the lid too
           joint=JointSpec("hinge", (-1.0, 0.0, 0.0), (0.0, back - 0.01, seat_top + lid_t), (0.0, 1.45)))
    lever_x = -tank_w / 2 + 0.05
    lever_z = bowl_h + tank_h - 0.12
    lever_y = tank_y - tank_d / 2
    lever = w.box((0.06, 0.012, 0.012), (lever_x + 0.03, lever_y - 0.006, lever_z))
    w.part("flush_lever", lever, kit.metal(w, rng), parent=tank_id,
           joint=JointSpec("hinge", (0.0, 1.0, 0.0), (lever_x, lever_y - 0.006, lever_z), (0.0, 0.6)))


def trash_can(w: ProgramWriter, rng: np.random.Generator) -> None:
    height = u(rng, 0.3, 0.7)
    shell, pedal_mat = kit.metal(w, rng) if rng.random() < 0.5 else kit.plastic(w, rng), kit.plastic(w, rng)
    t = 0.006
    lid_t = 0.02
    if rng.random() < 0.5:
        r = u(rng, 0.12, 0.2)
        body = w.lathe([(0.0, 0.0), (r, 0.0), (r, height), (r - t, height), (r - t, t), (0.0, t)], (0.0, 0.0, 0.0),
                       segments=32)
        lid = w.cylinder(r + 0.005, lid_t, (0.0, 0.0, height + lid_t / 2), segments=32)
        half_d = r
    else:
        sx, sy = u(rng, 0.22, 0.4), u(rng, 0.2, 0.32)
        body = kit.open_top_tray(w, (sx, sy, height), (0.0, 0.0, height / 2), t)
        lid = w.box((sx + 0.01, sy + 0.01, lid_t), (0.0, 0.0, height + lid_t / 2))
        half_d = sy / 2
    body_id = w.part("body", body, shell)
    w.part("lid", lid, shell, parent=body_id,
           joint=JointSpec("hinge", (-1.0, 0.0, 0.0), (0.0, half_d + 0.005, height), (0.0, u(rng, 1.3, 1.8))))
    if rng.random() < 0.7:
        pedal = w.box((0.1, 0.08, 0.015), (0.0, -half_d - 0.04, 0.03))
        w.part("pedal", pedal, pedal_mat, parent=body_id,
               joint=JointSpec("hinge", (1.0, 0.0, 0.0), (0.0, -half_d, 0.03), (0.0, 0.35)))


def door(w: ProgramWriter, rng: np.random.Generator) -> None:
    double = rng.random() < 0.3
    width = u(rng, 1.2, 1.8) if double else u(rng, 0.75, 1.0)
    height, t = u(rng, 1.95, 2.2), u(rng, 0.035, 0.045)
    frame_w, frame_d = 0.07, u(rng, 0.1, 0.16)
    leaf_mat, frame_mat, handle_mat = kit.wood(w, rng), kit.wood(w, rng), kit.metal(w, rng)
    outer = w.box((width + 2 * frame_w, frame_d, height + frame_w), (0.0, 0.0, (height + frame_w) / 2))
    opening = w.box((width, frame_d + 0.02, height + 0.01), (0.0, 0.0, (height - 0.01) / 2))
    frame = w.part("frame", w.difference(outer, opening), frame_mat)
    g = 0.003
    if double:
        leaves = [(-width / 2 + g, -g, "left"), (g, width / 2 - g, "right")]
    else:
        side = "left" if rng.random() < 0.5 else "right"
        leaves = [(-width / 2 + g, width / 2 - g, side)]
    swing = u(rng, 1.4, 1.9)
    y_face = -frame_d / 2  # leaves flush with the frame's front: they swing out past 90 degrees freely
    hz = u(rng, 0.95, 1.05)
    for x0, x1, side in leaves:
        leaf = w.box((x1 - x0, t, height - g), ((x0 + x1) / 2, y_face + t / 2, (height - g) / 2))
        hinge_x = x0 if side == "left" else x1
        axis = (0.0, 0.0, -1.0) if side == "left" else (0.0, 0.0, 1.0)
        leaf_id = w.part("leaf", leaf, leaf_mat, parent=frame, twin="leaf",
                         joint=JointSpec("hinge", axis, (hinge_x, y_face, height / 2), (0.0, swing)))
        free = 1.0 if side == "left" else -1.0  # direction from the hinge to the free edge
        hx = (x1 - 0.07) if side == "left" else (x0 + 0.07)
        hub = w.cylinder(0.025, 0.015, (hx, y_face - 0.0075, hz), axis="y", segments=16)
        grip = w.box((0.12, 0.018, 0.018), (hx - free * 0.06, y_face - 0.045, hz))
        stem = w.cylinder(0.008, 0.04, (hx, y_face - 0.02, hz), axis="y", segments=12)
        w.part("lever_handle", w.combine(hub, stem, grip), handle_mat, parent=leaf_id,
               joint=JointSpec("hinge", (0.0, -free, 0.0), (hx, y_face - 0.0075, hz), (0.0, 0.7)))


def _sash(w, x0, x1, z0, z1, y, t, bar):
    frame = w.box((x1 - x0, t, z1 - z0), ((x0 + x1) / 2, y, (z0 + z1) / 2))
    hole = w.box((x1 - x0 - 2 * bar, t + 0.02, z1 - z0 - 2 * bar), ((x0 + x1) / 2, y, (z0 + z1) / 2))
    pane = w.box((x1 - x0 - 2 * bar, 0.006, z1 - z0 - 2 * bar), ((x0 + x1) / 2, y, (z0 + z1) / 2))
    return w.difference(frame, hole), pane


def window(w: ProgramWriter, rng: np.random.Generator) -> None:
    width, height = u(rng, 0.6, 1.6), u(rng, 0.6, 1.5)
    frame_w, depth = 0.06, u(rng, 0.08, 0.14)
    frame_mat = kit.wood(w, rng) if rng.random() < 0.5 else kit.plastic(w, rng)
    pane_mat = kit.glass(w, rng)
    outer = w.box((width + 2 * frame_w, depth, height + 2 * frame_w), (0.0, 0.0, height / 2 + frame_w))
    hole = w.box((width, depth + 0.02, height), (0.0, 0.0, height / 2 + frame_w))
    frame = w.part("frame", w.difference(outer, hole), frame_mat)
    style = ("casement", "sliding", "double_hung")[int(rng.integers(3))]
    bar, t, g = 0.05, 0.04, 0.003
    z0, z1 = frame_w, frame_w + height
    if style == "casement":
        pair = width > 0.9
        spans = [(-width / 2, 0.0, "left"), (0.0, width / 2, "right")] if pair else \
            [(-width / 2, width / 2, "left" if rng.random() < 0.5 else "right")]
        for x0, x1, side in spans:
            sash, pane = _sash(w, x0 + g, x1 - g, z0 + g, z1 - g, -depth / 2 + t / 2, t, bar)
            hinge_x = x0 + g if side == "left" else x1 - g
            axis = (0.0, 0.0, -1.0) if side == "left" else (0.0, 0.0, 1.0)
            sid = w.part("sash", sash, frame_mat, parent=frame, twin="sash",
                         joint=JointSpec("hinge", axis, (hinge_x, -depth / 2, (z0 + z1) / 2), (0.0, 1.571)))
            w.part("pane", pane, pane_mat, parent=sid)
    elif style == "sliding":
        mid = 0.0
        for (x0, x1), y, moving in (((-width / 2, mid + 0.03), -t / 2 - 0.002, False),
                                    ((mid - 0.03, width / 2), t / 2 + 0.002, True)):
            sash, pane = _sash(w, x0 + g, x1 - g, z0 + g, z1 - g, y, t, bar)
            joint = JointSpec("slide", (-1.0, 0.0, 0.0), ((x0 + x1) / 2, y, (z0 + z1) / 2), (0.0, width / 2 - 0.06)) \
                if moving else None
            sid = w.part("sash", sash, frame_mat, parent=frame, joint=joint, twin="sash")
            w.part("pane", pane, pane_mat, parent=sid)
    else:
        mid = (z0 + z1) / 2
        for (za, zb), y, moving in (((z0, mid + 0.03), -t / 2 - 0.002, True), ((mid - 0.03, z1), t / 2 + 0.002, False)):
            sash, pane = _sash(w, -width / 2 + g, width / 2 - g, za + g, zb - g, y, t, bar)
            joint = JointSpec("slide", (0.0, 0.0, 1.0), (0.0, y, (za + zb) / 2), (0.0, height / 2 - 0.06)) \
                if moving else None
            sid = w.part("sash", sash, frame_mat, parent=frame, joint=joint, twin="sash")
            w.part("pane", pane, pane_mat, parent=sid)


def faucet(w: ProgramWriter, rng: np.random.Generator) -> None:
    chrome, lever_mat = w.material("Metal", kit.pick(rng, ("chrome", "brushed nickel", "matte black steel"))), \
        kit.metal(w, rng)
    base_r, body_h = u(rng, 0.025, 0.035), u(rng, 0.12, 0.3)
    pipe_r = base_r * 0.6
    base = w.cylinder(base_r, 0.02, (0.0, 0.0, 0.01), segments=24)
    column = w.cylinder(pipe_r, body_h, (0.0, 0.0, 0.02 + body_h / 2), segments=24)
    body = w.part("body", w.combine(base, column), chrome)
    reach, drop = u(rng, 0.12, 0.22), u(rng, 0.03, 0.08)
    top = 0.02 + body_h
    arc = [(0.0, 0.0, top), (0.0, 0.0, top + 0.01)]  # leaves the column straight up
    for k in range(1, 8):
        a = math.pi * k / 8
        arc.append((0.0, -reach / 2 + reach / 2 * math.cos(a), top + reach / 2 * math.sin(a) * 0.6))
    arc.append((0.0, -reach, top - drop))
    spout = w.sweep(arc, pipe_r * 0.8, segments=12)
    w.part("spout", spout, chrome, parent=body,
           joint=JointSpec("hinge", (0.0, 0.0, 1.0), (0.0, 0.0, top), (-0.785, 0.785)))
    lever_z = 0.02 + body_h * 0.7
    hub = w.cylinder(pipe_r * 0.9, 0.02, (0.0, pipe_r + 0.01, lever_z), axis="y", segments=16)
    arm = kit.rod(w, (0.0, pipe_r + 0.02, lever_z), (0.0, pipe_r + 0.02 + 0.06, lever_z + 0.03), 0.005)
    # a side lever turns about its hub's own axis: the hub spins in place beside the column (about
    # the column's tangent its end face swung 8 mm into the column and jammed)
    w.part("lever", w.combine(hub, arm), lever_mat, parent=body,
           joint=JointSpec("hinge", (0.0, 1.0, 0.0), (0.0, pipe_r + 0.01, lever_z), (0.0, 0.6)))


def lamp(w: ProgramWriter, rng: np.random.Generator) -> None:
    metal, shade_mat = kit.metal(w, rng), kit.metal(w, rng) if rng.random() < 0.5 else kit.fabric(w, rng)
    base_r = u(rng, 0.07, 0.12)
    base = w.part("base", w.cylinder(base_r, 0.025, (0.0, 0.0, 0.0125), segments=32), metal)
    l1, l2 = u(rng, 0.25, 0.4), u(rng, 0.25, 0.4)
    a1, a2 = math.radians(u(rng, 60.0, 80.0)), math.radians(u(rng, -30.0, 10.0))
    p0 = (0.0, 0.0, 0.025 + 0.012)  # the lower arm's hinge pin rests on the base
    p1 = (0.0, -l1 * math.cos(a1), p0[2] + l1 * math.sin(a1))
    p2 = (0.0, p1[1] - l2 * math.cos(a2), p1[2] + l2 * math.sin(a2))
    # the lower arm stops short of the elbow, where the upper arm's hinge pin sits
    elbow = tuple(b - 0.022 * (b - a) / l1 for a, b in zip(p0, p1))
    base_pin = w.cylinder(0.012, 0.03, p0, axis="x", segments=12)
    shade_h, shade_r = u(rng, 0.1, 0.16), u(rng, 0.06, 0.1)
    drop1, drop2 = _lamp_head_drops(p0[2], l1, a1, l2, a2, math.hypot(shade_h, shade_r) + 0.011)
    lower = w.part("lower_arm", w.combine(base_pin, kit.rod(w, p0, elbow, 0.01)), metal, parent=base,
                   joint=JointSpec("hinge", (1.0, 0.0, 0.0), p0, (-0.6, drop1)))
    pin = w.cylinder(0.012, 0.03, p1, axis="x", segments=12)
    upper = w.part("upper_arm", w.combine(pin, kit.rod(w, p1, p2, 0.008)), metal, parent=lower,
                   joint=JointSpec("hinge", (1.0, 0.0, 0.0), p1, (-0.8, drop2)))  # +: the head drops
    shade = w.cone(shade_r, shade_r * 0.3, shade_h, (0.0, p2[1], p2[2] - shade_h / 2 - 0.011), segments=24)
    tilt = _shade_tilt(shade_r, shade_r * 0.3, shade_h, 0.011, (math.cos(a2), -math.sin(a2)), l2, 0.008)
    w.part("shade", shade, shade_mat, parent=upper,  # pivots about the top of the shade, under the arm's end
           joint=JointSpec("hinge", (1.0, 0.0, 0.0), (0.0, p2[1], p2[2] - 0.011), (-0.6, tilt)))


LAMP_SHADE_CLEARANCE_M = 0.01  # the shade stops this far above the desk, whatever the arms' poses


def _shade_tilt(bottom_r: float, top_r: float, height: float, gap: float, arm_dir: tuple[float, float],
                arm: float, rod_r: float) -> float:
    """The largest tilt (rad, at most 0.6) of a conical shade, hung ``gap`` below the upper arm's end,
    towards the arm (+ about x) before the cone meets the arm's rod (``arm_dir``: the rod's (y, z)
    direction from that end; any overlap at rest is kept, not deepened): the arm is the shade's stop."""
    h, phi = np.meshgrid(np.linspace(0.0, height, 9), np.linspace(0.0, 2 * math.pi, 48, endpoint=False), indexing="ij")
    radius = top_r + (bottom_r - top_r) * h / height
    xs, ys, zs = (radius * np.cos(phi)).ravel(), (radius * np.sin(phi)).ravel(), -h.ravel()
    dy, dz = arm_dir

    def clearance(t: float) -> float:
        y, z = ys * math.cos(t) - zs * math.sin(t), ys * math.sin(t) + zs * math.cos(t) - gap  # from the arm's end
        along = np.clip(y * dy + z * dz, 0.0, arm)
        return float(np.min(np.sqrt(xs ** 2 + (y - along * dy) ** 2 + (z - along * dz) ** 2))) - rod_r

    floor = min(clearance(0.0), 0.0)
    best = 0.0
    for t in np.linspace(0.0, 0.6, 61):
        if clearance(float(t)) < floor:
            break
        best = float(t)
    return round(best, 2)


def _lamp_head_drops(pin_z: float, l1: float, a1: float, l2: float, a2: float, head_reach: float) -> tuple[float, float]:
    """The largest forward (+, head-lowering) angles of the lower and upper arm (rad, at most 0.6
    and 0.3) with which the shade, anywhere within ``head_reach`` of the upper arm's end, stays
    LAMP_SHADE_CLEARANCE_M above the desk in every pose of both arms: a real lamp's arms stop
    where the head would meet the desk. The upper arm's stop is chosen first with the lower arm at
    rest, then the lower arm's with the upper arm at that stop (the lowest head)."""
    def head_low(t1: float, t2: float) -> float:
        return pin_z + l1 * math.sin(a1 - t1) + l2 * math.sin(a2 - t1 - t2) - head_reach

    def largest(ok) -> float:
        return max((t for t in np.linspace(0.0, 0.6, 61) if ok(t)), default=0.0)

    drop2 = largest(lambda t: t <= 0.3 + 1e-9 and head_low(0.0, t) >= LAMP_SHADE_CLEARANCE_M)
    drop1 = largest(lambda t: head_low(t, drop2) >= LAMP_SHADE_CLEARANCE_M)
    return round(float(drop1), 2), round(float(drop2), 2)


def suitcase(w: ProgramWriter, rng: np.random.Generator) -> None:
    width, depth, height = u(rng, 0.35, 0.5), u(rng, 0.2, 0.3), u(rng, 0.5, 0.8)
    shell = w.material("Plastic", kit.pick(rng, ("hard polycarbonate shell", "navy ABS shell", "red ABS shell")))
    rubber, metal = w.material("Rubber", "black rubber"), kit.metal(w, rng)
    wheel_r = 0.03
    z0 = 2 * wheel_r
    body = w.part("shell", w.bevel((width, depth, height), 0.03, (0.0, 0.0, z0 + height / 2)), shell)
    top = z0 + height
    rail_x = width * 0.3
    rails = [w.cylinder(0.008, height * 0.6, (x, depth / 2 + 0.012, top - height * 0.3 + 0.02), segments=12)
             for x in (-rail_x, rail_x)]
    grip = w.box((2 * rail_x + 0.03, 0.025, 0.025), (0.0, depth / 2 + 0.012, top + 0.03))
    w.part("telescopic_handle", w.combine(*rails, grip), metal, parent=body,
           joint=JointSpec("slide", (0.0, 0.0, 1.0), (0.0, depth / 2 + 0.012, top + 0.03), (0.0, round(height * 0.5, 3))))
    carry = kit.bar_handle(w, 0.0, 0.0, 0.0, 0.12, vertical=False, standoff=0.03, radius=0.008)
    carry = w.rotate(carry, -90.0, "x", (0.0, 0.0, 0.0))
    w.part("carry_handle", w.translate(carry, (0.0, 0.0, top)), rubber, parent=body)
    for x, y in kit.corners(width / 2 - 0.04, depth / 2 - 0.04):
        wheel = w.cylinder(wheel_r, 0.02, (x, y, wheel_r), axis="x", segments=16)
        w.part("wheel", wheel, rubber, parent=body, twin="wheel",
               joint=JointSpec("hinge", (1.0, 0.0, 0.0), (x, y, wheel_r), kit.full_turn()))
