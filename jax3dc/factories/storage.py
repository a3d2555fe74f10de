"""Case furniture with doors and drawers: cabinet, drawer chest, wardrobe, kitchen unit,
nightstand, safe."""

from __future__ import annotations

from jax3dc.factories import kit
from jax3dc.factories.writer import JointSpec, ProgramWriter
from jax3dc.parameters import Chance as B, Choice as K, Count as C, Draws, Number as N, Schema

# a door, or two meeting in the middle (_door_pair)
DOOR_PAIR = (N("door_opening", 1.5, 2.0), B("two_doors", 0.4), B("hinge_left", 0.5))


def _shelves(w: ProgramWriter, body: int, width: float, depth: float, t: float, z_levels, material: int) -> None:
    for z in z_levels:
        board = w.box((width - 2 * t - 0.004, depth - t - 0.03, t), (0.0, -0.015 + t / 2, z))
        w.part("shelf", board, material, parent=body, twin="shelf")


def _door_pair(w, body, width, z0, z1, y_front, t, mat, handle_mat, p: Draws, x0=None, x1=None, handle="bar"):
    """One door, or two mirrored doors meeting in the middle, across [x0, x1]."""
    x0 = -width / 2 if x0 is None else x0
    x1 = width / 2 if x1 is None else x1
    g = kit.EPS
    opening = p.number("door_opening")
    if x1 - x0 > 0.65 or p.chance("two_doors"):
        mid = (x0 + x1) / 2
        kit.hinged_door(w, body, x0 + g, mid - g, z0 + g, z1 - g, y_front, t, "left", mat, handle_mat, opening, handle=handle)
        kit.hinged_door(w, body, mid + g, x1 - g, z0 + g, z1 - g, y_front, t, "right", mat, handle_mat, opening, handle=handle)
    else:
        side = "left" if p.chance("hinge_left") else "right"
        kit.hinged_door(w, body, x0 + g, x1 - g, z0 + g, z1 - g, y_front, t, side, mat, handle_mat, opening, handle=handle)


CABINET = Schema("cabinet", (
    N("width", 0.45, 1.0), N("depth", 0.32, 0.55), N("height", 0.6, 1.3), K("wood", kit.WOODS),
    K("handle_metal", kit.METALS), B("bar_handles", 0.6), B("drawer_row", 0.35), N("drawer_height", 0.12, 0.18),
    C("shelves", 1, 3), *DOOR_PAIR))


def cabinet(w: ProgramWriter, p: Draws) -> None:
    width, depth, height, t = p.number("width"), p.number("depth"), p.number("height"), 0.018
    mat, handle_mat = kit.wood(w, p, "wood"), kit.metal(w, p, "handle_metal")
    body = w.part("body", kit.carcass(w, width, depth, height, t), mat)
    handle = "bar" if p.chance("bar_handles") else "knob"
    doors_top = height
    if p.chance("drawer_row"):  # a row of drawers above the doors, behind a divider board
        drawer_h = p.number("drawer_height")
        doors_top = height - drawer_h
        w.part("divider", w.box((width - 2 * t, depth - t - 0.01, t), (0.0, -(t + 0.01) / 2, doors_top)), mat,
               parent=body)
        cols = 2 if width > 0.7 else 1
        col_w = width / cols
        for c in range(cols):
            x0 = -width / 2 + c * col_w
            kit.drawer(w, body, x0 + kit.EPS, x0 + col_w - kit.EPS, doors_top + kit.EPS, height - kit.EPS,
                       -depth / 2, depth - t - 0.02, t, mat, handle_mat, t, handle)
    n = p.count("shelves")
    _shelves(w, body, width, depth, t, [doors_top * (i + 1) / (n + 1) for i in range(n)], mat)
    _door_pair(w, body, width, 0.0, doors_top, -depth / 2, t, mat, handle_mat, p, handle=handle)


DRAWER_CHEST = Schema("drawer_chest", (
    N("width", 0.5, 1.2), N("depth", 0.38, 0.55), N("height", 0.6, 1.3), K("wood", kit.WOODS),
    K("handle_metal", kit.METALS), N("plinth", 0.04, 0.1), C("rows", 3, 6), B("two_columns", 0.6), B("bar_handles", 0.6)))


