"""Seating, sleeping and work furniture: table, chair, stool, office chair, sofa, bed, desk."""

from __future__ import annotations

import math

from jax3dc.factories import kit
from jax3dc.factories.writer import JointSpec, ProgramWriter
from jax3dc.parameters import Chance as B, Choice as K, Count as C, Draws, Number as N, Schema


TABLE = Schema("table", (
    N("height", 0.7, 0.78), N("top_thickness", 0.025, 0.045), K("wood", kit.WOODS), B("wooden_legs", 0.6),
    K("leg_metal", kit.METALS), B("round", 0.3), N("radius", 0.4, 0.6), N("width", 0.8, 1.8), N("depth", 0.6, 1.0),
    N("inset", 0.04, 0.1), N("leg", 0.04, 0.07), B("round_legs", 0.4), B("aprons", 0.5)))


def table(w: ProgramWriter, p: Draws) -> None:
    height, top_t = p.number("height"), p.number("top_thickness")
    mat = kit.wood(w, p, "wood")
    leg_mat = mat if p.chance("wooden_legs") else kit.metal(w, p, "leg_metal")
    if p.chance("round"):
        r = p.number("radius")
        top = w.part("top", w.cylinder(r, top_t, (0.0, 0.0, height - top_t / 2), segments=48), mat)
        stem = w.cylinder(0.04, height - top_t - 0.03, (0.0, 0.0, (height - top_t + 0.03) / 2), segments=16)
        foot = w.cylinder(r * 0.5, 0.03, (0.0, 0.0, 0.015), segments=32)
        w.part("pedestal", w.combine(stem, foot), leg_mat, parent=top)
        return
    width, depth = p.number("width"), p.number("depth")
    top = w.part("top", w.box((width, depth, top_t), (0.0, 0.0, height - top_t / 2)), mat)
    inset, leg = p.number("inset"), p.number("leg")
    kit.legs(w, top, kit.corners(width / 2 - inset, depth / 2 - inset), height - top_t, 0.0, leg, leg_mat,
             round_legs=p.chance("round_legs"))
    if p.chance("aprons"):
        apron_h = 0.08
        z = height - top_t - apron_h / 2
        for y in (-depth / 2 + inset, depth / 2 - inset):
            w.part("apron", w.box((width - 2 * inset - leg, 0.02, apron_h), (0.0, y, z)), mat, parent=top, twin="apron")


CHAIR = Schema("chair", (
    N("seat_height", 0.42, 0.48), N("width", 0.4, 0.5), N("depth", 0.4, 0.5), N("back_height", 0.35, 0.5),
    N("tilt_deg", 0.0, 12.0), K("wood", kit.WOODS), B("cushioned", 0.5), K("fabric", kit.FABRICS), N("leg", 0.03, 0.045),
    B("round_legs", 0.5), B("armrests", 0.4), N("arm_height", 0.18, 0.25)))


def chair(w: ProgramWriter, p: Draws) -> None:
    seat_h, width, depth = p.number("seat_height"), p.number("width"), p.number("depth")
    back_h, tilt = p.number("back_height"), p.number("tilt_deg")
    mat = kit.wood(w, p, "wood")
    cushion = kit.fabric(w, p, "fabric") if p.chance("cushioned") else mat
    seat_t = 0.04
    seat = w.part("seat", w.box((width, depth, seat_t), (0.0, 0.0, seat_h - seat_t / 2)), cushion)
    leg = p.number("leg")
    kit.legs(w, seat, kit.corners(width / 2 - leg / 2, depth / 2 - leg / 2), seat_h - seat_t, 0.0, leg, mat,
             round_legs=p.chance("round_legs"))
    back_t = 0.025
    hinge = (0.0, depth / 2 - back_t / 2, seat_h)
    back = w.rotate(w.box((width, back_t, back_h), (0.0, depth / 2 - back_t / 2, seat_h + back_h / 2)), tilt, "x", hinge)
    w.part("backrest", back, mat, parent=seat)
    if p.chance("armrests"):
        arm_z = seat_h + p.number("arm_height")
        for x in (-width / 2 - 0.02, width / 2 + 0.02):
            post = w.box((0.03, 0.03, arm_z - seat_h + 0.02), (x, -depth / 2 + 0.05, (seat_h + arm_z) / 2))
            rest = w.box((0.05, depth * 0.85, 0.025), (x, 0.0, arm_z))
            w.part("armrest", w.combine(post, rest), mat, parent=seat, twin="armrest")


