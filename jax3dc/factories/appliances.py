"""Kitchen and laundry appliances: refrigerator, oven, microwave, dishwasher, washing machine."""

from __future__ import annotations

from jax3dc.factories import kit
from jax3dc.factories.writer import JointSpec, ProgramWriter
from jax3dc.parameters import Chance as B, Choice as K, Count as C, Draws, Number as N, Schema


REFRIGERATOR = Schema("refrigerator", (
    N("width", 0.55, 0.95), N("depth", 0.6, 0.72), N("height", 1.4, 1.95),
    K("shell", ("white enamelled steel", "stainless steel", "black steel")), K("handle_metal", kit.METALS),
    K("shelf_glass", kit.GLASSES), B("side_by_side", 0.5), C("side_shelves", 2, 4), N("freezer_split", 0.3, 0.4),
    B("freezer_bottom", 0.6), C("shelves", 2, 3), B("hinge_left", 0.5), N("door_opening", 1.6, 2.1, slots=2)))


def refrigerator(w: ProgramWriter, p: Draws) -> None:
    width, depth, height, t = p.number("width"), p.number("depth"), p.number("height"), 0.04
    shell = w.material("Metal", p.choice("shell"))
    handle_mat, shelf_mat = kit.metal(w, p, "handle_metal"), kit.glass(w, p, "shelf_glass")
    body = w.part("body", kit.carcass(w, width, depth, height, t), shell)
    g, door_t = kit.EPS, 0.05
    if width > 0.72 and p.chance("side_by_side"):  # side by side: freezer left, fridge right, mirrored doors
        w.part("divider", w.box((t, depth - t - 0.01, height - 2 * t), (0.0, -(t + 0.01) / 2, height / 2)), shell,
               parent=body)
        for i in range(p.count("side_shelves")):
            z = t + (height - 2 * t) * (i + 1) / 5
            w.part("shelf", w.box((width / 2 - 1.5 * t - 0.004, depth - t - 0.06, 0.006),
                                  (width / 4 - t / 4, -0.03 + t / 2, z)), shelf_mat, parent=body, twin="shelf")
        opening = p.number("door_opening", 0)
        kit.hinged_door(w, body, -width / 2 + g, -g, g, height - g, -depth / 2, door_t, "left", shell, handle_mat,
                        opening, name="freezer_door", twin="door")
        kit.hinged_door(w, body, g, width / 2 - g, g, height - g, -depth / 2, door_t, "right", shell, handle_mat,
                        opening, name="fridge_door", twin="door")
        return
    split = height * p.number("freezer_split")
    freezer_bottom = p.chance("freezer_bottom")
    w.part("divider", w.box((width - 2 * t, depth - t - 0.01, t), (0.0, -(t + 0.01) / 2, split)), shell,
           parent=body)
    top_space = split + t / 2, height - t
    for i in range(p.count("shelves")):
        z = top_space[0] + (top_space[1] - top_space[0]) * (i + 1) / 4
        w.part("shelf", w.box((width - 2 * t - 0.004, depth - t - 0.06, 0.006), (0.0, -0.03 + t / 2, z)), shelf_mat,
               parent=body, twin="shelf")
    side = "left" if p.chance("hinge_left") else "right"
    bands = [(0.0, split), (split, height)]
    names = ("freezer_door", "fridge_door") if freezer_bottom else ("fridge_door", "freezer_door")
    for k, ((z0, z1), name) in enumerate(zip(bands, names)):
        kit.hinged_door(w, body, -width / 2 + g, width / 2 - g, z0 + g, z1 - g, -depth / 2, door_t, side, shell,
                        handle_mat, p.number("door_opening", k), name=name, twin=None)


def _cavity_body(w, width, depth, height, wall, z_cavity0, z_cavity1, x0=None, x1=None):
    """A solid housing with one front-opening cavity between the given heights (and x range)."""
    x0 = -width / 2 + wall if x0 is None else x0
    x1 = width / 2 - wall if x1 is None else x1
    outer = w.box((width, depth, height), (0.0, 0.0, height / 2))
    cavity = w.box((x1 - x0, depth - wall + 0.01, z_cavity1 - z_cavity0),
                   ((x0 + x1) / 2, -(wall + 0.01) / 2, (z_cavity0 + z_cavity1) / 2))
    return w.difference(outer, cavity)


