"""Household objects: storage box, laptop, toilet, trash can, door, window, faucet, lamp, suitcase."""

from __future__ import annotations

import math

import numpy as np

from jax3dc.factories import kit
from jax3dc.factories.writer import JointSpec, ProgramWriter
from jax3dc.parameters import Chance as B, Choice as K, Count as C, Draws, Number as N, Schema


STORAGE_BOX = Schema("storage_box", (
    N("width", 0.25, 0.6), N("depth", 0.18, 0.4), N("height", 0.12, 0.35), B("wooden", 0.5), K("wood", kit.WOODS),
    K("plastic", kit.PLASTICS), N("lid_opening", 1.6, 2.0), K("latch_metal", kit.METALS), B("side_handles", 0.6)))


def storage_box(w: ProgramWriter, p: Draws) -> None:
    width, depth, height = p.number("width"), p.number("depth"), p.number("height")
    mat = kit.wood(w, p, "wood") if p.chance("wooden") else kit.plastic(w, p, "plastic")
    t = 0.012
    body = w.part("body", kit.open_top_tray(w, (width, depth, height), (0.0, 0.0, height / 2), t), mat)
    lid_t = 0.015
    lid = w.box((width + 0.01, depth + 0.01, lid_t), (0.0, 0.0, height + lid_t / 2))
    lid_id = w.part("lid", lid, mat, parent=body,
                    joint=JointSpec("hinge", (-1.0, 0.0, 0.0), (0.0, depth / 2 + 0.005, height), (0.0, p.number("lid_opening"))))
    latch_mat = kit.metal(w, p, "latch_metal")
    w.part("latch", w.box((0.03, 0.008, 0.03), (0.0, -depth / 2 - 0.009, height - 0.005)), latch_mat, parent=lid_id)
    if p.chance("side_handles"):
        for x in (-width / 2 - 0.012, width / 2 + 0.012):
            grip = w.box((0.024, min(0.1, depth * 0.5), 0.02), (x, 0.0, height * 0.7))
            w.part("side_handle", grip, latch_mat, parent=body, twin="side_handle")


LAPTOP = Schema("laptop", (
    N("width", 0.28, 0.4), N("depth", 0.19, 0.27), N("base_height", 0.012, 0.02),
    K("shell", ("silver aluminium", "space grey aluminium")), N("opened_deg", 95.0, 130.0)))


def laptop(w: ProgramWriter, p: Draws) -> None:
    width, depth, base_h = p.number("width"), p.number("depth"), p.number("base_height")
    shell, keys, screen = (w.material("Metal", p.choice("shell")),
                           w.material("Plastic", "black keycaps"), w.material("Glass", "glossy display"))
    base = w.part("base", w.bevel((width, depth, base_h), 0.003, (0.0, 0.0, base_h / 2)), shell)
    w.part("keyboard", w.box((width * 0.85, depth * 0.4, 0.002), (0.0, depth * 0.08, base_h + 0.001)), keys,
           parent=base)
    w.part("touchpad", w.box((width * 0.3, depth * 0.25, 0.001), (0.0, -depth * 0.3, base_h + 0.0005)), keys,
           parent=base)
    opened = p.number("opened_deg")
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


TOILET = Schema("toilet", (
    K("seat_plastic", kit.PLASTICS), N("bowl_radius", 0.17, 0.2), N("bowl_height", 0.36, 0.42), N("stretch", 1.2, 1.4),
    N("tank_width", 0.36, 0.45), N("tank_depth", 0.15, 0.2), N("tank_height", 0.3, 0.4), K("lever_metal", kit.METALS)))


def toilet(w: ProgramWriter, p: Draws) -> None:
    porcelain = w.material("Ceramic", "white porcelain")
    seat_mat = kit.plastic(w, p, "seat_plastic")
    bowl_r, bowl_h = p.number("bowl_radius"), p.number("bowl_height")
    stretch = p.number("stretch")
    profile = [(0.0, 0.0), (bowl_r * 0.6, 0.0), (bowl_r * 0.55, bowl_h * 0.45), (bowl_r, bowl_h * 0.85),
               (bowl_r, bowl_h), (0.0, bowl_h)]
    bowl = w.scale(w.lathe(profile, (0.0, 0.0, 0.0), segments=32), (1.0, stretch, 1.0), (0.0, 0.0, 0.0))
    bowl_id = w.part("bowl", bowl, porcelain)
    back = bowl_r * stretch
    tank_w, tank_d, tank_h = p.number("tank_width"), p.number("tank_depth"), p.number("tank_height")
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
    w.part("flush_lever", lever, kit.metal(w, p, "lever_metal"), parent=tank_id,
           joint=JointSpec("hinge", (0.0, 1.0, 0.0), (lever_x, lever_y - 0.006, lever_z), (0.0, 0.6)))