STOOL = Schema("stool", (
    N("height", 0.45, 0.8), N("radius", 0.15, 0.22), K("wood", kit.WOODS), K("metal", kit.METALS), B("legged", 0.5),
    C("legs", 3, 4), N("splay", 0.02, 0.08)))


def stool(w: ProgramWriter, p: Draws) -> None:
    height, r = p.number("height"), p.number("radius")
    mat, metal = kit.wood(w, p, "wood"), kit.metal(w, p, "metal")
    seat_t = 0.035
    if p.chance("legged"):
        seat = w.part("seat", w.cylinder(r, seat_t, (0.0, 0.0, height - seat_t / 2), segments=32), mat)
        n = p.count("legs")
        splay = p.number("splay")
        for k in range(n):
            a = 2 * math.pi * k / n + math.pi / 4
            top = (0.7 * r * math.cos(a), 0.7 * r * math.sin(a), height - seat_t)
            foot = ((0.7 * r + splay) * math.cos(a), (0.7 * r + splay) * math.sin(a), 0.0)
            w.part("leg", kit.rod(w, foot, top, 0.015), mat, parent=seat, twin="leg")
        ring_z = height * 0.3
        leg_axis_r = 0.7 * r + splay * (1 - ring_z / (height - seat_t))  # legs' distance from the centre there
        ring = w.torus(leg_axis_r + 0.015 + 0.008 + 0.002, 0.008, (0.0, 0.0, ring_z), minor_segments=8)
        w.part("footrest", ring, metal, parent=seat)  # rests against the legs' outer sides
        return
    base = w.part("base", w.cylinder(r * 1.1, 0.03, (0.0, 0.0, 0.015), segments=32), metal)
    column = w.part("column", w.cylinder(0.025, height - seat_t - 0.03, (0.0, 0.0, (height - seat_t + 0.03) / 2),
                                         segments=16), metal, parent=base)
    w.part("seat", w.cylinder(r, seat_t, (0.0, 0.0, height - seat_t / 2), segments=32), mat, parent=column,
           joint=JointSpec("hinge", (0.0, 0.0, 1.0), (0.0, 0.0, height - seat_t), kit.full_turn()))


OFFICE_CHAIR = Schema("office_chair", (
    N("seat_height", 0.44, 0.52), N("width", 0.45, 0.52), N("depth", 0.42, 0.5), K("plastic", kit.PLASTICS),
    K("fabric", kit.FABRICS), K("metal", kit.METALS), N("leg_length", 0.28, 0.34), N("back_height", 0.4, 0.6),
    B("armrests", 0.6)))


