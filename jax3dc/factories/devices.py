"""Small devices of PartNet-Mobility categories that had no factory: camera, coffee machine, switch,
knife, bottle, remote, pen, scissors.

Without a factory a category never appears in the synthetic training data, and the model guessed
its joints from look-alikes (it called camera buttons hinges). The joints follow what the
PartNet-Mobility training pool (``shared/real_train``, read through the project's URDF importer)
shows, in the project frame (+Z up, front -Y):

* buttons slide into the face they sit on, along its normal, a few mm (camera: top buttons along Z,
  back buttons along Y; coffee machine: front buttons along Y); knobs and mode dials hinge about
  their own axis over a full turn [-pi, pi]; a camera lens turns about its optical axis (Y);
* a switch's toggle or rocker hinges about a horizontal axis in the plate (X), a small range; a
  slide switch slides along the plate (Z);
* a knife lies flat, its length along Y: a utility blade slides along Y, a folding blade hinges
  about Z (normal to the blade) at the handle's end, ~170 degrees;
* a bottle cap turns about the vertical axis, [-pi, pi]; a few lids slide up along Z;
* a pen stands along Z, its cap sliding off along Z; scissors lie flat, one blade hinging about Z.

Moving parts sit in pockets cut a little deeper than their travel, so pressing a button or
retracting a blade runs into nothing (tests/factories/test_factories_contacts.py).
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from jax3dc.factories import kit
from jax3dc.factories.writer import JointSpec, ProgramWriter, Ref
from jax3dc.parameters import Chance as B, Choice as K, Count as C, Draws, Number as N, Schema

TURN = (-3.1416, 3.1416)  # a dial or cap turns freely: the pool's continuous joints, one turn either way
SINK = 0.001  # how far a button reaches below the face it sits on (m), so it never floats free
CLEAR = 0.0006  # gap between a moving part and its pocket's walls (m)
BUTTON_SIDES = 12  # round buttons are small: 12 sides look round and keep the body's pockets few faces
AXES = "xyz"


def _axis_letter(normal: tuple[float, float, float]) -> str:
    return AXES[int(np.argmax(np.abs(normal)))]


def _along(point, normal, distance: float) -> tuple[float, float, float]:
    return tuple(float(p + n * distance) for p, n in zip(point, normal))


def _face_size(size_in_face: tuple[float, float], normal, length: float) -> tuple[float, float, float]:
    """The size of a box lying on a face: `size_in_face` over the two axes other than the
    normal's (in x, y, z order), `length` along the normal."""
    k = int(np.argmax(np.abs(normal)))
    others = iter(size_in_face)
    return tuple(length if i == k else next(others) for i in range(3))


def button_pocket(w: ProgramWriter, face_point, normal, size: tuple[float, float], travel: float,
                  round_: bool) -> Ref:
    """The hole a push button sits in: its outline plus CLEAR, deeper than SINK + travel, so the
    pressed button stays clear of the body."""
    depth = SINK + travel + 0.0008
    centre = _along(face_point, normal, (0.001 - depth) / 2)
    if round_:
        return w.cylinder(size[0] / 2 + CLEAR, depth + 0.001, centre, axis=_axis_letter(normal), segments=BUTTON_SIDES)
    return w.box(_face_size((size[0] + 2 * CLEAR, size[1] + 2 * CLEAR), normal, depth + 0.001), centre)


def push_button(w: ProgramWriter, parent: int, material: int, face_point, normal, size: tuple[float, float],
                height: float, travel: float, round_: bool, name: str = "button", twin: str | None = "button") -> int:
    """A button standing `height` proud of a face (outward `normal`), in the pocket of
    `button_pocket`: a slide into the face along its normal, range [0, travel]."""
    centre = _along(face_point, normal, (height - SINK) / 2)
    if round_:
        mesh = w.cylinder(size[0] / 2, height + SINK, centre, axis=_axis_letter(normal), segments=BUTTON_SIDES)
    else:
        mesh = w.box(_face_size(size, normal, height + SINK), centre)
    inward = tuple(float(-v) for v in normal)
    return w.part(name, mesh, material, parent=parent, twin=twin,
                  joint=JointSpec("slide", inward, tuple(face_point), (0.0, round(travel, 4))))


def dial(w: ProgramWriter, parent: int, material: int, face_point, normal, radius: float, height: float,
         name: str = "knob", twin: str | None = None, segments: int = 24) -> int:
    """A knob or dial standing on a face, turning about its own axis (the face's normal)."""
    mesh = w.cylinder(radius, height, _along(face_point, normal, height / 2), axis=_axis_letter(normal),
                      segments=segments)
    return w.part(name, mesh, material, parent=parent, twin=twin,
                  joint=JointSpec("hinge", tuple(float(v) for v in normal), tuple(face_point), TURN))


def _material(w: ProgramWriter, p: Draws, metal_chance: str) -> int:
    """A shell of plastic or (when `metal_chance` is drawn) metal, from the entries `<stem>_plastic`
    / `<stem>_metal` where the chance is `<stem>_is_metal`."""
    stem = metal_chance.removesuffix("_is_metal")
    return kit.metal(w, p, f"{stem}_metal") if p.chance(metal_chance) else kit.plastic(w, p, f"{stem}_plastic")