OVEN = Schema("oven", (
    N("width", 0.5, 0.9), N("depth", 0.55, 0.65), N("height", 0.82, 0.92),
    K("shell", ("stainless steel", "white enamelled steel", "black enamel")), K("handle_metal", kit.METALS),
    K("knob_plastic", kit.PLASTICS), K("glass", kit.GLASSES), N("panel_height", 0.1, 0.15), C("knobs", 3, 5)))


def oven(w: ProgramWriter, p: Draws) -> None:
    width, depth, height = p.number("width"), p.number("depth"), p.number("height")
    shell = w.material("Metal", p.choice("shell"))
    handle_mat, knob_mat, pane = kit.metal(w, p, "handle_metal"), kit.plastic(w, p, "knob_plastic"), kit.glass(w, p, "glass")
    panel_h = p.number("panel_height")
    door_top = height - panel_h
    base = 0.08
    body = w.part("body", _cavity_body(w, width, depth, height, 0.04, base + 0.04, door_top - 0.04), shell)
    g, door_t = kit.EPS, 0.045
    door = w.box((width - 2 * g, door_t, door_top - base - 2 * g),
                 (0.0, -depth / 2 - door_t / 2, (base + door_top) / 2))
    door_id = w.part("door", door, shell, parent=body,
                     joint=JointSpec("hinge", (1.0, 0.0, 0.0), (0.0, -depth / 2, base + g), (0.0, 1.571)))
    win_h = (door_top - base) * 0.5
    y_face = -depth / 2 - door_t
    w.part("window", w.box((width * 0.6, 0.004, win_h), (0.0, y_face - 0.002, base + (door_top - base) * 0.45)),
           pane, parent=door_id)
    handle = kit.bar_handle(w, 0.0, y_face, door_top - 0.05, width * 0.7, vertical=False, standoff=0.04, radius=0.009)
    w.part("handle", handle, handle_mat, parent=door_id)
    n_knobs = p.count("knobs")
    for i in range(n_knobs):
        x = -width / 2 + width * (i + 1) / (n_knobs + 1)
        z = door_top + panel_h / 2
        w.part("knob", kit.knob(w, x, -depth / 2, z, 0.02, 0.025), knob_mat, parent=body, twin="knob",
               joint=JointSpec("hinge", (0.0, -1.0, 0.0), (x, -depth / 2 - 0.0125, z), (0.0, 4.712)))
    burner_r = min(width, depth) * 0.12
    for bx in (-width / 4, width / 4):
        for by in (-depth / 4, depth / 4):
            w.part("burner", w.cylinder(burner_r, 0.015, (bx, by, height + 0.0075), segments=24), shell, parent=body,
                   twin="burner")


MICROWAVE = Schema("microwave", (
    N("width", 0.45, 0.6), N("depth", 0.33, 0.45), N("height", 0.26, 0.35), K("shell_metal", kit.METALS),
    K("glass", kit.GLASSES), K("keys_plastic", kit.PLASTICS), N("panel_share", 0.22, 0.28), N("door_opening", 1.5, 1.9)))