def office_chair(w: ProgramWriter, p: Draws) -> None:
    seat_h, width, depth = p.number("seat_height"), p.number("width"), p.number("depth")
    plastic, cushion, metal = kit.plastic(w, p, "plastic"), kit.fabric(w, p, "fabric"), kit.metal(w, p, "metal")
    rubber = w.material("Rubber", "black rubber")
    leg_len, caster_r = p.number("leg_length"), 0.025
    spoke = w.box((leg_len, 0.04, 0.03), (leg_len / 2, 0.0, 2 * caster_r + 0.015))
    base = w.part("star_base", w.radial_array(spoke, 5, (0.0, 0.0, 0.0)), plastic)
    caster = w.sphere(caster_r, (leg_len - 0.02, 0.0, caster_r), segments=12, rings=6)
    w.part("casters", w.radial_array(caster, 5, (0.0, 0.0, 0.0)), rubber, parent=base)
    col_bottom = 2 * caster_r + 0.03
    col_h = seat_h - 0.06 - col_bottom
    column = w.part("gas_lift", w.cylinder(0.025, col_h, (0.0, 0.0, col_bottom + col_h / 2), segments=16), metal,
                    parent=base, joint=JointSpec("slide", (0.0, 0.0, 1.0), (0.0, 0.0, col_bottom + col_h), (0.0, 0.1)))
    seat_t = 0.06
    seat = w.part("seat", w.bevel((width, depth, seat_t), 0.015, (0.0, 0.0, seat_h - seat_t / 2)), cushion,
                  parent=column,
                  joint=JointSpec("hinge", (0.0, 0.0, 1.0), (0.0, 0.0, seat_h - seat_t), kit.full_turn()))
    back_h = p.number("back_height")
    back = w.bevel((width * 0.9, 0.05, back_h), 0.012, (0.0, depth / 2 + 0.04, seat_h + 0.05 + back_h / 2))
    arm = w.box((0.02, 0.04, 0.06), (0.0, depth / 2 + 0.02, seat_h + 0.02))
    w.part("backrest", w.combine(back, arm), cushion, parent=seat)
    if p.chance("armrests"):
        for x in (-width / 2 - 0.03, width / 2 + 0.03):
            post = w.box((0.025, 0.03, 0.2), (x, 0.0, seat_h + 0.08))
            pad = w.box((0.06, depth * 0.6, 0.025), (x, 0.0, seat_h + 0.19))
            w.part("armrest", w.combine(post, pad), plastic, parent=seat, twin="armrest")


SOFA = Schema("sofa", (
    C("seats", 2, 3), N("seat_width", 0.55, 0.7), N("depth", 0.8, 0.95), N("arm_width", 0.12, 0.22),
    N("leg_height", 0.05, 0.12), K("fabric", kit.FABRICS), K("leg_wood", kit.WOODS), N("back_thickness", 0.15, 0.22),
    N("back_height", 0.35, 0.5), N("arm_height", 0.15, 0.25), N("cushion_height", 0.1, 0.16)))


def sofa(w: ProgramWriter, p: Draws) -> None:
    seats = p.count("seats")
    seat_w, depth = p.number("seat_width"), p.number("depth")
    arm_w, leg_h = p.number("arm_width"), p.number("leg_height")
    width = seats * seat_w + 2 * arm_w
    upholstery, leg_mat = kit.fabric(w, p, "fabric"), kit.wood(w, p, "leg_wood")
    base_h = 0.2
    back_t = p.number("back_thickness")
    frame = w.part("frame", w.box((width, depth, base_h), (0.0, 0.0, leg_h + base_h / 2)), upholstery)
    kit.legs(w, frame, kit.corners(width / 2 - 0.05, depth / 2 - 0.05), leg_h, 0.0, 0.04, leg_mat, round_legs=True)
    back_h = p.number("back_height")
    w.part("back", w.box((width - 2 * arm_w, back_t, back_h), (0.0, depth / 2 - back_t / 2, leg_h + base_h + back_h / 2)),
           upholstery, parent=frame)
    arm_h = p.number("arm_height")
    for x in (-width / 2 + arm_w / 2, width / 2 - arm_w / 2):
        w.part("armrest", w.box((arm_w, depth, arm_h), (x, 0.0, leg_h + base_h + arm_h / 2)), upholstery,
               parent=frame, twin="armrest")
    cushion_h = p.number("cushion_height")
    cushion_d = depth - back_t - 0.01
    for i in range(seats):
        x = -width / 2 + arm_w + seat_w * (i + 0.5)
        cushion = w.bevel((seat_w - 0.01, cushion_d, cushion_h), 0.02,
                          (x, -depth / 2 + cushion_d / 2, leg_h + base_h + cushion_h / 2))
        w.part("seat_cushion", cushion, upholstery, parent=frame, twin="seat_cushion")


BED = Schema("bed", (
    N("width", 0.9, 1.8), N("length", 1.95, 2.1), N("frame_height", 0.15, 0.25), N("leg_height", 0.08, 0.2),
    K("wood", kit.WOODS), K("fabric", kit.FABRICS), N("headboard_height", 0.5, 0.9), N("mattress_height", 0.15, 0.25)))