CAMERA = Schema("camera", (
    N("width", 0.1, 0.15), N("depth", 0.035, 0.065), N("height", 0.06, 0.1), B("body_is_metal", 0.3),
    K("body_plastic", kit.PLASTICS), K("body_metal", kit.METALS), B("grip", 0.6), N("grip_width", 0.02, 0.035),
    N("lens_radius", 0.4, 0.9), N("lens_offset", 0.0, 1.0), N("travel", 0.001, 0.004),
    N("shutter_radius", 0.004, 0.006), N("dial_radius", 0.008, 0.013), C("top_buttons", 0, 2),
    N("back_button", 0.006, 0.009), C("back_rows", 1, 3), C("back_columns", 1, 2), K("lens_plastic", kit.PLASTICS),
    N("lens_length", 0.015, 0.06), K("lens", ("turning barrel", "focus ring", "zoom barrel")), N("zoom", 0.3, 0.8),
    B("flash", 0.4), B("screen_hinges", 0.5)))


def camera(w: ProgramWriter, p: Draws) -> None:
    """A compact or mirrorless camera: lens on the front, shutter button, top buttons and mode dial
    on top, a grid of buttons (and a screen, sometimes flipping out) on the back, sometimes a
    pop-up flash."""
    width, depth, height = p.number("width"), p.number("depth"), p.number("height")
    shell = _material(w, p, "body_is_metal")
    dark, glass = w.material("Plastic", "black rubberised plastic"), w.material("Glass", "coated lens glass")
    hw, hd = width / 2, depth / 2
    grip_w = p.number("grip_width") if p.chance("grip") else 0.0
    # the lens fills most of the front that the grip leaves, at mid height
    room = (width - grip_w - 0.02) / 2
    radius = min(p.number("lens_radius") * 0.45 * height, room)
    lx_lo, lx_hi = -hw + 0.006 + radius, hw - grip_w - 0.01 - radius
    lx = lx_lo + (lx_hi - lx_lo) * p.number("lens_offset")
    lz = height / 2
    travel = p.number("travel")

    top_buttons = []  # (face point, size, round, name, twin)
    rs = p.number("shutter_radius")
    shutter_x = hw - 0.008 - rs
    top_buttons.append(((shutter_x, -hd + 0.006 + rs, height), (2 * rs, 2 * rs), True, "shutter_button", None))
    rd = p.number("dial_radius")
    dial_x = shutter_x - rs - 0.006 - rd
    dial_pt = (dial_x, min(hd - 0.004 - rd, 0.004), height)
    for i in range(p.count("top_buttons")):
        top_buttons.append(((dial_x - rd - 0.007 - i * 0.009, -hd + 0.008, height), (0.005, 0.005), True,
                            "button", "top_button"))
    back_buttons = []
    s = p.number("back_button")
    rows, cols = p.count("back_rows"), p.count("back_columns")
    for r in range(rows):
        for c in range(cols):
            back_buttons.append(((hw - 0.008 - s / 2 - c * (s + 0.004), hd, height - 0.012 - s / 2 - r * (s + 0.004)),
                                 (s, s), False, "button", "back_button"))
    pockets = [button_pocket(w, pt, (0, 0, 1), size, travel, rnd) for pt, size, rnd, _, _ in top_buttons]
    pockets += [button_pocket(w, pt, (0, 1, 0), size, travel, rnd) for pt, size, rnd, _, _ in back_buttons]
    shape = w.bevel((width, depth, height), min(0.004, depth / 8), (0.0, 0.0, height / 2))
    if grip_w:
        grip = w.bevel((grip_w, 0.012, height * 0.8), 0.003, (hw - grip_w / 2, -hd - 0.0055, height * 0.42))
        shape = w.combine(shape, grip)
    body = w.part("camera_body", w.difference(shape, *pockets), shell)

    for pt, size, rnd, name, twin in top_buttons:
        push_button(w, body, dark, pt, (0, 0, 1), size, 0.003, travel, rnd, name=name, twin=twin)
    for pt, size, rnd, name, twin in back_buttons:
        push_button(w, body, dark, pt, (0, 1, 0), size, 0.002, travel, rnd, name=name, twin=twin)
    dial(w, body, dark, dial_pt, (0, 0, 1), rd, 0.006, name="mode_dial")

    lens_mat = kit.plastic(w, p, "lens_plastic")
    length = p.number("lens_length")
    y0 = -hd  # the body's front face
    kind = p.choice("lens")
    if kind == "turning barrel":  # the whole barrel turns about the optical axis
        barrel = w.cylinder(radius, length, (lx, y0 - length / 2, lz), axis="y", segments=32)
        lens = w.part("lens", barrel, lens_mat, parent=body, joint=JointSpec("hinge", (0.0, -1.0, 0.0), (lx, y0, lz), TURN))
        w.part("lens_glass", w.cylinder(radius * 0.6, 0.002, (lx, y0 - length - 0.001, lz), axis="y", segments=32),
               glass, parent=lens)
    elif kind == "focus ring":  # a fixed barrel, a ring around it turning
        fixed = w.part("lens_barrel", w.cylinder(radius, length, (lx, y0 - length / 2, lz), axis="y", segments=32),
                       lens_mat, parent=body)
        w.part("lens_glass", w.cylinder(radius * 0.6, 0.002, (lx, y0 - length - 0.001, lz), axis="y", segments=32),
               glass, parent=fixed)
        ring_w = 0.45 * length
        ring = w.difference(w.cylinder(radius + 0.004, ring_w, (lx, y0 - length / 2, lz), axis="y", segments=32),
                            w.cylinder(radius + 0.0006, ring_w + 0.002, (lx, y0 - length / 2, lz), axis="y", segments=32))
        w.part("lens_ring", ring, dark, parent=fixed,
               joint=JointSpec("hinge", (0.0, -1.0, 0.0), (lx, y0 - length / 2, lz), TURN))
    else:  # a zoom barrel sliding out of a fixed tube along the optical axis
        wall = max(0.002, 0.12 * radius)
        tube = w.difference(w.cylinder(radius, length, (lx, y0 - length / 2, lz), axis="y", segments=32),
                            w.cylinder(radius - wall, length + 0.002, (lx, y0 - length / 2 - 0.001, lz), axis="y",
                                       segments=32))
        fixed = w.part("lens_barrel", tube, lens_mat, parent=body)
        inner_len = length + 0.004
        inner = w.combine(
            w.cylinder(radius - wall - CLEAR, inner_len, (lx, y0 - inner_len / 2, lz), axis="y", segments=32),
            w.cylinder((radius - wall) * 0.7, 0.002, (lx, y0 - inner_len - 0.001, lz), axis="y", segments=32))
        w.part("lens", inner, lens_mat, parent=fixed,
               joint=JointSpec("slide", (0.0, -1.0, 0.0), (lx, y0 - inner_len, lz),
                               (0.0, round(p.number("zoom") * length, 4))))

    if p.chance("flash"):  # a pop-up flash on the top left, hinged at its back edge, clear of the controls
        leftmost = min(pt[0] - size[0] / 2 for pt, size, *_ in top_buttons + [(dial_pt, (2 * rd, 0))])
        fw, fd = min(0.3 * width, leftmost - 0.004 - (-hw + 0.006)), min(0.022, depth * 0.6)
        fx = -hw + 0.006 + fw / 2
        flash = w.box((fw, fd, 0.008), (fx, -hd + 0.003 + fd / 2, height + 0.004))
        w.part("flash_lid", flash, shell, parent=body,
               joint=JointSpec("hinge", (-1.0, 0.0, 0.0), (fx, -hd + 0.003 + fd, height), (0.0, 1.2)))
    screen_x1 = hw - 0.012 - cols * (s + 0.004)
    sw, sh = screen_x1 - (-hw + 0.006), height * 0.7
    sx, sz0 = (-hw + 0.006 + screen_x1) / 2, height * 0.12
    screen = w.box((sw, 0.005, sh), (sx, hd + 0.0025, sz0 + sh / 2))
    if p.chance("screen_hinges"):  # flips out about its bottom edge, top away from the body
        w.part("screen", screen, dark, parent=body,
               joint=JointSpec("hinge", (-1.0, 0.0, 0.0), (sx, hd, sz0), (0.0, 1.571)))
    else:
        w.part("screen", screen, dark, parent=body)



