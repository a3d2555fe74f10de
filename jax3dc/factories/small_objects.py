"""Small articulated household objects in the spirit of PartNet-Mobility's categories:
kitchen pot, kettle, bucket, eyeglasses, globe, desk fan, printer, toaster, stapler."""

from __future__ import annotations

import math

import numpy as np

from jax3dc.factories import kit
from jax3dc.factories.writer import JointSpec, ProgramWriter
from jax3dc.parameters import Chance as B, Choice as K, Count as C, Draws, Number as N, Schema


def _cup(w: ProgramWriter, r_bottom: float, r_top: float, height: float, t: float, z0: float = 0.0):
    """An open-topped vessel of wall thickness t (lathe of its cross-section)."""
    profile = [(0.0, 0.0), (r_bottom, 0.0), (r_top, height), (r_top - t, height), (r_bottom - t, t), (0.0, t)]
    return w.lathe(profile, (0.0, 0.0, z0), segments=32)


KITCHEN_POT = Schema("kitchen_pot", (
    N("radius", 0.08, 0.15), N("height", 0.08, 0.18), K("metal", kit.METALS)))


def kitchen_pot(w: ProgramWriter, p: Draws) -> None:
    r, h = p.number("radius"), p.number("height")
    steel, grip = kit.metal(w, p, "metal"), w.material("Plastic", "black bakelite")
    body = w.part("body", _cup(w, r, r, h, 0.004), steel)
    for x in (-r - 0.02, r + 0.02):
        w.part("handle", w.box((0.04, 0.025, 0.015), (x, 0.0, 0.8 * h)), grip, parent=body, twin="handle")
    lid = w.cylinder(r + 0.004, 0.006, (0.0, 0.0, h + 0.003), segments=32)
    knob = w.cylinder(0.012, 0.015, (0.0, 0.0, h + 0.0135), segments=16)
    w.part("lid", w.combine(lid, knob), steel, parent=body,
           joint=JointSpec("slide", (0.0, 0.0, 1.0), (0.0, 0.0, h + 0.003), (0.0, 0.1)))


KETTLE = Schema("kettle", (
    N("radius", 0.07, 0.1), N("height", 0.16, 0.24), B("metal_shell", 0.5), K("shell_metal", kit.METALS),
    K("shell_plastic", kit.PLASTICS), K("base_plastic", kit.PLASTICS)))


def kettle(w: ProgramWriter, p: Draws) -> None:
    r, h = p.number("radius"), p.number("height")
    shell, base_mat = (kit.metal(w, p, "shell_metal") if p.chance("metal_shell") else
                       kit.plastic(w, p, "shell_plastic")), kit.plastic(w, p, "base_plastic")
    z0 = 0.02
    base = w.part("power_base", w.cylinder(1.15 * r, z0, (0.0, 0.0, z0 / 2), segments=32), base_mat)
    top_r = 0.7 * r
    pot = w.lathe([(0.0, 0.0), (r, 0.0), (1.05 * r, 0.5 * h), (top_r, h), (0.0, h)], (0.0, 0.0, z0), segments=32)
    spout = w.sweep([(0.0, -0.95 * r, z0 + 0.3 * h), (0.0, -r - 0.05, z0 + 0.55 * h), (0.0, -r - 0.08, z0 + 0.75 * h)],
                    0.012, segments=12)
    handle = w.sweep([(0.0, 1.0 * r, z0 + 0.25 * h), (0.0, 1.05 * r + 0.05, z0 + 0.3 * h),
                      (0.0, 1.05 * r + 0.05, z0 + 0.8 * h), (0.0, 0.78 * r, z0 + 0.85 * h)], 0.01, segments=12)
    body = w.part("body", w.combine(pot, spout, handle), shell, parent=base)
    lid_r = top_r * 0.92
    lid = w.combine(w.cylinder(lid_r, 0.01, (0.0, 0.0, z0 + h + 0.005), segments=32),
                    w.cylinder(0.01, 0.012, (0.0, 0.0, z0 + h + 0.016), segments=12))
    w.part("lid", lid, shell, parent=body,
           joint=JointSpec("hinge", (-1.0, 0.0, 0.0), (0.0, lid_r, z0 + h), (0.0, 1.4)))


BUCKET = Schema("bucket", (
    N("bottom_radius", 0.09, 0.13), N("top_radius", 0.13, 0.17), N("height", 0.2, 0.3), B("plastic_shell", 0.6),
    K("shell_plastic", kit.PLASTICS), K("shell_metal", kit.METALS), K("bail_metal", kit.METALS)))