def bed(w: ProgramWriter, p: Draws) -> None:
    width, length = p.number("width"), p.number("length")
    frame_h, leg_h = p.number("frame_height"), p.number("leg_height")
    wood, bedding = kit.wood(w, p, "wood"), kit.fabric(w, p, "fabric")
    frame = w.part("frame", w.box((width, length, frame_h), (0.0, 0.0, leg_h + frame_h / 2)), wood)
    kit.legs(w, frame, kit.corners(width / 2 - 0.04, length / 2 - 0.04), leg_h, 0.0, 0.06, wood, round_legs=False)
    head_h = p.number("headboard_height")
    w.part("headboard", w.box((width + 0.04, 0.05, head_h), (0.0, length / 2 + 0.025, leg_h + head_h / 2)), wood,
           parent=frame)
    mattress_h = p.number("mattress_height")
    top = leg_h + frame_h
    w.part("mattress", w.bevel((width - 0.04, length - 0.04, mattress_h), 0.03, (0.0, 0.0, top + mattress_h / 2)),
           bedding, parent=frame)
    n = 2 if width > 1.2 else 1
    pw = (width - 0.1) / n - 0.05
    for i in range(n):
        x = -width / 2 + 0.05 + (width - 0.1) * (i + 0.5) / n
        pillow = w.bevel((pw, 0.35, 0.12), 0.04, (x, length / 2 - 0.25, top + mattress_h + 0.06))
        w.part("pillow", pillow, bedding, parent=frame, twin="pillow")


DESK = Schema("desk", (
    N("width", 1.0, 1.6), N("depth", 0.55, 0.8), N("height", 0.72, 0.76), K("wood", kit.WOODS),
    K("handle_metal", kit.METALS), N("pedestal_width", 0.38, 0.45), B("pedestal_left", 0.5), C("drawers", 2, 3),
    B("keyboard_tray", 0.5)))


def desk(w: ProgramWriter, p: Draws) -> None:
    width, depth, height = p.number("width"), p.number("depth"), p.number("height")
    mat, handle_mat = kit.wood(w, p, "wood"), kit.metal(w, p, "handle_metal")
    top_t, t = 0.03, 0.018
    top = w.part("top", w.box((width, depth, top_t), (0.0, 0.0, height - top_t / 2)), mat)
    ped_w = p.number("pedestal_width")
    ped_h = height - top_t
    side_x = -width / 2 + ped_w / 2 if p.chance("pedestal_left") else width / 2 - ped_w / 2
    pedestal = w.part("pedestal", kit.carcass(w, ped_w, depth - 0.04, ped_h, t, cx=side_x), mat, parent=top)
    panel_x = width / 2 - t / 2 if side_x < 0 else -width / 2 + t / 2
    w.part("side_panel", w.box((t, depth - 0.04, ped_h), (panel_x, 0.0, ped_h / 2)), mat, parent=top)
    n = p.count("drawers")
    row = (ped_h - 0.02) / n
    y_front = -(depth - 0.04) / 2
    for i in range(n):
        z0 = 0.02 + i * row
        kit.drawer(w, pedestal, side_x - ped_w / 2 + kit.EPS, side_x + ped_w / 2 - kit.EPS, z0 + kit.EPS,
                   z0 + row - kit.EPS, y_front, depth - 0.04 - t - 0.02, t, mat, handle_mat, t)
    if p.chance("keyboard_tray"):
        tray_w = width - ped_w - 0.1 - t
        tray_x = (panel_x + (side_x - ped_w / 2 if side_x > 0 else side_x + ped_w / 2)) / 2
        tray = w.box((tray_w, depth * 0.6, 0.015), (tray_x, -depth * 0.15, height - top_t - 0.05))
        w.part("keyboard_tray", tray, mat, parent=top,
               joint=JointSpec("slide", (0.0, -1.0, 0.0), (tray_x, -depth * 0.45, height - top_t - 0.05),
                               (0.0, depth * 0.35)))