COFFEE_MACHINE = Schema("coffee_machine", (
    N("width", 0.18, 0.3), N("depth", 0.25, 0.4), N("height", 0.28, 0.42), B("shell_is_metal", 0.4),
    K("shell_plastic", kit.PLASTICS), K("shell_metal", kit.METALS), N("bay_width", 0.5, 0.7),
    N("bay_top", 0.55, 0.7), C("knobs", 0, 2), N("knob_radius", 0.012, 0.02), C("buttons", 1, 4),
    N("button_size", 0.008, 0.014), B("round_buttons", 0.5), B("drip_tray", 0.7), B("water_tank", 0.5),
    N("tank_height", 0.4, 0.7), N("lid_depth", 0.35, 0.6), B("portafilter", 0.5), K("handle_plastic", kit.PLASTICS)))


def coffee_machine(w: ProgramWriter, p: Draws) -> None:
    """An espresso or pod machine: a brew bay in the front, a control strip above it with buttons
    (slides into the face) and knobs (turning about their axis), a lid on top hinged at its back
    edge, sometimes a drip tray or a water tank that slides out and a portafilter that turns."""
    width, depth, height = p.number("width"), p.number("depth"), p.number("height")
    shell, dark = _material(w, p, "shell_is_metal"), w.material("Plastic", "black plastic")
    hw, hd = width / 2, depth / 2
    bay_w, bay_top = p.number("bay_width") * width, p.number("bay_top") * height
    bay_d = 0.4 * depth
    cuts = [w.box((bay_w, bay_d + 0.01, bay_top - 0.03), (0.0, -hd + (bay_d - 0.01) / 2, 0.03 + (bay_top - 0.03) / 2))]
    # the control strip above the bay: knobs at its ends, buttons between
    strip_z = (bay_top + height) / 2
    n_knobs, kr = p.count("knobs"), p.number("knob_radius")
    knob_x = [(-1) ** i * (hw - 0.012 - kr) for i in range(n_knobs)]
    n_buttons, size = p.count("buttons"), p.number("button_size")
    round_ = p.chance("round_buttons")
    room = width - 2 * (2 * kr + 0.016) if n_knobs else width - 0.03
    pitch = min(size + 0.008, room / n_buttons)
    size = min(size, pitch - 0.004)
    buttons = [((-(n_buttons - 1) / 2 + i) * pitch, -hd, strip_z) for i in range(n_buttons)]
    travel = 0.003
    cuts += [button_pocket(w, pt, (0, -1, 0), (size, size), travel, round_) for pt in buttons]
    tray = p.chance("drip_tray")
    tray_w, tray_h, tray_d = bay_w * 0.9, 0.022, bay_d + 0.04
    if tray:  # the tray runs in a slot under the bay floor
        cuts.append(w.box((tray_w + 2 * CLEAR, tray_d + 0.01, tray_h + 2 * CLEAR),
                          (0.0, -hd + (tray_d - 0.01) / 2, 0.004 + tray_h / 2)))
    tank = p.chance("water_tank")
    tank_h = p.number("tank_height") * height
    tank_w, tank_d = width * 0.7, min(0.3 * depth, 0.09)
    tank_y = hd - 0.008 - tank_d / 2
    if tank:  # the tank stands in a well at the back of the top
        cuts.append(w.box((tank_w + 2 * CLEAR, tank_d + 2 * CLEAR, tank_h), (0.0, tank_y, height - tank_h / 2 + 0.001)))
    body = w.part("coffee_machine_body", w.difference(w.bevel((width, depth, height), 0.006, (0.0, 0.0, height / 2)), *cuts),
                  shell)
    for pt in buttons:
        push_button(w, body, dark, pt, (0, -1, 0), (size, size), 0.004, travel, round_)
    for x in knob_x:
        dial(w, body, dark, (x, -hd, strip_z), (0, -1, 0), kr, 0.014, twin="knob")
    # the lid over the front part of the top (a hopper or water lid), hinged at its back edge
    lid_back = -hd + 0.01 + p.number("lid_depth") * depth
    if tank:
        lid_back = min(lid_back, tank_y - tank_d / 2 - 0.02)
    lid_t = 0.01
    lid = w.box((width * 0.8, lid_back - (-hd + 0.01), lid_t), (0.0, (lid_back - hd + 0.01) / 2, height + lid_t / 2))
    w.part("lid", lid, shell, parent=body,
           joint=JointSpec("hinge", (-1.0, 0.0, 0.0), (0.0, lid_back, height), (0.0, 1.4)))
    if tray:
        grid = w.box((tray_w, tray_d, tray_h), (0.0, -hd + tray_d / 2 - 0.008, 0.004 + CLEAR + tray_h / 2))
        w.part("drip_tray", grid, dark, parent=body,
               joint=JointSpec("slide", (0.0, -1.0, 0.0), (0.0, -hd - 0.008, 0.004 + tray_h / 2),
                               (0.0, round(0.7 * tray_d, 4))))
    if tank:
        box = w.box((tank_w, tank_d, tank_h + 0.01), (0.0, tank_y, height - tank_h + 0.001 + (tank_h + 0.01) / 2))
        w.part("water_tank", box, w.material("Plastic", "translucent blue plastic"), parent=body,
               joint=JointSpec("slide", (0.0, 0.0, 1.0), (0.0, tank_y, height), (0.0, round(0.8 * tank_h, 4))))
    if p.chance("portafilter"):  # hangs under the bay's ceiling; it locks by turning about the vertical
        pr = min(0.03, bay_w / 4)
        cy, top = -hd + pr + 0.012, bay_top
        basket = w.cylinder(pr, 0.025, (0.0, cy, top - 0.0125), segments=24)
        arm_len = 0.09
        arm = w.box((0.018, arm_len, 0.016), (0.0, cy - pr - arm_len / 2 + 0.002, top - 0.014))
        w.part("portafilter", w.combine(basket, arm), kit.plastic(w, p, "handle_plastic"), parent=body,
               joint=JointSpec("hinge", (0.0, 0.0, 1.0), (0.0, cy, top), (-0.785, 0.0)))