def bucket(w: ProgramWriter, p: Draws) -> None:
    r0, r1, h = p.number("bottom_radius"), p.number("top_radius"), p.number("height")
    shell, bail_mat = (kit.plastic(w, p, "shell_plastic") if p.chance("plastic_shell") else
                       kit.metal(w, p, "shell_metal")), kit.metal(w, p, "bail_metal")
    z_e = 0.85 * h
    r_at = r0 + (r1 - r0) * z_e / h  # wall radius where the bail is hooked on
    r_e = r1 + 0.03
    ears = [w.box((r_e - 0.004 - r_at + 0.002, 0.02, 0.02), (s * (r_at - 0.002 + r_e - 0.004) / 2, 0.0, z_e))
            for s in (-1.0, 1.0)]
    body = w.part("body", w.combine(_cup(w, r0, r1, h, 0.004), *ears), shell)
    arc = [(r_e * math.cos(a), 0.0, z_e + r_e * math.sin(a)) for a in np.linspace(0.0, math.pi, 17)]
    w.part("bail_handle", w.sweep(arc, 0.004, segments=8), bail_mat, parent=body,
           joint=JointSpec("hinge", (1.0, 0.0, 0.0), (0.0, 0.0, z_e), (-1.3, 1.3)))


EYEGLASSES = Schema("eyeglasses", (
    N("lens_radius", 0.02, 0.027), N("gap", 0.014, 0.02), N("oval", 1.1, 1.4), B("plastic_frame", 0.5),
    K("frame_plastic", kit.PLASTICS), K("frame_metal", kit.METALS), K("glass", kit.GLASSES), N("temple_length", 0.12, 0.15)))


def eyeglasses(w: ProgramWriter, p: Draws) -> None:
    lens_r, gap, oval = p.number("lens_radius"), p.number("gap"), p.number("oval")
    frame_mat = kit.plastic(w, p, "frame_plastic") if p.chance("plastic_frame") else kit.metal(w, p, "frame_metal")
    lens_mat, rim = kit.glass(w, p, "glass"), 0.0025
    cx = gap / 2 + oval * (lens_r + rim)
    outer = cx + oval * (lens_r + rim)
    rims = [w.scale(w.torus(lens_r + rim, rim, (s * cx, 0.0, 0.0), axis="y", major_segments=32, minor_segments=6),
                    (oval, 1.0, 1.0), (s * cx, 0.0, 0.0)) for s in (-1.0, 1.0)]
    bridge = w.sweep([(-gap / 2 - 0.002, 0.0, 0.3 * lens_r), (0.0, 0.0, 0.45 * lens_r), (gap / 2 + 0.002, 0.0, 0.3 * lens_r)],
                     0.0018, segments=8)
    end_x = outer + 0.006
    ends = [w.box((end_x - outer + 0.002, 2 * rim, 0.008), (s * (outer - 0.002 + end_x) / 2, 0.0, 0.2 * lens_r))
            for s in (-1.0, 1.0)]
    frame = w.part("frame", w.combine(*rims, bridge, *ends), frame_mat)
    for s in (-1.0, 1.0):
        lens = w.scale(w.cylinder(lens_r, 0.002, (s * cx, 0.0, 0.0), axis="y", segments=32), (oval, 1.0, 1.0),
                       (s * cx, 0.0, 0.0))
        w.part("lens", lens, lens_mat, parent=frame, twin="lens")
    t = 0.004
    length = min(p.number("temple_length"), round(2 * (end_x - t) - 0.004, 3))  # folded, it clears the other temple
    for s in (-1.0, 1.0):
        inner_x = s * (end_x - t)  # the temple's inner face; it folds inwards about its front inner edge
        temple = w.box((t, length, 0.006), (s * (end_x - t / 2), rim + length / 2, 0.2 * lens_r))
        w.part("temple", temple, frame_mat, parent=frame, twin="temple",
               joint=JointSpec("hinge", (0.0, 0.0, s), (inner_x, rim, 0.2 * lens_r), (0.0, 1.571)))


GLOBE = Schema("globe", (
    N("radius", 0.1, 0.16), K("wood", kit.WOODS), K("metal", kit.METALS), N("column", 0.06, 0.12),
    B("wooden_stand", 0.5)))