TRASH_CAN = Schema("trash_can", (
    N("height", 0.3, 0.7), B("metal_shell", 0.5), K("shell_metal", kit.METALS), K("shell_plastic", kit.PLASTICS),
    K("pedal_plastic", kit.PLASTICS), B("round", 0.5), N("radius", 0.12, 0.2), N("size_x", 0.22, 0.4),
    N("size_y", 0.2, 0.32), N("lid_opening", 1.3, 1.8), B("pedal", 0.7)))


def trash_can(w: ProgramWriter, p: Draws) -> None:
    height = p.number("height")
    shell, pedal_mat = (kit.metal(w, p, "shell_metal") if p.chance("metal_shell") else
                        kit.plastic(w, p, "shell_plastic")), kit.plastic(w, p, "pedal_plastic")
    t = 0.006
    lid_t = 0.02
    if p.chance("round"):
        r = p.number("radius")
        body = w.lathe([(0.0, 0.0), (r, 0.0), (r, height), (r - t, height), (r - t, t), (0.0, t)], (0.0, 0.0, 0.0),
                       segments=32)
        lid = w.cylinder(r + 0.005, lid_t, (0.0, 0.0, height + lid_t / 2), segments=32)
        half_d = r
    else:
        sx, sy = p.number("size_x"), p.number("size_y")
        body = kit.open_top_tray(w, (sx, sy, height), (0.0, 0.0, height / 2), t)
        lid = w.box((sx + 0.01, sy + 0.01, lid_t), (0.0, 0.0, height + lid_t / 2))
        half_d = sy / 2
    body_id = w.part("body", body, shell)
    w.part("lid", lid, shell, parent=body_id,
           joint=JointSpec("hinge", (-1.0, 0.0, 0.0), (0.0, half_d + 0.005, height), (0.0, p.number("lid_opening"))))
    if p.chance("pedal"):
        pedal = w.box((0.1, 0.08, 0.015), (0.0, -half_d - 0.04, 0.03))
        w.part("pedal", pedal, pedal_mat, parent=body_id,
               joint=JointSpec("hinge", (1.0, 0.0, 0.0), (0.0, -half_d, 0.03), (0.0, 0.35)))


DOOR = Schema("door", (
    B("double", 0.3), N("double_width", 1.2, 1.8), N("width", 0.75, 1.0), N("height", 1.95, 2.2),
    N("thickness", 0.035, 0.045), N("frame_depth", 0.1, 0.16), K("leaf_wood", kit.WOODS), K("frame_wood", kit.WOODS),
    K("handle_metal", kit.METALS), B("hinge_left", 0.5), N("swing", 1.4, 1.9), N("handle_height", 0.95, 1.05)))


def door(w: ProgramWriter, p: Draws) -> None:
    double = p.chance("double")
    width = p.number("double_width") if double else p.number("width")
    height, t = p.number("height"), p.number("thickness")
    frame_w, frame_d = 0.07, p.number("frame_depth")
    leaf_mat, frame_mat, handle_mat = kit.wood(w, p, "leaf_wood"), kit.wood(w, p, "frame_wood"), kit.metal(w, p, "handle_metal")
    outer = w.box((width + 2 * frame_w, frame_d, height + frame_w), (0.0, 0.0, (height + frame_w) / 2))
    opening = w.box((width, frame_d + 0.02, height + 0.01), (0.0, 0.0, (height - 0.01) / 2))
    frame = w.part("frame", w.difference(outer, opening), frame_mat)
    g = 0.003
    if double:
        leaves = [(-width / 2 + g, -g, "left"), (g, width / 2 - g, "right")]
    else:
        side = "left" if p.chance("hinge_left") else "right"
        leaves = [(-width / 2 + g, width / 2 - g, side)]
    swing = p.number("swing")
    y_face = -frame_d / 2  # leaves flush with the frame's front: they swing out past 90 degrees freely
    hz = p.number("handle_height")
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


WINDOW = Schema("window", (
    N("width", 0.6, 1.6), N("height", 0.6, 1.5), N("depth", 0.08, 0.14), B("wooden", 0.5), K("wood", kit.WOODS),
    K("plastic", kit.PLASTICS), K("glass", kit.GLASSES), K("style", ("casement", "sliding", "double_hung")),
    B("hinge_left", 0.5)))