def drawer_chest(w: ProgramWriter, p: Draws) -> None:
    width, depth, height, t = p.number("width"), p.number("depth"), p.number("height"), 0.018
    mat, handle_mat = kit.wood(w, p, "wood"), kit.metal(w, p, "handle_metal")
    plinth = p.number("plinth")
    body = w.part("body", kit.carcass(w, width, depth, height - plinth, t, z0=plinth), mat)
    w.part("plinth", w.box((width - 0.04, depth - 0.04, plinth), (0.0, 0.01, plinth / 2)), mat, parent=body)
    top = w.box((width + 0.02, depth + 0.02, t), (0.0, 0.0, height + t / 2))
    w.part("top", top, mat, parent=body)
    rows = p.count("rows")
    cols = 2 if width > 0.9 and p.chance("two_columns") else 1
    handle = "bar" if p.chance("bar_handles") else "knob"
    row_h = (height - plinth) / rows
    col_w = width / cols
    for r in range(rows):
        for c in range(cols):
            x0, z0 = -width / 2 + c * col_w, plinth + r * row_h
            kit.drawer(w, body, x0 + kit.EPS, x0 + col_w - kit.EPS, z0 + kit.EPS, z0 + row_h - kit.EPS,
                       -depth / 2, depth - t - 0.01, t, mat, handle_mat, t, handle)


WARDROBE = Schema("wardrobe", (
    N("width", 0.9, 1.6), N("depth", 0.55, 0.65), N("height", 1.8, 2.2), K("wood", kit.WOODS),
    K("handle_metal", kit.METALS), K("rail_metal", kit.METALS), B("drawers", 0.5), N("drawer_height", 0.18, 0.25),
    B("sliding_doors", 0.35), N("door_opening", 1.5, 2.0)))


def wardrobe(w: ProgramWriter, p: Draws) -> None:
    width, depth, height, t = p.number("width"), p.number("depth"), p.number("height"), 0.02
    mat, handle_mat, rail_mat = kit.wood(w, p, "wood"), kit.metal(w, p, "handle_metal"), kit.metal(w, p, "rail_metal")
    body = w.part("body", kit.carcass(w, width, depth, height, t), mat)
    drawer_h = p.number("drawer_height") if p.chance("drawers") else 0.0
    rail = w.cylinder(0.012, width - 2 * t, (0.0, 0.0, height - 0.12), axis="x", segments=16)
    w.part("hanging_rail", rail, rail_mat, parent=body)
    w.part("shelf", w.box((width - 2 * t - 0.004, depth - t - 0.03, t), (0.0, -0.015 + t / 2, height - 0.3)),
           mat, parent=body)
    if drawer_h:
        w.part("divider", w.box((width - 2 * t - 0.004, depth - t - 0.01, t), (0.0, -(t + 0.01) / 2, drawer_h)),
               mat, parent=body)
        half = width / 2
        for x0 in (-half, 0.0):
            kit.drawer(w, body, x0 + kit.EPS, x0 + half - kit.EPS, kit.EPS, drawer_h - kit.EPS,
                       -depth / 2, depth - t - 0.02, t, mat, handle_mat, t)
    z0 = drawer_h
    g = kit.EPS
    if p.chance("sliding_doors"):  # sliding doors on two tracks in front of the carcass
        overlap, travel = 0.03, width / 2 - 0.05
        for side, track in (("left", 1), ("right", 0)):
            x0, x1 = (-width / 2 + g, overlap / 2) if side == "left" else (-overlap / 2, width / 2 - g)
            y_back = -depth / 2 - track * (t + g)
            panel = w.box((x1 - x0, t, height - z0 - 2 * g), ((x0 + x1) / 2, y_back - t / 2, (z0 + height) / 2))
            toward = 1.0 if side == "left" else -1.0
            door = w.part("door", panel, mat, parent=body, twin="door",
                          joint=JointSpec("slide", (toward, 0.0, 0.0), ((x0 + x1) / 2, y_back - t / 2, (z0 + height) / 2),
                                          (0.0, travel)))
            grip_x = x0 + 0.06 if side == "left" else x1 - 0.06
            if track:  # the outer door's handle stands off its face
                grip = kit.bar_handle(w, grip_x, y_back - t, (z0 + height) / 2, 0.3, vertical=True, standoff=0.015)
            else:  # the inner door's grip is a flat strip, thinner than the gap to the outer track
                grip = w.box((0.02, 0.0012, 0.3), (grip_x, y_back - t - 0.0006, (z0 + height) / 2))
            w.part("handle", grip, handle_mat, parent=door)
        return
    opening = p.number("door_opening")
    kit.hinged_door(w, body, -width / 2 + g, -g, z0 + g, height - g, -depth / 2, t, "left", mat, handle_mat, opening)
    kit.hinged_door(w, body, g, width / 2 - g, z0 + g, height - g, -depth / 2, t, "right", mat, handle_mat, opening)