SWITCH = Schema("switch", (
    C("gangs", 1, 3), K("kind", ("toggle", "rocker", "slide", "push")), N("gang_width", 0.025, 0.04),
    N("plate_height", 0.07, 0.12), N("plate_thickness", 0.008, 0.012), B("plate_is_metal", 0.2),
    K("plate_plastic", kit.PLASTICS), K("plate_metal", kit.METALS), K("switch_plastic", kit.PLASTICS),
    N("size", 0.6, 1.0), N("toggle_angle", 0.25, 0.5), N("rocker_angle", 0.1, 0.2), B("screws", 0.5)))


def switch(w: ProgramWriter, p: Draws) -> None:
    """A wall plate (front -Y, its back against the wall) with 1-3 gangs of one kind: toggles and
    rockers hinge about a horizontal axis (X) through their pivot in the plate's face, a small
    range either way; slide switches slide up the plate (Z); push buttons slide into it (Y)."""
    n, kind = p.count("gangs"), p.choice("kind")
    gang_w, height, t = p.number("gang_width"), p.number("plate_height"), p.number("plate_thickness")
    plate_mat = _material(w, p, "plate_is_metal")
    mat = kit.plastic(w, p, "switch_plastic")
    width = n * gang_w + 0.02
    zc = height / 2
    xs = [(-(n - 1) / 2 + i) * gang_w for i in range(n)]
    f = p.number("size")
    cuts, moving = [], []
    if kind in ("toggle", "rocker"):
        if kind == "toggle":  # a bat lever on a round boss sunk in the plate
            angle = p.number("toggle_angle")
            bw, bh, sink, out = 0.008 * f + 0.004, 0.012 * f + 0.006, 0.003, 0.002
        else:  # a wide paddle, proud of the plate, rocking about its middle
            angle = p.number("rocker_angle")
            bw, bh, sink, out = 0.6 * gang_w, (0.35 + 0.15 * f) * height, 0.003, 0.004
        # the pocket holds every pose: the corners of the sunk block swing by up to its half-height
        # times sin(angle) in depth and its depth times sin(angle) in height
        reach = max(sink, out + 0.003)  # the lever's root, as wide as the bat, swings in too
        pz = bh / 2 + reach * math.sin(angle) + 0.001
        py = sink + bh / 2 * math.sin(angle) + 0.001
        for x in xs:
            cuts.append(w.box((bw + 2 * CLEAR, py + 0.001, 2 * pz), (x, (py - 0.001) / 2, zc)))
        for x in xs:
            block = w.box((bw, sink + out, bh), (x, (sink - out) / 2, zc))
            if kind == "toggle":
                lever = w.cone(0.0025 * f + 0.002, 0.0035 * f + 0.002, 0.014, (x, -out - 0.007, zc), axis="y", segments=12)
                mesh = w.combine(block, lever)
            else:
                mesh = block
            swing = (-round(angle, 4), round(angle, 4))
            moving.append((kind, mesh, JointSpec("hinge", (1.0, 0.0, 0.0), (x, 0.0, zc), swing)))
    elif kind == "slide":  # a knob in a vertical slot, slid up to switch
        kw, kh, travel = 0.008 * f + 0.004, 0.008 * f + 0.004, 0.012 + 0.01 * f
        sink, out = 0.003, 0.006
        for x in xs:
            cuts.append(w.box((kw + 2 * CLEAR, sink + 0.002, kh + travel + 2 * CLEAR), (x, (sink + 0.002) / 2 - 0.001, zc)))
        for x in xs:
            knob_mesh = w.box((kw, sink + out, kh), (x, (sink - out) / 2, zc - travel / 2))
            joint = JointSpec("slide", (0.0, 0.0, 1.0), (x, 0.0, zc - travel / 2), (0.0, round(travel, 4)))
            moving.append(("slider", knob_mesh, joint))
    else:  # push buttons, pressed into the plate
        size, travel = (0.5 + 0.3 * f) * gang_w, 0.003
        for x in xs:
            cuts.append(button_pocket(w, (x, 0.0, zc), (0, -1, 0), (size, size), travel, False))
        for x in xs:
            mesh = w.box((size, 0.004 + SINK, size), (x, -(0.004 - SINK) / 2, zc))
            moving.append(("button", mesh, JointSpec("slide", (0.0, 1.0, 0.0), (x, 0.0, zc), (0.0, travel))))
    plate = w.bevel((width, t, height), min(0.002, t / 4), (0.0, t / 2, zc))
    frame = w.part("switch_frame", w.difference(plate, *cuts), plate_mat)
    for name, mesh, joint in moving:
        w.part(name, mesh, mat, parent=frame, joint=joint, twin=name)
    if p.chance("screws"):  # two screw heads above and below the switches
        for z in (0.008, height - 0.008):
            w.part("screw", w.cylinder(0.003, 0.0015, (0.0, -0.00075, z), axis="y", segments=12),
                   w.material("Metal", "chrome"), parent=frame, twin="screw")