def microwave(w: ProgramWriter, p: Draws) -> None:
    width, depth, height = p.number("width"), p.number("depth"), p.number("height")
    shell, pane, keys = kit.metal(w, p, "shell_metal"), kit.glass(w, p, "glass"), kit.plastic(w, p, "keys_plastic")
    panel_w = width * p.number("panel_share")
    wall = 0.025
    cav_x1 = width / 2 - panel_w - wall
    body = w.part("body", _cavity_body(w, width, depth, height, wall, wall, height - wall, x1=cav_x1), shell)
    g, door_t = kit.EPS, 0.03
    door_x1 = width / 2 - panel_w
    door = w.box((door_x1 + width / 2 - 2 * g, door_t, height - 2 * g),
                 ((-width / 2 + door_x1) / 2, -depth / 2 - door_t / 2, height / 2))
    door_id = w.part("door", door, shell, parent=body,
                     joint=JointSpec("hinge", (0.0, 0.0, -1.0), (-width / 2 + g, -depth / 2, height / 2),
                                     (0.0, p.number("door_opening"))))
    w.part("window", w.box(((door_x1 + width / 2) * 0.7, 0.004, height * 0.6),
                           ((-width / 2 + door_x1) / 2 - 0.01, -depth / 2 - door_t - 0.002, height / 2)), pane,
           parent=door_id)
    panel = w.box((panel_w - 2 * g, 0.01, height - 2 * g), (door_x1 + panel_w / 2, -depth / 2 - 0.005, height / 2))
    buttons = w.grid_array(w.box((0.025, 0.008, 0.018), (door_x1 + panel_w / 2 - 0.02, -depth / 2 - 0.014, height * 0.3)),
                           (2, 1, 3), (0.04, 0.0, 0.035))
    w.part("control_panel", w.combine(panel, buttons), keys, parent=body)
    plate_r = min(cav_x1 + width / 2 - wall, depth - wall) * 0.42
    plate_x = (-width / 2 + wall + cav_x1) / 2
    w.part("turntable", w.cylinder(plate_r, 0.008, (plate_x, 0.0, wall + 0.014), segments=32), pane, parent=body,
           joint=JointSpec("hinge", (0.0, 0.0, 1.0), (plate_x, 0.0, wall + 0.014), kit.full_turn()))


DISHWASHER = Schema("dishwasher", (
    N("width", 0.45, 0.6), N("depth", 0.55, 0.62), N("height", 0.8, 0.87), K("shell_metal", kit.METALS),
    K("handle_metal", kit.METALS), K("rack_plastic", kit.PLASTICS)))


def dishwasher(w: ProgramWriter, p: Draws) -> None:
    width, depth, height = p.number("width"), p.number("depth"), p.number("height")
    shell, handle_mat, rack_mat = kit.metal(w, p, "shell_metal"), kit.metal(w, p, "handle_metal"), kit.plastic(w, p, "rack_plastic")
    wall, panel_h, base = 0.03, 0.1, 0.08
    door_top = height - 0.005
    body = w.part("body", _cavity_body(w, width, depth, height, wall, base + wall, height - wall), shell)
    g, door_t = kit.EPS, 0.05
    # shown with the door folded down, so that the racks can slide out over it; closing is -90 degrees
    hinge = (0.0, -depth / 2, base)
    door = w.box((width - 2 * g, door_t, door_top - base), (0.0, -depth / 2 - door_t / 2, (base + door_top) / 2))
    door_id = w.part("door", w.rotate(door, 90.0, "x", hinge), shell, parent=body,
                     joint=JointSpec("hinge", (1.0, 0.0, 0.0), hinge, (-1.571, 0.0)))
    handle = kit.bar_handle(w, 0.0, -depth / 2 - door_t, door_top - panel_h / 2, width * 0.5, vertical=False)
    w.part("handle", w.rotate(handle, 90.0, "x", hinge), handle_mat, parent=door_id)
    inner_w, inner_d = width - 2 * wall - 0.02, depth - wall - 0.04
    span = height - wall - (base + wall)
    for level in (0.15, 0.6):
        z = base + wall + span * level
        rack = kit.open_top_tray(w, (inner_w, inner_d, 0.12), (0.0, -wall / 2 + 0.0, z + 0.06), 0.01)
        w.part("rack", rack, rack_mat, parent=body, twin="rack",
               joint=JointSpec("slide", (0.0, -1.0, 0.0), (0.0, -inner_d / 2, z + 0.06), (0.0, inner_d * 0.7)))


WASHING_MACHINE = Schema("washing_machine", (
    N("width", 0.58, 0.62), N("depth", 0.5, 0.62), N("height", 0.82, 0.88), K("ring_plastic", kit.PLASTICS),
    K("glass", kit.GLASSES), K("knob_plastic", kit.PLASTICS), B("top_loader", 0.3), N("console_height", 0.08, 0.14),
    N("lid_opening", 1.3, 1.55), N("door_share", 0.28, 0.33), N("door_opening", 1.6, 2.0)))