KITCHEN_UNIT = Schema("kitchen_unit", (
    N("width", 0.4, 1.2), N("height", 0.78, 0.84), K("wood", kit.WOODS), K("handle_metal", kit.METALS),
    K("stone", ("grey granite", "white quartz", "black marble")), B("sink", 0.35), N("drawer_height", 0.13, 0.18),
    *DOOR_PAIR))


def kitchen_unit(w: ProgramWriter, p: Draws) -> None:
    width, depth, t = p.number("width"), 0.58, 0.018
    plinth, height = 0.1, p.number("height")
    mat, handle_mat, top_mat = kit.wood(w, p, "wood"), kit.metal(w, p, "handle_metal"), w.material("Stone", p.choice("stone"))
    sink = width >= 0.6 and p.chance("sink")
    top_t = 0.03
    hole = None
    if sink:  # one opening through the countertop and the carcass top, holding a basin
        hole_w, hole_d, hole_y = min(width - 0.16, 0.5), 0.36, -0.03
        hole = w.box((hole_w, hole_d, 0.12), (0.0, hole_y, height))
    cuts = (hole,) if hole is not None else ()
    body = w.part("body", kit.carcass(w, width, depth, height - plinth, t, z0=plinth, extra_cuts=cuts), mat)
    w.part("plinth", w.box((width, 0.018, plinth), (0.0, -depth / 2 + 0.06, plinth / 2)), mat, parent=body)
    # the carcass stands on four feet behind the plinth (on the plinth board alone it would rock back)
    feet = [(x, y) for x in (-width / 2 + 0.05, width / 2 - 0.05) for y in (-depth / 2 + 0.12, depth / 2 - 0.05)]
    kit.legs(w, body, feet, plinth, 0.0, 0.03, mat, round_legs=True, name="foot")
    slab = w.box((width + 0.01, depth + 0.04, top_t), (0.0, -0.02, height + top_t / 2))
    counter = w.part("countertop", w.difference(slab, hole) if hole is not None else slab, top_mat, parent=body)
    drawer_h = p.number("drawer_height")
    top_of_doors = height - drawer_h
    if sink:
        steel = w.material("Metal", "stainless steel")
        basin_h = 0.16
        basin = kit.open_top_tray(w, (hole_w, hole_d, basin_h), (0.0, hole_y, height + top_t - basin_h / 2), 0.008)
        w.part("sink_basin", basin, steel, parent=counter)
        w.part("false_front", w.box((width - 2 * kit.EPS, t, drawer_h - 2 * kit.EPS),
                                    (0.0, -depth / 2 - t / 2, height - drawer_h / 2)), mat, parent=body)
        _sink_tap(w, counter, (0.0, hole_y + hole_d / 2 + 0.04, height + top_t), steel)
    else:
        kit.drawer(w, body, -width / 2 + kit.EPS, width / 2 - kit.EPS, top_of_doors + kit.EPS, height - kit.EPS,
                   -depth / 2, depth - t - 0.02, t, mat, handle_mat, t, twin=None)
    _shelves(w, body, width, depth, t, [plinth + (top_of_doors - plinth) / 2], mat)
    _door_pair(w, body, width, plinth, top_of_doors, -depth / 2, t, mat, handle_mat, p)


def _sink_tap(w: ProgramWriter, parent: int, base, material: int) -> None:
    """A tap standing on the countertop behind the basin, with a lever on top."""
    x, y, z = base
    height, reach = 0.22, 0.17
    column = w.cylinder(0.02, height, (x, y, z + height / 2), segments=16)
    spout = w.sweep([(x, y, z + height), (x, y, z + height + 0.03), (x, y - 0.05, z + height + 0.05),
                     (x, y - reach, z + height + 0.02), (x, y - reach, z + height - 0.04)], 0.011, segments=12)
    tap = w.part("tap", w.combine(column, spout), material, parent=parent)
    lever = w.box((0.015, 0.07, 0.012), (x, y + 0.02 + 0.035, z + height * 0.6))
    w.part("tap_lever", lever, material, parent=tap,
           joint=JointSpec("hinge", (1.0, 0.0, 0.0), (x, y + 0.02, z + height * 0.6), (0.0, 0.5)))