def globe(w: ProgramWriter, p: Draws) -> None:
    radius, tilt = p.number("radius"), 23.5
    wood, metal, paper = kit.wood(w, p, "wood"), kit.metal(w, p, "metal"), w.material("Other", "printed paper map")
    base_h, column = 0.025, p.number("column")
    centre = (0.0, 0.0, base_h + column + radius + 0.012)
    holder_r = radius + 0.012
    a = math.radians(tilt)
    axis = (math.sin(a), 0.0, math.cos(a))
    arc = [(centre[0] + holder_r * math.cos(t) * axis[0] - holder_r * math.sin(t) * axis[2],
            0.0, centre[2] + holder_r * math.cos(t) * axis[2] + holder_r * math.sin(t) * axis[0])
           for t in np.linspace(0.0, math.pi, 19)]
    foot_x, foot_z = arc[-1][0], arc[-1][2]  # the meridian's lower end, where the column meets it
    stand = w.combine(w.cylinder(radius * 0.7, base_h, (0.0, 0.0, base_h / 2), segments=32),
                      w.cylinder(0.01, foot_z - base_h, (foot_x, 0.0, (base_h + foot_z) / 2), segments=12),
                      w.sweep(arc, 0.005, segments=8))
    stand_id = w.part("stand", stand, wood if p.chance("wooden_stand") else metal)
    ball = w.rotate(w.sphere(radius, centre, segments=32, rings=16), tilt, "y", centre)
    # pins on the rotation axis reach from the ball to the meridian's ends (touching its tube)
    pins = [kit.rod(w, tuple(c + s * 0.97 * radius * a for c, a in zip(centre, axis)),
                    tuple(c + s * (holder_r - 0.0055) * a for c, a in zip(centre, axis)), 0.004, segments=8)
            for s in (1.0, -1.0)]
    w.part("globe", w.combine(ball, *pins), paper, parent=stand_id,
           joint=JointSpec("hinge", axis, centre, kit.full_turn()))


DESK_FAN = Schema("desk_fan", (
    K("body_plastic", kit.PLASTICS), K("blade_plastic", kit.PLASTICS), K("guard_metal", kit.METALS),
    N("blade_radius", 0.1, 0.16), N("stand_height", 0.15, 0.3), C("blades", 3, 5)))


def desk_fan(w: ProgramWriter, p: Draws) -> None:
    plastic, blade_mat, guard_mat = (kit.plastic(w, p, "body_plastic"), kit.plastic(w, p, "blade_plastic"),
                                     kit.metal(w, p, "guard_metal"))
    blade_r, stand_h = p.number("blade_radius"), p.number("stand_height")
    base = w.combine(w.cylinder(blade_r * 0.9, 0.03, (0.0, 0.0, 0.015), segments=32),
                     w.cylinder(0.015, stand_h, (0.0, 0.0, 0.03 + stand_h / 2), segments=16))
    base_id = w.part("stand", base, plastic)
    top = 0.03 + stand_h
    hub_z = top + blade_r + 0.03
    motor = w.combine(w.cylinder(0.04, 0.08, (0.0, 0.04, hub_z), axis="y", segments=24),
                      w.cylinder(0.012, hub_z - top, (0.0, 0.04, (top + hub_z) / 2), segments=12))
    head = w.part("head", motor, plastic, parent=base_id,
                  joint=JointSpec("hinge", (0.0, 0.0, 1.0), (0.0, 0.04, top), (-0.8, 0.8)))
    guard_r = blade_r + 0.015
    cross = ((1, 0), (-1, 0), (0, 1), (0, -1))
    rings = w.combine(w.torus(guard_r, 0.003, (0.0, -0.045, hub_z), axis="y", major_segments=48, minor_segments=6),
                      w.torus(guard_r, 0.003, (0.0, 0.003, hub_z), axis="y", major_segments=48, minor_segments=6),
                      *[kit.rod(w, (x * guard_r, -0.045, hub_z + z * guard_r), (x * guard_r, 0.003, hub_z + z * guard_r),
                                0.003, segments=6) for x, z in cross],
                      # spokes from the motor's face carry the guard
                      *[kit.rod(w, (x * 0.038, 0.003, hub_z + z * 0.038), (x * guard_r, 0.003, hub_z + z * guard_r),
                                0.003, segments=6) for x, z in cross])
    w.part("guard", rings, guard_mat, parent=head)
    blade = w.rotate(w.box((0.04, 0.004, blade_r - 0.02), (0.0, -0.025, hub_z + 0.02 + (blade_r - 0.02) / 2)),
                     20.0, (0.0, 0.0, 1.0), (0.0, -0.025, hub_z))
    n = p.count("blades")
    rotor = w.combine(w.cylinder(0.022, 0.03, (0.0, -0.025, hub_z), axis="y", segments=16),
                      w.cylinder(0.005, 0.01, (0.0, -0.005, hub_z), axis="y", segments=8),  # shaft into the motor
                      w.radial_array(blade, n, (0.0, -0.025, hub_z), axis="y"))
    w.part("blades", rotor, blade_mat, parent=head,
           joint=JointSpec("hinge", (0.0, -1.0, 0.0), (0.0, -0.025, hub_z), kit.full_turn()))


PRINTER = Schema("printer", (
    N("width", 0.38, 0.5), N("depth", 0.3, 0.42), N("height", 0.15, 0.25), K("shell_plastic", kit.PLASTICS)))