def washing_machine(w: ProgramWriter, p: Draws) -> None:
    width, depth, height = p.number("width"), p.number("depth"), p.number("height")
    shell, ring_mat, pane, knob_mat = (w.material("Metal", "white enamelled steel"), kit.plastic(w, p, "ring_plastic"),
                                       kit.glass(w, p, "glass"), kit.plastic(w, p, "knob_plastic"))
    if p.chance("top_loader"):
        _top_loader(w, p, width, depth, height, shell, ring_mat, knob_mat)
        return
    dw, dh = width * 0.35, 0.07
    dx, dz = -width / 2 + 0.03 + dw / 2, height - 0.06
    slot = w.box((dw + 0.004, depth * 0.5 + 0.01, dh + 0.004), (dx, -depth / 2 + depth * 0.25 - 0.005, dz))
    body = w.part("body", w.difference(w.box((width, depth, height), (0.0, 0.0, height / 2)), slot), shell)
    r = min(width, height) * p.number("door_share")
    cz = height * 0.45
    y_front = -depth / 2
    ring = w.torus(r, 0.03, (0.0, y_front - 0.03, cz), axis="y", major_segments=32, minor_segments=8)
    door_id = w.part("door", ring, ring_mat, parent=body,
                     joint=JointSpec("hinge", (0.0, 0.0, -1.0), (-r - 0.03, y_front - 0.03, cz), (0.0, p.number("door_opening"))))
    w.part("window", w.cylinder(r - 0.03, 0.02, (0.0, y_front - 0.03, cz), axis="y", segments=32), pane,
           parent=door_id)
    tray = w.box((dw, depth * 0.5, dh), (dx, y_front + depth * 0.25 - 0.005, dz))
    w.part("detergent_drawer", tray, ring_mat, parent=body,
           joint=JointSpec("slide", (0.0, -1.0, 0.0), (dx, y_front, dz),
                           (0.0, depth * 0.35)))
    kx, kz = width / 2 - 0.09, height - 0.06
    w.part("program_knob", kit.knob(w, kx, y_front, kz, 0.03, 0.025), knob_mat, parent=body,
           joint=JointSpec("hinge", (0.0, -1.0, 0.0), (kx, y_front - 0.0125, kz), kit.full_turn()))


def _top_loader(w, p: Draws, width, depth, height, shell, lid_mat, knob_mat) -> None:
    """Washing machine loaded from the top: a lid hinged at the back, a console behind it."""
    console_d, console_h = 0.12, p.number("console_height")
    opening = min(width, depth - console_d) * 0.76  # square: kept from the box-only difference, as the data was built
    drum_box = w.box((opening, opening, 0.4), (0.0, -console_d / 2, height - 0.2))
    body = w.part("body", w.difference(w.box((width, depth, height), (0.0, 0.0, height / 2)), drum_box), shell)
    lid_d = depth - console_d - 0.035  # 25 mm short of the console: room for the lid standing open
    lid = w.box((width - 0.04, lid_d, 0.02), (0.0, -depth / 2 + 0.01 + lid_d / 2, height + 0.01))
    hinge_y = -depth / 2 + 0.01 + lid_d
    w.part("lid", lid, lid_mat, parent=body,
           joint=JointSpec("hinge", (-1.0, 0.0, 0.0), (0.0, hinge_y, height), (0.0, p.number("lid_opening"))))
    console = w.box((width, console_d, console_h), (0.0, depth / 2 - console_d / 2, height + console_h / 2))
    console_id = w.part("control_panel", console, shell, parent=body)
    kx, ky, kz = width / 2 - 0.1, depth / 2 - console_d / 2, height + console_h + 0.01  # on top, clear of the lid
    w.part("program_knob", w.cylinder(0.025, 0.02, (kx, ky, kz), segments=16), knob_mat, parent=console_id,
           joint=JointSpec("hinge", (0.0, 0.0, 1.0), (kx, ky, kz), kit.full_turn()))