KNIFE = Schema("knife", (
    B("folding", 0.4), N("handle_length", 0.09, 0.15), N("handle_width", 0.018, 0.028), N("handle_thickness", 0.01, 0.018),
    B("handle_is_metal", 0.3), K("handle_plastic", kit.PLASTICS), K("handle_metal", kit.METALS),
    K("blade_metal", kit.METALS),
    N("blade_length", 0.5, 0.9), N("blade_width", 0.5, 0.8), N("exposed", 0.15, 0.35), N("extend", 0.005, 0.015)))


def knife(w: ProgramWriter, p: Draws) -> None:
    """A knife lying flat, its handle along Y and the blade pointing -Y: a utility knife whose blade
    slides along the handle (pushed by a thumb slider in a slot on top), or a folding knife whose
    blade hinges about Z (normal to the blade) at the handle's front end, folding into a slit."""
    folding = p.chance("folding")
    length, width, thick = p.number("handle_length"), p.number("handle_width"), p.number("handle_thickness")
    handle_mat, steel = _material(w, p, "handle_is_metal"), kit.metal(w, p, "blade_metal")
    hl, hw = length / 2, width / 2
    blade_len = p.number("blade_length") * length
    bw = p.number("blade_width") * (width - 0.006)
    bt = 0.002  # blade thickness
    zc = thick / 2
    if not folding:
        exposed = p.number("exposed") * blade_len
        extend = p.number("extend")
        y_tip = -hl - exposed
        y_back = y_tip + blade_len
        retract = exposed - 0.004
        channel_end = y_back + retract + 0.002  # the blade's back end, fully retracted, stays short of it
        channel = w.box((bw + 2 * CLEAR, channel_end + hl + 0.01, bt + 2 * CLEAR), (0.0, (channel_end - hl - 0.01) / 2, zc))
        thumb_y = y_back - 0.012
        slot_lo, slot_hi = thumb_y - 0.004 - extend - 0.001, thumb_y + 0.004 + retract + 0.001
        slot = w.box((0.003 + 2 * CLEAR, slot_hi - slot_lo, thick), (0.0, (slot_lo + slot_hi) / 2, zc + thick / 2))
        handle = w.part("knife_body", w.difference(w.bevel((width, length, thick), 0.002, (0.0, 0.0, zc)), channel, slot),
                        handle_mat)
        profile = [(-bw / 2, y_back), (bw / 2, y_back), (bw / 2, y_tip + 0.6 * bw), (-bw / 2, y_tip)]
        blade = w.part("blade", w.extrude(profile, bt, (0.0, 0.0, zc)), steel, parent=handle,
                       joint=JointSpec("slide", (0.0, -1.0, 0.0), (0.0, -hl, zc), (-round(retract, 4), round(extend, 4))))
        stem = w.box((0.003, 0.004, thick / 2 + 0.001), (0.0, thumb_y, zc + thick / 4 + 0.0005 + bt / 4))
        grip = w.bevel((0.009, 0.008, 0.004), 0.001, (0.0, thumb_y, thick + 0.002))
        w.part("slider", w.combine(stem, grip), handle_mat, parent=blade)
        return
    spine = 0.003
    gap = bt + 2 * CLEAR
    # the slit, open at the front end and along the +X side, takes the folded blade
    slit = w.box((width - spine + 0.01, length + 0.02, gap), (-hw + spine + (width - spine + 0.01) / 2, 0.0, zc))
    handle = w.part("knife_body", w.difference(w.bevel((width, length, thick), 0.002, (0.0, 0.0, zc)), slit),
                    handle_mat)
    bw = min(bw, width - spine - 0.004)
    px = -hw + spine + 0.002 + bw / 2  # folded, the blade lies in the slit clear of the spine
    py = -hl + 0.006
    blade_len = min(blade_len, length - 0.01)
    root = 0.004  # blade behind the pivot
    profile = [(px - bw / 2, py + root), (px + bw / 2, py + root), (px + bw / 2, py - blade_len + 0.5 * bw),
               (px - bw / 2, py - blade_len)]
    w.part("blade", w.extrude(profile, bt, (0.0, 0.0, zc)), steel, parent=handle,
           joint=JointSpec("hinge", (0.0, 0.0, 1.0), (px, py, zc), (0.0, 2.95)))