def printer(w: ProgramWriter, p: Draws) -> None:
    width, depth, height = p.number("width"), p.number("depth"), p.number("height")
    shell, dark = kit.plastic(w, p, "shell_plastic"), w.material("Plastic", "dark grey plastic")
    tray_h, slot_h = 0.03, 0.025
    tray_slot = w.box((width * 0.7, depth * 0.75, tray_h + 0.004), (0.0, -depth / 2 + depth * 0.375 - 0.01, 0.01 + tray_h / 2))
    out_slot = w.box((width * 0.7, 0.06, slot_h), (0.0, -depth / 2 + 0.02, height * 0.55))
    lid_t = 0.02
    body = w.part("body", w.difference(w.box((width, depth, height - lid_t), (0.0, 0.0, (height - lid_t) / 2)),
                                       tray_slot, out_slot), shell)
    lid = w.box((width, depth, lid_t), (0.0, 0.0, height - lid_t / 2))
    w.part("scanner_lid", lid, shell, parent=body,
           joint=JointSpec("hinge", (-1.0, 0.0, 0.0), (0.0, depth / 2, height - lid_t), (0.0, 1.3)))
    tray = w.box((width * 0.7 - 0.004, depth * 0.75, tray_h), (0.0, -depth / 2 + depth * 0.375 - 0.01, 0.012 + tray_h / 2))
    w.part("paper_tray", tray, dark, parent=body,
           joint=JointSpec("slide", (0.0, -1.0, 0.0), (0.0, -depth / 2 - 0.01, 0.012 + tray_h / 2), (0.0, depth * 0.6)))
    flap_h = slot_h + 0.03
    flap = w.box((width * 0.75, 0.006, flap_h), (0.0, -depth / 2 - 0.003, height * 0.55 - slot_h / 2 - 0.015 + flap_h / 2))
    bottom = height * 0.55 - slot_h / 2 - 0.015
    w.part("output_flap", flap, dark, parent=body,
           joint=JointSpec("hinge", (1.0, 0.0, 0.0), (0.0, -depth / 2, bottom), (0.0, 1.571)))


TOASTER = Schema("toaster", (
    N("width", 0.25, 0.35), N("depth", 0.14, 0.2), N("height", 0.17, 0.22), K("shell_metal", kit.METALS),
    C("slots", 1, 2)))


def toaster(w: ProgramWriter, p: Draws) -> None:
    width, depth, height = p.number("width"), p.number("depth"), p.number("height")
    shell, dark = kit.metal(w, p, "shell_metal"), w.material("Plastic", "black plastic")
    slots = p.count("slots")
    cut = [w.box((width * 0.65, 0.035, height * 0.7), (0.0, (i - (slots - 1) / 2) * 0.06, height - height * 0.35 + 0.01))
           for i in range(slots)]
    body = w.part("body", w.difference(w.box((width, depth, height), (0.0, 0.0, height / 2)), *cut), shell)
    lx = width / 2 - 0.04
    lever = w.box((0.03, 0.02, 0.012), (lx, -depth / 2 - 0.01, height * 0.75))
    travel = round(height * 0.4, 3)
    w.part("lever", lever, dark, parent=body,
           joint=JointSpec("slide", (0.0, 0.0, -1.0), (lx, -depth / 2 - 0.01, height * 0.75), (0.0, travel)))
    kx, kz = -width / 2 + 0.04, height * 0.3
    w.part("browning_knob", kit.knob(w, kx, -depth / 2, kz, 0.012, 0.012), dark, parent=body,
           joint=JointSpec("hinge", (0.0, -1.0, 0.0), (kx, -depth / 2 - 0.006, kz), (0.0, 4.712)))


STAPLER = Schema("stapler", (
    N("length", 0.13, 0.2), N("width", 0.035, 0.05), K("metal", kit.METALS), K("grip_plastic", kit.PLASTICS),
    N("arm_height", 0.025, 0.035)))


def stapler(w: ProgramWriter, p: Draws) -> None:
    length, width = p.number("length"), p.number("width")
    metal, grip = kit.metal(w, p, "metal"), kit.plastic(w, p, "grip_plastic")
    base_h, arm_h = 0.012, p.number("arm_height")
    base = w.part("base", w.box((width, length, base_h), (0.0, 0.0, base_h / 2)), grip)
    post = w.box((width * 0.8, 0.02, 0.012), (0.0, length / 2 - 0.012, base_h + 0.006))
    w.part("hinge_block", post, metal, parent=base)
    top = base_h + 0.012
    arm = w.bevel((width * 0.9, length - 0.004, arm_h), 0.004, (0.0, 0.0, top + arm_h / 2))
    w.part("top_arm", arm, grip, parent=base,
           joint=JointSpec("hinge", (-1.0, 0.0, 0.0), (0.0, length / 2 - 0.002, top), (0.0, 0.9)))