NIGHTSTAND = Schema("nightstand", (
    N("width", 0.38, 0.6), N("depth", 0.3, 0.45), N("leg_height", 0.08, 0.25), N("box_height", 0.3, 0.5),
    K("wood", kit.WOODS), K("handle_metal", kit.METALS), B("round_legs", 0.5), C("drawers", 1, 2), B("knobs", 0.5)))


def nightstand(w: ProgramWriter, p: Draws) -> None:
    width, depth, t = p.number("width"), p.number("depth"), 0.018
    leg_h, box_h = p.number("leg_height"), p.number("box_height")
    mat, handle_mat = kit.wood(w, p, "wood"), kit.metal(w, p, "handle_metal")
    body = w.part("body", kit.carcass(w, width, depth, box_h, t, z0=leg_h), mat)
    kit.legs(w, body, kit.corners(width / 2 - 0.025, depth / 2 - 0.025), leg_h, 0.0, 0.03, mat,
             round_legs=p.chance("round_legs"))
    n = p.count("drawers")
    row = box_h / n
    handle = "knob" if p.chance("knobs") else "bar"
    for i in range(n):
        z0 = leg_h + i * row
        kit.drawer(w, body, -width / 2 + kit.EPS, width / 2 - kit.EPS, z0 + kit.EPS, z0 + row - kit.EPS,
                   -depth / 2, depth - t - 0.01, t, mat, handle_mat, t, handle)


SAFE = Schema("safe", (
    N("width", 0.35, 0.6), N("depth", 0.35, 0.5), N("height", 0.3, 0.7),
    K("steel", ("dark grey painted steel", "black steel")), K("dial_metal", kit.METALS), B("hinge_left", 0.5),
    N("door_opening", 1.5, 1.9)))


def safe(w: ProgramWriter, p: Draws) -> None:
    width, depth, height, t = p.number("width"), p.number("depth"), p.number("height"), 0.04
    steel, dial_mat = w.material("Metal", p.choice("steel")), kit.metal(w, p, "dial_metal")
    body = w.part("body", kit.carcass(w, width, depth, height, t), steel)
    side = "left" if p.chance("hinge_left") else "right"
    door_t = 0.05
    g = kit.EPS
    door = w.box((width - 2 * g, door_t, height - 2 * g), (0.0, -depth / 2 - door_t / 2, height / 2))
    hinge_x = -width / 2 + g if side == "left" else width / 2 - g
    axis = (0.0, 0.0, -1.0) if side == "left" else (0.0, 0.0, 1.0)
    door_id = w.part("door", door, steel, parent=body,
                     joint=JointSpec("hinge", axis, (hinge_x, -depth / 2, height / 2), (0.0, p.number("door_opening"))))
    y_front = -depth / 2 - door_t
    dial_r = min(width, height) * 0.09
    dial_x = 0.0 if width < 0.45 else (0.05 if side == "left" else -0.05)
    dial = w.cylinder(dial_r, 0.02, (dial_x, y_front - 0.01, height * 0.62), axis="y", segments=24)
    w.part("dial", dial, dial_mat, parent=door_id,
           joint=JointSpec("hinge", (0.0, -1.0, 0.0), (dial_x, y_front - 0.01, height * 0.62), kit.full_turn()))
    free = 1.0 if side == "left" else -1.0
    hx, hz = dial_x + free * (width * 0.3), height * 0.4
    hub = w.cylinder(0.015, 0.03, (hx, y_front - 0.015, hz), axis="y", segments=12)
    lever = w.box((0.02, 0.015, 0.09), (hx, y_front - 0.03, hz - 0.04))
    w.part("handle", w.combine(hub, lever), dial_mat, parent=door_id,
           joint=JointSpec("hinge", (0.0, -1.0, 0.0), (hx, y_front - 0.015, hz), (0.0, 1.571)))