BOTTLE = Schema("bottle", (
    N("radius", 0.025, 0.05), N("height", 0.12, 0.3), N("shoulder", 0.55, 0.85), N("neck_radius", 0.35, 0.6),
    N("neck_height", 0.01, 0.04), B("body_is_metal", 0.2), K("body_plastic", kit.PLASTICS + ("clear PET",)),
    K("body_metal", kit.METALS), N("cap_height", 0.012, 0.03), K("cap_plastic", kit.PLASTICS), B("screw_cap", 0.6),
    K("top", ("flip lid", "pump", "push-on cap")), N("pump_travel", 0.008, 0.018)))


def _hollow_cap(w: ProgramWriter, r_in: float, r_out: float, z0: float, height: float, over: float,
                segments: int = 32) -> Ref:
    """A cap of outer radius `r_out` from z0 to z0 + height whose underside is hollowed up to
    z0 + over (radius `r_in`), so it sits over the top `over` of a neck."""
    return w.difference(w.cylinder(r_out, height, (0.0, 0.0, z0 + height / 2), segments=segments),
                        w.cylinder(r_in, over + 0.001, (0.0, 0.0, z0 + (over - 0.001) / 2), segments=segments))


def bottle(w: ProgramWriter, p: Draws) -> None:
    """A bottle (a lathe of body, shoulder and neck) with a screw cap turning about the vertical
    axis (the pool's most common joint), or a flip lid hinged at the back, a pump head pressed down,
    or a push-on cap lifted off along the vertical."""
    r, h = p.number("radius"), p.number("height")
    sh = p.number("shoulder") * h
    rn = max(0.011, p.number("neck_radius") * r)
    neck = p.number("neck_height")
    top = h + neck
    profile = [(0.0, 0.0), (r, 0.0), (r, sh), (rn, h), (rn, top), (0.0, top)]
    body_mat = _material(w, p, "body_is_metal")
    body = w.part("bottle_body", w.lathe(profile, (0.0, 0.0, 0.0), segments=32), body_mat)
    ch = p.number("cap_height")
    over = min(0.8 * neck, ch - 0.003)
    rc = rn + 0.003
    cap_mat = kit.plastic(w, p, "cap_plastic")
    if p.chance("screw_cap"):
        cap = _hollow_cap(w, rn + CLEAR, rc, top - over, ch, over)
        w.part("cap", cap, cap_mat, parent=body, joint=JointSpec("hinge", (0.0, 0.0, 1.0), (0.0, 0.0, top), TURN))
        return
    kind = p.choice("top")
    if kind == "push-on cap":
        cap = _hollow_cap(w, rn + CLEAR, rc, top - over, ch, over)
        lift = JointSpec("slide", (0.0, 0.0, 1.0), (0.0, 0.0, top), (0.0, round(over + 0.01, 4)))
        w.part("cap", cap, cap_mat, parent=body, joint=lift)
        return
    travel = p.number("pump_travel") if kind == "pump" else 0.0
    above = max(0.5 * ch, travel + 0.004)  # the collar's height above the neck
    collar_top = top + above
    collar = _hollow_cap(w, rn + CLEAR, rc, top - over, over + above, over)
    if kind == "flip lid":  # a collar on the neck, a lid hinged at its back edge
        collar_id = w.part("cap", collar, cap_mat, parent=body)
        lid_t = 0.004
        lid = w.cylinder(rc, lid_t, (0.0, 0.0, collar_top + lid_t / 2), segments=32)
        w.part("lid", lid, cap_mat, parent=collar_id,
               joint=JointSpec("hinge", (-1.0, 0.0, 0.0), (0.0, rc, collar_top), (0.0, 1.9)))
        return
    # a pump: a collar with a bore, a stem pressed down into it, a head with a nozzle to the front
    rs = 0.0035
    bore = w.cylinder(rs + CLEAR, above + 0.001, (0.0, 0.0, top + (above + 0.001) / 2), segments=16)
    collar_id = w.part("cap", w.difference(collar, bore), cap_mat, parent=body)
    stem_lo = top + travel + 0.001  # pressed, the stem stops 1 mm above the neck
    head_lo = collar_top + travel + 0.001
    stem = w.cylinder(rs, head_lo - stem_lo + 0.001, (0.0, 0.0, (stem_lo + head_lo + 0.001) / 2), segments=16)
    head = w.cylinder(rc, 0.012, (0.0, 0.0, head_lo + 0.006), segments=24)
    nozzle = w.box((0.008, 0.02 + rc, 0.007), (0.0, -(0.02 + rc) / 2, head_lo + 0.008))
    w.part("pump_head", w.combine(stem, head, nozzle), cap_mat, parent=collar_id,
           joint=JointSpec("slide", (0.0, 0.0, -1.0), (0.0, 0.0, head_lo), (0.0, round(travel, 4))))