def window(w: ProgramWriter, p: Draws) -> None:
    width, height = p.number("width"), p.number("height")
    frame_w, depth = 0.06, p.number("depth")
    frame_mat = kit.wood(w, p, "wood") if p.chance("wooden") else kit.plastic(w, p, "plastic")
    pane_mat = kit.glass(w, p, "glass")
    outer = w.box((width + 2 * frame_w, depth, height + 2 * frame_w), (0.0, 0.0, height / 2 + frame_w))
    hole = w.box((width, depth + 0.02, height), (0.0, 0.0, height / 2 + frame_w))
    frame = w.part("frame", w.difference(outer, hole), frame_mat)
    style = p.choice("style")
    bar, t, g = 0.05, 0.04, 0.003
    z0, z1 = frame_w, frame_w + height
    if style == "casement":
        pair = width > 0.9
        spans = [(-width / 2, 0.0, "left"), (0.0, width / 2, "right")] if pair else \
            [(-width / 2, width / 2, "left" if p.chance("hinge_left") else "right")]
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


FAUCET = Schema("faucet", (
    K("finish", ("chrome", "brushed nickel", "matte black steel")), K("lever_metal", kit.METALS),
    N("base_radius", 0.025, 0.035), N("body_height", 0.12, 0.3), N("reach", 0.12, 0.22), N("drop", 0.03, 0.08)))


def faucet(w: ProgramWriter, p: Draws) -> None:
    chrome, lever_mat = w.material("Metal", p.choice("finish")), kit.metal(w, p, "lever_metal")
    base_r, body_h = p.number("base_radius"), p.number("body_height")
    pipe_r = base_r * 0.6
    base = w.cylinder(base_r, 0.02, (0.0, 0.0, 0.01), segments=24)
    column = w.cylinder(pipe_r, body_h, (0.0, 0.0, 0.02 + body_h / 2), segments=24)
    body = w.part("body", w.combine(base, column), chrome)
    reach, drop = p.number("reach"), p.number("drop")
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


LAMP = Schema("lamp", (
    K("arm_metal", kit.METALS), B("metal_shade", 0.5), K("shade_metal", kit.METALS), K("shade_fabric", kit.FABRICS),
    N("base_radius", 0.07, 0.12), N("lower_arm", 0.25, 0.4), N("upper_arm", 0.25, 0.4), N("lower_angle_deg", 60.0, 80.0),
    N("upper_angle_deg", -30.0, 10.0), N("shade_height", 0.1, 0.16), N("shade_radius", 0.06, 0.1)))


def lamp(w: ProgramWriter, p: Draws) -> None:
    metal, shade_mat = kit.metal(w, p, "arm_metal"), (kit.metal(w, p, "shade_metal") if p.chance("metal_shade") else
                                                       kit.fabric(w, p, "shade_fabric"))
    base_r = p.number("base_radius")
    base = w.part("base", w.cylinder(base_r, 0.025, (0.0, 0.0, 0.0125), segments=32), metal)
    l1, l2 = p.number("lower_arm"), p.number("upper_arm")
    a1, a2 = math.radians(p.number("lower_angle_deg")), math.radians(p.number("upper_angle_deg"))
    p0 = (0.0, 0.0, 0.025 + 0.012)  # the lower arm's hinge pin rests on the base
    p1 = (0.0, -l1 * math.cos(a1), p0[2] + l1 * math.sin(a1))
    p2 = (0.0, p1[1] - l2 * math.cos(a2), p1[2] + l2 * math.sin(a2))
    # the lower arm stops short of the elbow, where the upper arm's hinge pin sits
    elbow = tuple(b - 0.022 * (b - a) / l1 for a, b in zip(p0, p1))
    base_pin = w.cylinder(0.012, 0.03, p0, axis="x", segments=12)
    shade_h, shade_r = p.number("shade_height"), p.number("shade_radius")
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


SUITCASE = Schema("suitcase", (
    N("width", 0.35, 0.5), N("depth", 0.2, 0.3), N("height", 0.5, 0.8),
    K("shell", ("hard polycarbonate shell", "navy ABS shell", "red ABS shell")), K("handle_metal", kit.METALS)))


def suitcase(w: ProgramWriter, p: Draws) -> None:
    width, depth, height = p.number("width"), p.number("depth"), p.number("height")
    shell = w.material("Plastic", p.choice("shell"))
    rubber, metal = w.material("Rubber", "black rubber"), kit.metal(w, p, "handle_metal")
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