REMOTE = Schema("remote", (
    N("length", 0.12, 0.22), N("width", 0.04, 0.065), N("thickness", 0.014, 0.026), K("body_plastic", kit.PLASTICS),
    C("rows", 2, 4), C("columns", 2, 3), N("button_size", 0.5, 0.8), B("round_buttons", 0.5), N("travel", 0.001, 0.0025),
    B("power_button", 0.7), K("button_plastic", ("grey rubber", "black rubber", "white rubber", "red plastic"))))


def remote(w: ProgramWriter, p: Draws) -> None:
    """A remote control lying flat, its length along Y: a grid of buttons on the top face, each a
    slide down into its pocket (the face's normal, -Z), and sometimes a power button at the top."""
    length, width, thick = p.number("length"), p.number("width"), p.number("thickness")
    shell = kit.plastic(w, p, "body_plastic")
    rows, cols = p.count("rows"), p.count("columns")
    pitch_x = (width - 0.012) / cols
    pitch_y = min(pitch_x * 1.2, (0.6 * length) / rows)
    size = p.number("button_size") * min(pitch_x, pitch_y)
    round_ = p.chance("round_buttons")
    travel = p.number("travel")
    grid_y = -length / 2 + 0.02 + pitch_y * rows / 2  # the grid sits towards the -Y end, the hand's end
    grid = [((-(cols - 1) / 2 + c) * pitch_x, grid_y + (-(rows - 1) / 2 + r) * pitch_y, thick)
            for r in range(rows) for c in range(cols)]
    power = p.chance("power_button")
    power_pt = (0.0, length / 2 - 0.018, thick)
    power_size = (min(0.012, 0.35 * width), 0.007)  # wider than a grid button and shaped apart
    pockets = [button_pocket(w, pt, (0, 0, 1), (size, size), travel, round_) for pt in grid]
    if power:
        pockets.append(button_pocket(w, power_pt, (0, 0, 1), power_size, travel, False))
    body = w.part("remote_body", w.difference(w.bevel((width, length, thick), min(0.004, thick / 4), (0.0, 0.0, thick / 2)),
                                              *pockets), shell)
    rubber = w.material("Plastic", p.choice("button_plastic"))
    for pt in grid:
        push_button(w, body, rubber, pt, (0, 0, 1), (size, size), 0.002, travel, round_)
    if power:
        push_button(w, body, w.material("Plastic", "red plastic"), power_pt, (0, 0, 1), power_size, 0.0025, travel,
                    False, name="power_button", twin=None)


PEN = Schema("pen", (
    N("length", 0.12, 0.15), N("radius", 0.004, 0.007), B("click", 0.5), B("barrel_is_metal", 0.3),
    K("barrel_plastic", kit.PLASTICS + ("transparent blue plastic",)), K("barrel_metal", kit.METALS),
    K("part_plastic", kit.PLASTICS), N("click_travel", 0.002, 0.005), N("cap_length", 0.03, 0.05), B("clip", 0.7)))


def pen(w: ProgramWriter, p: Draws) -> None:
    """A pen lying on its side along Y, clip up: a click pen whose button slides into the barrel
    along its axis, or a capped pen whose cap slides off the tip end along the axis; sometimes a
    pocket clip. Built standing along Z, writing tip down, then laid down: the pool's one pen
    stands so, but a pen on end falls over, and the physics check asks that it rest as left."""
    length, r = p.number("length"), p.number("radius")
    click = p.chance("click")
    barrel_mat, part_mat = _material(w, p, "barrel_is_metal"), kit.plastic(w, p, "part_plastic")
    if click:
        travel = p.number("click_travel")
        tip = 0.015
        profile = [(0.0, 0.0), (0.0008, 0.0), (r, tip), (r, length), (0.0, length)]
        bore = w.cylinder(0.6 * r + CLEAR, travel + 0.007, (0.0, 0.0, length - (travel + 0.007) / 2 + 0.001), segments=16)
        barrel = w.part("pen_body", w.difference(w.lathe(profile, (0.0, 0.0, 0.0), segments=24), bore), barrel_mat)
        lo = length - 0.005  # pressed by travel, it stops 1 mm above the bore's floor
        button = w.cylinder(0.6 * r, length + 0.008 - lo, (0.0, 0.0, (lo + length + 0.008) / 2), segments=16)
        holder = barrel
        w.part("button", button, part_mat, parent=barrel,
               joint=JointSpec("slide", (0.0, 0.0, -1.0), (0.0, 0.0, length), (0.0, round(travel, 4))))
        clip_top = length - 0.004
    else:
        cap_len = p.number("cap_length")
        over = cap_len - 0.004  # the cap covers the tip and this much of the barrel
        tip = 0.012
        # the barrel starts its cone where the cap's bore ends (above the cap's closed end)
        profile = [(0.0, 0.004), (0.0006, 0.004), (r, 0.004 + tip), (r, length), (0.0, length)]
        barrel = w.part("pen_body", w.lathe(profile, (0.0, 0.0, 0.0), segments=24), barrel_mat)
        wall = 0.0012
        cap = w.difference(w.cylinder(r + wall, cap_len, (0.0, 0.0, cap_len / 2), segments=24),
                           w.cylinder(r + CLEAR * 0.5, over + 0.001, (0.0, 0.0, cap_len - (over - 0.001) / 2), segments=24))
        holder = w.part("cap", cap, part_mat, parent=barrel,
                        joint=JointSpec("slide", (0.0, 0.0, -1.0), (0.0, 0.0, cap_len), (0.0, round(over + 0.005, 4))))
        r = r + wall
        clip_top = cap_len - 0.003
    if p.chance("clip"):  # a clip along the barrel (or the cap), on its back
        clip = w.box((0.003, 0.0015, 0.03), (0.0, r + 0.0018, clip_top - 0.015))
        w.part("clip", w.combine(clip, w.box((0.003, 0.002, 0.003), (0.0, r + 0.0006, clip_top - 0.0015))), part_mat,
               parent=holder)
    w.turn(1, "x")  # +Z (the pen) onto -Y, the clip's +Y side up


SCISSORS = Schema("scissors", (
    N("blade_length", 0.06, 0.12), N("blade_width", 0.012, 0.02), N("handle_length", 0.05, 0.08),
    N("ring_radius", 0.01, 0.016), N("thickness", 0.002, 0.004), K("blade_metal", kit.METALS),
    K("handle_plastic", kit.PLASTICS + ("orange plastic",)), N("opening", 0.5, 0.9)))


def _scissor_leg(w: ProgramWriter, side: float, blade_len: float, blade_w: float, handle_len: float, ring_r: float,
                 z0: float, t: float) -> tuple[Ref, Ref]:
    """One leg in the slab z0..z0+t, pivot at the origin: a blade towards -Y and a ring handle
    towards +Y on the other side (the blade edges cross x = 0), so that opening the
    blades spreads the handles."""
    zc = z0 + t / 2
    edge = -side * 0.25 * blade_w  # the cutting edges pass each other: closed, the blades overlap
    outline = [(edge, 0.006), (side * blade_w, 0.006), (side * blade_w * 0.4, -blade_len), (edge, -blade_len)]
    blade = w.extrude(outline if side > 0 else outline[::-1], t, (0.0, 0.0, zc))
    ring_c = (-side * (ring_r + 0.003), handle_len, zc)  # the legs cross: a blade's handle is on the other side
    shank = w.box((0.006, handle_len - ring_r - 0.002, t), (-side * 0.004, (handle_len - ring_r + 0.006) / 2, zc))
    ring = w.difference(w.cylinder(ring_r + 0.004, t, ring_c, segments=24),
                        w.cylinder(ring_r, t + 0.002, ring_c, segments=24))
    return blade, w.combine(shank, ring)


def scissors(w: ProgramWriter, p: Draws) -> None:
    """Scissors lying flat and closed: two legs stacked in two thin slabs, the upper hinging about
    Z (normal to the blades) at the pivot screw; opening turns its blade away from the other."""
    blade_len, blade_w = p.number("blade_length"), p.number("blade_width")
    handle_len, ring_r, t = p.number("handle_length"), p.number("ring_radius"), p.number("thickness")
    steel, grip = kit.metal(w, p, "blade_metal"), kit.plastic(w, p, "handle_plastic")
    blade_a, handle_a = _scissor_leg(w, 1.0, blade_len, blade_w, handle_len, ring_r, 0.0, t)
    leg_a = w.part("blade", blade_a, steel)
    w.part("handle", handle_a, grip, parent=leg_a)
    blade_b, handle_b = _scissor_leg(w, -1.0, blade_len, blade_w, handle_len, ring_r, t, t)
    screw = w.cylinder(0.003, 0.0012, (0.0, 0.0, 2 * t + 0.0006), segments=12)
    leg_b = w.part("blade", w.combine(blade_b, screw), steel, parent=leg_a,
                   joint=JointSpec("hinge", (0.0, 0.0, -1.0), (0.0, 0.0, t), (0.0, round(p.number("opening"), 4))))
    w.part("handle", handle_b, grip, parent=leg_b)

BUILDS: dict[str, tuple[Callable[[ProgramWriter, Draws], None], Schema]] = {
    "camera": (camera, CAMERA),
    "coffee_machine": (coffee_machine, COFFEE_MACHINE),
    "switch": (switch, SWITCH),
    "knife": (knife, KNIFE),
    "bottle": (bottle, BOTTLE),
    "remote": (remote, REMOTE),
    "pen": (pen, PEN),
    "scissors": (scissors, SCISSORS),
}
