"""Mechanisms that robot-manipulation benchmarks model by hand: button panels, dial panels, levers
(and handle presses, vertical sliders), sliding windows, sliding-door cabinets, desks with drawers,
faucets with a toggle lever or two turning handles.

Benchmarks (robosuite, ManiSkill, RoboCasa, CALVIN, LIBERO, Meta-World-style scenes) write these
in MJCF/URDF, often as bare boxes and often with the working face along +X. So each factory varies
sizes, counts, positions and materials, has a `simple` switch between box primitives and more
detailed geometry, and ends with `_face`, which turns the finished object about +Z.

Facing. Every factory builds facing -Y (kit conventions) and then reads `turned` and `facing`:
the rendering camera stays in the front hemisphere around -Y (jax3dc.render.sample_camera) and
MJCF/URDF imports keep their source frame unless told otherwise (only PartNet-Mobility is turned,
data_pipeline.importers.source.default_front), so a benchmark object whose mechanism looks along
+X arrives seen from its side. Training must show such objects, with joint axes and pivots turned
with the geometry (ProgramWriter.turn). About half face -Y, the usual case; the other half
share +X, -X and +Y equally (+Y, its back to the camera, teaches that hidden mechanisms exist).
-Y is `turned = 0` rather than an option of `facing`, so each object has one record (the stage-1
target): a `facing` left unread keeps its default.
"""

from __future__ import annotations

import math
from typing import Callable

from jax3dc.factories import kit
from jax3dc.factories.writer import JointSpec, ProgramWriter, Ref
from jax3dc.parameters import Chance as B, Choice as K, Count as C, Draws, Number as N, Schema

FACINGS = ("+x", "-x", "+y")
QUARTER_TURNS = {"-y": 0, "+x": 1, "+y": 2, "-x": 3}  # counter-clockwise about +Z from -Y
FACING = (B("turned", 0.5), K("facing", FACINGS))
BUTTON_COLOURS = ("red plastic", "green plastic", "yellow plastic", "blue plastic", "black plastic",
                  "white plastic")
G = kit.EPS


def _face(w: ProgramWriter, p: Draws) -> str:
    """Turns the finished object so its working face looks along the drawn direction; returns it."""
    facing = p.choice("facing") if p.chance("turned") else "-y"
    w.turn(QUARTER_TURNS[facing])
    return facing


def _block(w: ProgramWriter, size, center, simple: bool) -> Ref:
    """A box, or in detailed variants a box with bevelled edges."""
    if simple:
        return w.box(size, center)
    return w.bevel(size, min(0.006, 0.12 * min(size)), center)


def _grid(n: int, rows: int, a: float, b: float) -> tuple[list[tuple[float, float]], float]:
    """Centres of `n` items in `rows` rows over an a x b face (offsets from its centre), and the pitch."""
    cols = math.ceil(n / rows)
    pitch = min(a / cols, b / rows)
    out = []
    for i in range(n):
        r, c = divmod(i, cols)
        in_row = min(cols, n - r * cols)
        out.append(((c - (in_row - 1) / 2) * a / cols, ((rows - 1) / 2 - r) * b / rows))
    return out, pitch


# ---------------------------------------------------------------- button panel
BUTTON_PANEL = Schema("button_panel", (
    K("body", ("box", "plate")), N("width", 0.08, 0.5), N("depth", 0.06, 0.3), N("height", 0.045, 0.25),
    N("plate_thickness", 0.035, 0.06), K("face", ("top", "front")), C("buttons", 1, 6), B("two_rows", 0.4),
    B("round_buttons", 0.7), N("button_size", 0.012, 0.05), N("proud", 0.004, 0.022), N("travel_share", 0.5, 0.95),
    B("metal_body", 0.3), K("body_plastic", kit.PLASTICS), K("body_metal", kit.METALS),
    K("button_colour", BUTTON_COLOURS), K("guard", ("none", "collars", "flip_cover")), N("cover_opening", 1.0, 1.5),
    B("simple", 0.4), *FACING))


def button_panel(w: ProgramWriter, p: Draws) -> None:
    """Push buttons that slide into the body along their face's inward normal (+ range: pressed).

    Each button is a cap over a stem in a blind hole a little wider than it, so it can travel in
    without meeting the body; the travel stops before the cap is flush.
    """
    plate = p.choice("body") == "plate"
    width = p.number("width")
    if plate:
        depth, height, face = p.number("plate_thickness"), p.number("height") + 0.05, "front"
    else:
        depth, height, face = p.number("depth"), p.number("height"), p.choice("face")
    mat = kit.metal(w, p, "body_metal") if p.chance("metal_body") else kit.plastic(w, p, "body_plastic")
    button_mat = w.material("Plastic", p.choice("button_colour"))
    simple = p.chance("simple")
    n, rows = p.count("buttons"), 2 if p.chance("two_rows") else 1
    rows = min(rows, n)
    round_buttons = p.chance("round_buttons")
    proud = p.number("proud")
    travel = round(proud * p.number("travel_share"), 4)
    guard = p.choice("guard")
    margin = 0.012 if guard == "none" else 0.02
    cell = 0.024 if guard == "none" else 0.032  # room for a button (and its collar), whatever the draw
    width = max(width, math.ceil(n / rows) * cell + 2 * margin)
    if face == "top":
        depth = max(depth, rows * cell + 2 * margin)
    else:
        height = max(height, rows * cell + 2 * margin)
    stem = 0.006
    foot_t = 0.015
    z0 = foot_t if plate else 0.0
    if face == "top":  # face frame: centre, outward normal, in-face axes u (x) and v
        centre, normal, v_axis, extent_v, cyl_axis = (0.0, 0.0, height), (0.0, 0.0, 1.0), (0.0, 1.0, 0.0), depth, "z"
    else:
        centre, normal, v_axis, extent_v, cyl_axis = ((0.0, -depth / 2, z0 + height / 2), (0.0, -1.0, 0.0),
                                                      (0.0, 0.0, 1.0), height, "y")
    spots, pitch = _grid(n, rows, width - 2 * margin, extent_v - 2 * margin)
    size = min(p.number("button_size"), 0.6 * pitch)

    def at(u: float, v: float, out: float) -> tuple[float, float, float]:
        return tuple(centre[i] + u * (i == 0) + v * v_axis[i] + out * normal[i] for i in range(3))

    def along(length: float, across: float) -> tuple[float, float, float]:
        return tuple(length if normal[i] else across for i in range(3))

    holes, caps = [], []
    for u, v in spots:
        hole_depth = stem + travel + 0.004
        if round_buttons:
            holes.append(w.cylinder(size / 2 + 0.0015, hole_depth + 0.002, at(u, v, 0.001 - hole_depth / 2), cyl_axis))
            caps.append(w.cylinder(size / 2, proud + stem, at(u, v, (proud - stem) / 2), cyl_axis))
        else:
            holes.append(w.box(along(hole_depth + 0.002, size + 0.003), at(u, v, 0.001 - hole_depth / 2)))
            caps.append(_block(w, along(proud + stem, size), at(u, v, (proud - stem) / 2), simple))
    if plate:
        panel = w.difference(_block(w, (width, depth, height), (0.0, 0.0, z0 + height / 2), simple), *holes)
        foot = w.box((width, max(0.1, 0.5 * height), foot_t), (0.0, 0.0, foot_t / 2))
        body = w.part("body", w.combine(panel, foot), mat)
    else:
        body = w.part("body", w.difference(_block(w, (width, depth, height), (0.0, 0.0, height / 2), simple), *holes),
                      mat)
    inward = tuple(0.0 - x for x in normal)  # 0.0 - x: no -0.0 in the axis
    for (u, v), cap in zip(spots, caps):
        w.part("button", cap, button_mat, parent=body, twin="button",
               joint=JointSpec("slide", inward, at(u, v, 0.0), (0.0, travel)))
    if guard == "collars":  # a fixed ring around each button, a little prouder than it
        ring_h = proud + 0.003
        for u, v in spots:
            if round_buttons:
                outer = w.cylinder(size / 2 + 0.006, ring_h, at(u, v, ring_h / 2), cyl_axis)
                inner = w.cylinder(size / 2 + 0.0025, ring_h + 0.002, at(u, v, ring_h / 2), cyl_axis)
            else:
                outer = w.box(along(ring_h, size + 0.012), at(u, v, ring_h / 2))
                inner = w.box(along(ring_h + 0.002, size + 0.005), at(u, v, ring_h / 2))
            w.part("guard", w.difference(outer, inner), mat, parent=body, twin="guard")
    elif guard == "flip_cover":  # a clear hood over all buttons, hinged at its far (+v) edge, lifting away
        clear = w.material("Plastic", "clear polycarbonate")
        us, vs = [u for u, _ in spots], [v for _, v in spots]
        span_u = min(max(us) - min(us) + size + 0.016, width - 0.004)
        span_v = min(max(vs) - min(vs) + size + 0.016, extent_v - 0.004)
        mid_u, mid_v, hood_h, t = (max(us) + min(us)) / 2, (max(vs) + min(vs)) / 2, proud + 0.008, 0.002
        outer = w.box(_hood_size(normal, span_u, span_v, hood_h), at(mid_u, mid_v, hood_h / 2))
        inner = w.box(_hood_size(normal, span_u - 2 * t, span_v - 2 * t, hood_h), at(mid_u, mid_v, hood_h / 2 - t))
        hinge = at(mid_u, mid_v + span_v / 2, 0.0)
        w.part("cover", w.difference(outer, inner), clear, parent=body,
               joint=JointSpec("hinge", (-1.0, 0.0, 0.0), hinge, (0.0, p.number("cover_opening"))))
    _face(w, p)


def _hood_size(normal, span_u: float, span_v: float, h: float) -> tuple[float, float, float]:
    """A hood's box size: span_u along x, h along the face normal, span_v along the other axis."""
    return (span_u, h, span_v) if normal[1] else (span_u, span_v, h)


# ---------------------------------------------------------------- dial panel
DIAL_PANEL = Schema("dial_panel", (
    K("layout", ("panel", "stove", "top")), N("width", 0.12, 0.9), N("depth", 0.08, 0.6), N("height", 0.04, 0.3),
    C("dials", 1, 6), B("two_rows", 0.3), N("dial_radius", 0.008, 0.04), N("dial_depth", 0.008, 0.035),
    K("dial_shape", ("plain", "skirted", "finned")), N("turn", 1.571, 6.283), B("both_ways", 0.3),
    B("metal_body", 0.5), K("body_metal", kit.METALS), K("body_plastic", kit.PLASTICS), K("dial_plastic", kit.PLASTICS),
    C("burners", 1, 4), B("simple", 0.4), *FACING))


def dial_panel(w: ProgramWriter, p: Draws) -> None:
    """Knobs and dials that each turn about their own axis, the outward normal of their face.

    Layouts: a panel with dials on its front, a stove-like top (burners on top, dials in front),
    or a console with dials on its top. A dial's pointer or fin lies on its outer face, inside its
    radius, so turning never sweeps it into the body.
    """
    layout = p.choice("layout")
    width, depth, height = p.number("width"), p.number("depth"), p.number("height")
    n = p.count("dials")
    rows = 2 if n >= 2 and layout != "stove" and p.chance("two_rows") else 1
    cols = math.ceil(n / rows)
    r, dd = p.number("dial_radius"), p.number("dial_depth")
    shape = p.choice("dial_shape")
    footprint = r * (1.3 if shape == "skirted" else 1.0)
    # the body grows to hold the dials with some margin, whatever was drawn
    width = max(width, cols * (2 * footprint + 0.012) + 0.02)
    face_v = depth if layout == "top" else height
    face_v = max(face_v, rows * (2 * footprint + 0.012) + 0.016)
    if layout == "top":
        depth = face_v
    else:
        height = face_v
    if layout == "panel":  # a panel, not a cabinet: thin behind its face
        depth = min(depth, 0.2)
    elif layout == "stove":
        depth = max(depth, 0.3)
        width = max(width, 0.3)
    turn = p.number("turn")
    rng = (-turn / 2, turn / 2) if p.chance("both_ways") else (0.0, turn)
    mat = kit.metal(w, p, "body_metal") if p.chance("metal_body") else kit.plastic(w, p, "body_plastic")
    dial_mat = kit.plastic(w, p, "dial_plastic")
    simple = p.chance("simple")
    body = w.part("body", _block(w, (width, depth, height), (0.0, 0.0, height / 2), simple), mat)
    if layout == "stove":
        _burners(w, p, body, width, depth, height, simple)
    spots, _ = _grid(n, rows, width - 0.02, face_v - 0.016)
    for u, v in spots:
        if layout == "top":
            base, normal, axis_name = (u, v, height), (0.0, 0.0, 1.0), "z"
        else:
            base, normal, axis_name = (u, -depth / 2, height / 2 + v), (0.0, -1.0, 0.0), "y"

        def out(d: float, base=base, normal=normal) -> tuple[float, float, float]:
            return tuple(base[i] + d * normal[i] for i in range(3))

        meshes = [w.cylinder(r, dd, out(dd / 2), axis_name, segments=8 if simple else 24)]
        if shape == "skirted":
            meshes.append(w.cylinder(1.3 * r, 0.25 * dd, out(0.125 * dd), axis_name, segments=24))
        elif shape == "finned":
            fin = 0.6 * dd
            size = (1.8 * r, fin, 0.35 * r) if axis_name == "y" else (1.8 * r, 0.35 * r, fin)
            meshes.append(w.box(size, out(dd + fin / 2)))
        else:  # a pointer mark on the outer face, off the axis so the angle shows
            mark = (0.15 * r, 0.002, 0.5 * r) if axis_name == "y" else (0.15 * r, 0.5 * r, 0.002)
            mark_at = out(dd + 0.001)
            mark_at = (mark_at[0], mark_at[1], mark_at[2] + 0.45 * r) if axis_name == "y" else \
                (mark_at[0], mark_at[1] + 0.45 * r, mark_at[2])
            meshes.append(w.box(mark, mark_at))
        w.part("dial", w.combine(*meshes) if len(meshes) > 1 else meshes[0], dial_mat, parent=body, twin="dial",
               joint=JointSpec("hinge", normal, base, rng))
    _face(w, p)


def _burners(w: ProgramWriter, p: Draws, body: int, width: float, depth: float, height: float, simple: bool) -> None:
    """Fixed burners on a stove-like top: flat discs, or rings over discs in detailed variants."""
    n = p.count("burners")
    spots, pitch = _grid(n, 2 if n > 2 else 1, width - 0.04, depth - 0.04)
    radius = min(0.1, 0.32 * pitch)
    iron = w.material("Metal", "black cast iron")
    for u, v in spots:
        disc = w.cylinder(radius, 0.008, (u, v, height + 0.004), segments=24)
        if not simple:
            disc = w.combine(disc, w.torus(radius * 0.7, 0.004, (u, v, height + 0.012)))
        w.part("burner", disc, iron, parent=body, twin="burner")


# ---------------------------------------------------------------- lever, handle press, vertical slider
LEVER = Schema("lever", (
    K("kind", ("lever", "press", "slider")), N("base_width", 0.06, 0.3), N("base_depth", 0.06, 0.3),
    N("base_height", 0.015, 0.1), N("arm_length", 0.06, 0.35), N("arm_radius", 0.004, 0.014),
    N("knob_radius", 0.008, 0.03), N("swing_deg", 30.0, 90.0), B("sideways", 0.3), B("one_sided", 0.3),
    N("press_height", 0.08, 0.3), N("press_drop_deg", 15.0, 45.0), N("slider_travel", 0.03, 0.2),
    K("base_metal", kit.METALS), K("grip_plastic", kit.PLASTICS), B("metal_grip", 0.3), B("simple", 0.4), *FACING))


def lever(w: ProgramWriter, p: Draws) -> None:
    """A lever arm on a horizontal hinge at its foot, a handle press pushed down about its back
    end, or a knob sliding up a vertical slot."""
    kind = p.choice("kind")
    base_mat = kit.metal(w, p, "base_metal")
    grip_mat = base_mat if p.chance("metal_grip") else kit.plastic(w, p, "grip_plastic")
    simple = p.chance("simple")
    bw, bd, bh = p.number("base_width"), p.number("base_depth"), p.number("base_height")
    if kind == "lever":
        _lever_arm(w, p, bw, bd, bh, base_mat, grip_mat, simple)
    elif kind == "press":
        _handle_press(w, p, bw, bd, bh, base_mat, grip_mat, simple)
    else:
        _vertical_slider(w, p, bw, bd, bh, base_mat, grip_mat, simple)
    _face(w, p)


def _lever_arm(w: ProgramWriter, p: Draws, bw: float, bd: float, bh: float, base_mat: int, grip_mat: int,
               simple: bool) -> None:
    """The arm stands on a hub between two cheeks, high enough that at +-90 degrees its knob
    passes over the base; it tilts forward/back (hinge along x) or, sideways, left/right."""
    length, arm_r, knob_r = p.number("arm_length"), p.number("arm_radius"), p.number("knob_radius")
    knob_r = max(knob_r, arm_r * 1.2)
    hub_r = max(1.6 * arm_r, 0.008)
    hub_len = 2 * max(knob_r, hub_r) + 0.006
    cheek_t = 0.006
    sideways = p.chance("sideways")
    across = hub_len + 2 * (G + cheek_t) + 0.01  # the base's extent along the hinge axis
    narrow = 2.4 * hub_r + 0.01  # the base's extent across the hinge axis
    bw, bd = (max(bw, narrow), max(bd, across)) if sideways else (max(bw, across), max(bd, narrow))
    pz = bh + max(hub_r, knob_r, arm_r) + 0.004

    def local(a: float, b: float, z: float) -> tuple[float, float, float]:
        """(along the hinge axis, across it, z) in the object frame."""
        return (b, a, z) if sideways else (a, b, z)

    def size(a: float, b: float, z: float) -> tuple[float, float, float]:
        return (b, a, z) if sideways else (a, b, z)

    axis_name = "y" if sideways else "x"
    base = _block(w, (bw, bd, bh), (0.0, 0.0, bh / 2), simple)
    cheek_h = pz + 1.2 * hub_r - bh
    cheek_a = hub_len / 2 + G + cheek_t / 2
    cheeks = [w.box(size(cheek_t, 2.4 * hub_r, cheek_h), local(s * cheek_a, 0.0, bh + cheek_h / 2))
              for s in (-1, 1)]
    body = w.part("base", w.combine(base, *cheeks), base_mat)
    hub = w.cylinder(hub_r, hub_len, (0.0, 0.0, pz), axis_name, segments=16)
    arm = w.cylinder(arm_r, length, (0.0, 0.0, pz + length / 2), "z", segments=12)
    knob = (w.box((2 * knob_r,) * 3, (0.0, 0.0, pz + length + knob_r * 0.8)) if simple else
            w.sphere(knob_r, (0.0, 0.0, pz + length + knob_r * 0.8)))
    arm_id = w.part("lever_arm", w.combine(hub, arm), base_mat, parent=body,
                    joint=JointSpec("hinge", (0.0, 1.0, 0.0) if sideways else (1.0, 0.0, 0.0), (0.0, 0.0, pz),
                                    _swing(p)))
    w.part("grip", knob, grip_mat, parent=arm_id)


def _swing(p: Draws) -> tuple[float, float]:
    swing = round(math.radians(p.number("swing_deg")), 3)
    return (0.0, swing) if p.chance("one_sided") else (-swing, swing)


def _handle_press(w: ProgramWriter, p: Draws, bw: float, bd: float, bh: float, base_mat: int, grip_mat: int,
                  simple: bool) -> None:
    """A column at the back of the base carries a handle reaching forward; pushing its grip down
    turns it about its bottom-back edge, where nothing of it can swing behind the column."""
    length, arm_r, knob_r = p.number("arm_length"), p.number("arm_radius"), min(p.number("knob_radius"), 0.018)
    bd = max(bd, 0.1)
    column_h = p.number("press_height")
    col = max(0.03, 3 * arm_r)
    y_col = bd / 2 - col / 2 - 0.005
    column = _block(w, (col, col, column_h), (0.0, y_col, bh + column_h / 2), simple)
    body = w.part("base", w.combine(_block(w, (bw, bd, bh), (0.0, 0.0, bh / 2), simple), column), base_mat)
    pz, py = bh + column_h, y_col - col / 2 - G
    arm_t = 2 * arm_r
    length = max(length, bd * 0.6)
    arm = w.box((col * 0.8, length, arm_t), (0.0, py - length / 2, pz + arm_t / 2))
    grip_len = max(0.08, 4 * knob_r)
    grip = w.cylinder(knob_r, grip_len, (0.0, py - length - knob_r, pz + arm_t / 2), "x", segments=8 if simple else 16)
    lowest = knob_r - arm_t / 2  # how far the grip (across the arm's tip) hangs below the arm's bottom
    reach = math.hypot(length + 2 * knob_r, lowest + arm_t)
    room = (pz - bh - lowest - 0.01) / reach
    drop = min(math.radians(p.number("press_drop_deg")), 0.9 * math.asin(max(0.0, min(1.0, room))))
    arm_id = w.part("handle", arm, base_mat, parent=body,
                    joint=JointSpec("hinge", (1.0, 0.0, 0.0), (0.0, py, pz), (0.0, round(max(drop, 0.1), 3))))
    w.part("grip", grip, grip_mat, parent=arm_id)


def _vertical_slider(w: ProgramWriter, p: Draws, bw: float, bd: float, bh: float, base_mat: int, grip_mat: int,
                     simple: bool) -> None:
    """An upright plate on a foot with a vertical slot; a knob in front, its stem in the slot,
    slides up (+Z) the slot's free length."""
    travel = p.number("slider_travel")
    knob_r = p.number("knob_radius")
    t = 0.025
    stem_w, stem_h = 0.01, 0.02
    slot_len = travel + stem_h + 2 * G
    plate_h = slot_len + 0.05
    bd = max(bd, 0.1, 0.4 * plate_h)
    bw = max(bw, 2 * knob_r + 0.03, 0.05)
    z0 = bh + 0.025  # the slot starts above the foot
    plate = _block(w, (bw, t, plate_h), (0.0, 0.0, bh + plate_h / 2), simple)
    slot = w.box((stem_w + 2 * G, 0.012, slot_len), (0.0, -t / 2 + 0.005, z0 + slot_len / 2))
    body = w.part("base", w.combine(_block(w, (bw, bd, bh), (0.0, 0.0, bh / 2), simple), w.difference(plate, slot)),
                  base_mat)
    zc = z0 + G + stem_h / 2
    stem = w.box((stem_w, 0.011, stem_h), (0.0, -t / 2 + 0.0035, zc))  # from the cap into the slot
    cap_d = 0.02
    cap = (w.box((2 * knob_r, cap_d, max(2 * knob_r, stem_h)), (0.0, -t / 2 - G - cap_d / 2, zc)) if simple else
           w.cylinder(knob_r, cap_d, (0.0, -t / 2 - G - cap_d / 2, zc), "y", segments=20))
    w.part("slider_knob", w.combine(stem, cap), grip_mat, parent=body,
           joint=JointSpec("slide", (0.0, 0.0, 1.0), (0.0, -t / 2, zc), (0.0, round(travel, 4))))


# ---------------------------------------------------------------- sliding window
SLIDING_WINDOW = Schema("sliding_window", (
    N("width", 0.4, 1.6), N("height", 0.4, 1.4), N("depth", 0.09, 0.16), N("frame_width", 0.03, 0.08),
    K("style", ("horizontal", "vertical", "casement", "top_hung")), B("both_slide", 0.4), B("hinge_left", 0.5),
    N("sash_bar", 0.025, 0.06), N("casement_opening", 0.6, 1.571), N("top_hung_opening", 0.3, 0.9),
    B("wooden", 0.4), K("wood", kit.WOODS), K("frame_plastic", kit.PLASTICS), K("frame_metal", kit.METALS),
    B("metal_frame", 0.3), K("glass", kit.GLASSES), B("handles", 0.6), B("simple", 0.4), *FACING))


def _sash_meshes(w: ProgramWriter, x0: float, x1: float, z0: float, z1: float, y: float, t: float,
                 bar: float) -> tuple[Ref, Ref]:
    """A sash frame over [x0, x1] x [z0, z1] centred at depth y, and its pane."""
    xc, zc = (x0 + x1) / 2, (z0 + z1) / 2
    outer = w.box((x1 - x0, t, z1 - z0), (xc, y, zc))
    hole = w.box((x1 - x0 - 2 * bar, t + 0.02, z1 - z0 - 2 * bar), (xc, y, zc))
    pane = w.box((x1 - x0 - 2 * bar, 0.006, z1 - z0 - 2 * bar), (xc, y, zc))
    return w.difference(outer, hole), pane


def sliding_window(w: ProgramWriter, p: Draws) -> None:
    """A frame with sashes that slide within it (side by side on two tracks, or one above the
    other), or a single sash hinged at its side (casement) or top (top-hung), opening outwards.

    Sliding sashes run on tracks a gap apart in depth, so they pass each other, and their travel
    ends a gap short of the opening's far side: they stay inside the frame over the whole range.
    """
    width, height, depth = p.number("width"), p.number("height"), p.number("depth")
    fw = p.number("frame_width")
    if p.chance("wooden"):
        frame_mat = kit.wood(w, p, "wood")
    else:
        frame_mat = kit.metal(w, p, "frame_metal") if p.chance("metal_frame") else kit.plastic(w, p, "frame_plastic")
    pane_mat = kit.glass(w, p, "glass")
    simple = p.chance("simple")
    z0, z1 = fw, fw + height
    outer = _block(w, (width + 2 * fw, depth, height + 2 * fw), (0.0, 0.0, height / 2 + fw), simple)
    frame = w.part("frame", w.difference(outer, w.box((width, depth + 0.02, height), (0.0, 0.0, height / 2 + fw))),
                   frame_mat)
    style = p.choice("style")
    bar = min(p.number("sash_bar"), 0.2 * min(width, height) / 2)
    t, gap, overlap = min(0.04, (depth - 0.01) / 2.5), 0.003, 2 * bar
    handles = p.chance("handles")
    handle_mat = w.material("Metal", "white painted aluminium") if simple else w.material("Metal", "chrome")
    if style in ("horizontal", "vertical"):
        both = p.chance("both_slide")
        horizontal = style == "horizontal"
        span = width if horizontal else height
        lo, hi = (-width / 2, width / 2) if horizontal else (z0, z1)
        mid = (lo + hi) / 2
        travel = round(span / 2 - overlap / 2 - 2 * gap, 4)
        # (extent along the sliding direction, track depth, slide direction, moves?)
        sashes = ((lo + gap, mid + overlap / 2), -(t / 2 + gap / 2), 1.0, both), \
                 ((mid - overlap / 2, hi - gap), t / 2 + gap / 2, -1.0, True)
        if not horizontal:  # the lower sash is the inner one that lifts; the upper one lowers
            sashes = ((lo + gap, mid + overlap / 2), t / 2 + gap / 2, 1.0, True), \
                     ((mid - overlap / 2, hi - gap), -(t / 2 + gap / 2), -1.0, both)
        for (a, b), y, direction, moves in sashes:
            if horizontal:
                box = (a, b, z0 + gap, z1 - gap)
                axis = (direction, 0.0, 0.0)
            else:
                box = (-width / 2 + gap, width / 2 - gap, a, b)
                axis = (0.0, 0.0, direction)
            sash, pane = _sash_meshes(w, *box, y, t, bar)
            centre = ((box[0] + box[1]) / 2, y, (box[2] + box[3]) / 2)
            joint = JointSpec("slide", axis, centre, (0.0, travel)) if moves else None
            sid = w.part("sash", sash, frame_mat, parent=frame, joint=joint, twin="sash")
            w.part("pane", pane, pane_mat, parent=sid, twin="pane")
            if handles and moves:
                # a flat pull on the meeting bar, on the face away from the other track
                if horizontal:
                    gx, gz = (box[1] - bar / 2 if direction > 0 else box[0] + bar / 2), centre[2]
                    gsize = (bar * 0.4, 0.0015, min(0.12, 0.3 * height))
                else:
                    gx, gz = centre[0], (box[3] - bar / 2 if direction > 0 else box[2] + bar / 2)
                    gsize = (min(0.12, 0.3 * width), 0.0015, bar * 0.4)
                gy = y - t / 2 - 0.00075 if y < 0 else y + t / 2 + 0.00075
                w.part("handle", w.box(gsize, (gx, gy, gz)), handle_mat, parent=sid, twin="handle")
    else:
        y = -depth / 2 + t / 2  # flush with the outside face, so it swings out past the frame freely
        sash, pane = _sash_meshes(w, -width / 2 + gap, width / 2 - gap, z0 + gap, z1 - gap, y, t, bar)
        if style == "casement":
            side = "left" if p.chance("hinge_left") else "right"
            hinge_x = -width / 2 + gap if side == "left" else width / 2 - gap
            joint = JointSpec("hinge", (0.0, 0.0, -1.0) if side == "left" else (0.0, 0.0, 1.0),
                              (hinge_x, -depth / 2, (z0 + z1) / 2), (0.0, p.number("casement_opening")))
        else:
            joint = JointSpec("hinge", (-1.0, 0.0, 0.0), (0.0, -depth / 2, z1 - gap),
                              (0.0, p.number("top_hung_opening")))
        sid = w.part("sash", sash, frame_mat, parent=frame, joint=joint)
        w.part("pane", pane, pane_mat, parent=sid)
        if handles:  # a lever on the room side of the free edge's bar
            if style == "casement":
                hx, hz = (width / 2 - gap - bar / 2) * (1 if side == "left" else -1), (z0 + z1) / 2
                size = (bar * 0.5, 0.02, 0.1)
            else:
                hx, hz = 0.0, z0 + gap + bar / 2
                size = (0.1, 0.02, bar * 0.5)
            w.part("handle", w.box(size, (hx, y + t / 2 + 0.01, hz)), handle_mat, parent=sid)
    _face(w, p)


# ---------------------------------------------------------------- sliding-door cabinet
SLIDING_DOOR_CABINET = Schema("sliding_door_cabinet", (
    N("width", 0.4, 1.4), N("depth", 0.25, 0.55), N("height", 0.3, 1.2), C("doors", 1, 2), B("glass_doors", 0.35),
    K("wood", kit.WOODS), K("glass", kit.GLASSES), K("handle_metal", kit.METALS), B("drawers", 0.35),
    C("drawer_count", 1, 3), N("drawer_height", 0.1, 0.2), B("plinth", 0.4), C("shelves", 0, 2), B("simple", 0.4),
    *FACING))


def sliding_door_cabinet(w: ProgramWriter, p: Draws) -> None:
    """A carcass whose doors slide sideways on two tracks set into its front opening, sometimes
    over a row of drawers. Each door covers half the opening (plus an overlap) and runs to the
    opening's other side; shelves stand behind the tracks."""
    width, depth, height, t = p.number("width"), p.number("depth"), p.number("height"), 0.018
    mat, handle_mat = kit.wood(w, p, "wood"), kit.metal(w, p, "handle_metal")
    n_doors = p.count("doors")
    glass_doors = p.chance("glass_doors")
    door_mat = kit.glass(w, p, "glass") if glass_doors else mat
    simple = p.chance("simple")
    z_base = 0.06 if p.chance("plinth") else 0.0
    body_h = height
    body = w.part("body", kit.carcass(w, width, depth, body_h, t, z0=z_base), mat)
    if z_base:
        w.part("plinth", w.box((width - 0.04, depth - 0.04, z_base), (0.0, 0.01, z_base / 2)), mat, parent=body)
    doors_z0 = z_base
    if p.chance("drawers"):
        drawer_h = p.number("drawer_height")
        doors_z0 = z_base + drawer_h
        w.part("divider", w.box((width - 2 * t, depth - t - 0.01, t), (0.0, -(t + 0.01) / 2, doors_z0 + t / 2)), mat,
               parent=body)
        cols = p.count("drawer_count") if width > 0.5 else 1
        col_w = width / cols
        for c in range(cols):
            x0 = -width / 2 + c * col_w
            kit.drawer(w, body, x0 + G, x0 + col_w - G, z_base + G, doors_z0 - G, -depth / 2, depth - t - 0.02, t, mat,
                       handle_mat, t, "knob" if simple else "bar")
        doors_z0 += t
    # the door zone: inside the carcass walls, from the divider (or bottom board) to the top board
    x_lo, x_hi = -width / 2 + t, width / 2 - t
    z_lo, z_hi = (doors_z0 if doors_z0 > z_base else z_base + t), z_base + body_h - t
    door_t = 0.012 if not glass_doors else 0.008
    track_y = (-depth / 2 + 0.004 + door_t / 2, -depth / 2 + 0.004 + door_t * 1.5 + 0.004)  # front, back track
    n_shelves = p.count("shelves")
    shelf_y0 = track_y[1] + door_t / 2 + 0.006
    for i in range(n_shelves):
        z = z_lo + (z_hi - z_lo) * (i + 1) / (n_shelves + 1)
        w.part("shelf", w.box((x_hi - x_lo - 0.004, depth / 2 - t - shelf_y0 - 0.002, t),
                              (0.0, (shelf_y0 + depth / 2 - t) / 2, z)), mat, parent=body, twin="shelf")
    span = x_hi - x_lo
    overlap = 0.03
    leaf = (span + overlap) / 2 if n_doors == 2 else span / 2 + overlap / 2
    for k in range(n_doors):
        # door k starts at its own side; the single door covers the left half and runs right
        left = k == 0
        a = x_lo + G if left else x_hi - G - leaf
        b = a + leaf
        y = track_y[0] if left else track_y[1]
        travel = round(span - leaf - 2 * G - 0.002, 4)
        zc = (z_lo + z_hi) / 2
        panel = w.box((leaf, door_t, z_hi - z_lo - 2 * G), ((a + b) / 2, y, zc))
        door = w.part("door", panel, door_mat, parent=body, twin="door",
                      joint=JointSpec("slide", (1.0 if left else -1.0, 0.0, 0.0), ((a + b) / 2, y, zc), (0.0, travel)))
        grip_x = a + 0.04 if left else b - 0.04
        grip_h = min(0.12, 0.4 * (z_hi - z_lo))
        if left:  # the front door's grip stands on its face
            grip = (w.box((0.012, 0.008, grip_h), (grip_x, y - door_t / 2 - 0.004, zc)) if simple else
                    kit.bar_handle(w, grip_x, y - door_t / 2, zc, grip_h, vertical=True, standoff=0.015, radius=0.004))
        else:  # the back door's grip is a flat strip, thinner than the gap between the tracks
            grip = w.box((0.012, 0.0015, grip_h), (grip_x, y - door_t / 2 - 0.00075, zc))
        w.part("handle", grip, handle_mat, parent=door)
    _face(w, p)


# ---------------------------------------------------------------- desk with drawers
DESK_DRAWERS = Schema("desk_drawers", (
    K("style", ("pedestal", "two_pedestals", "table")), N("width", 0.8, 1.7), N("depth", 0.5, 0.8),
    N("height", 0.68, 0.78), N("pedestal_width", 0.32, 0.48), C("pedestal_drawers", 1, 3), C("table_drawers", 1, 2),
    B("pedestal_left", 0.5), K("other_side", ("legs", "door", "drawers")),
    K("middle", ("none", "drawer", "keyboard_tray")),
    N("door_opening", 1.4, 1.9), K("wood", kit.WOODS), K("handle_metal", kit.METALS), K("leg_metal", kit.METALS),
    B("metal_legs", 0.4), B("bar_handles", 0.6), B("simple", 0.4), *FACING))


def desk_drawers(w: ProgramWriter, p: Draws) -> None:
    """A desk with a pedestal of drawers (and, on the other side, legs, a door or more drawers)
    and maybe a centre drawer or keyboard tray; or a table with drawers in its apron. Every drawer
    and tray slides out along -Y; the one door hinges on a vertical edge and swings out of the front."""
    style = p.choice("style")
    width, depth, height = p.number("width"), p.number("depth"), p.number("height")
    top_t, t = 0.028, 0.018
    mat, handle_mat = kit.wood(w, p, "wood"), kit.metal(w, p, "handle_metal")
    handle = "bar" if p.chance("bar_handles") else "knob"
    simple = p.chance("simple")
    z_top = height - top_t
    top = w.part("top", _block(w, (width, depth, top_t), (0.0, 0.0, height - top_t / 2), simple), mat)
    if style == "table":
        _table_apron_drawers(w, p, top, width, depth, z_top, mat, handle_mat, handle)
        _face(w, p)
        return
    ped_w = min(p.number("pedestal_width"), width * 0.42)
    ped_d = depth - 0.04
    sign = -1.0 if p.chance("pedestal_left") else 1.0
    sides = [sign]
    other = "drawers" if style == "two_pedestals" else p.choice("other_side")
    if other != "legs":
        sides.append(-sign)
    n_drawers = p.count("pedestal_drawers")  # a second pedestal of drawers repeats the first, 1-4 in all
    if other == "drawers":
        n_drawers = min(n_drawers, 2)
    total = n_drawers * (2 if other == "drawers" else 1)
    for k, s in enumerate(sides):
        cx = s * (width / 2 - ped_w / 2)
        ped = w.part("pedestal", kit.carcass(w, ped_w, ped_d, z_top, t, cx=cx), mat, parent=top, twin="pedestal")
        x0, x1 = cx - ped_w / 2 + G, cx + ped_w / 2 - G
        if k == 1 and other == "door":
            hinge = "left" if s < 0 else "right"  # hinged on the outer edge
            kit.hinged_door(w, ped, x0, x1, G, z_top - G, -ped_d / 2, t, hinge, mat, handle_mat,
                            p.number("door_opening"), handle=handle, twin=None)
            continue
        row = z_top / n_drawers
        for r in range(n_drawers):
            kit.drawer(w, ped, x0, x1, r * row + G, (r + 1) * row - G, -ped_d / 2, ped_d - t - 0.01, t, mat, handle_mat,
                       t, handle)
    if other == "legs":
        lx = -sign * (width / 2 - 0.04)
        leg_mat = kit.metal(w, p, "leg_metal") if p.chance("metal_legs") else mat
        kit.legs(w, top, [(lx, -depth / 2 + 0.04), (lx, depth / 2 - 0.04)], z_top, 0.0, 0.04, leg_mat,
                 round_legs=not simple)
    gap_x0 = -width / 2 + (ped_w if (sign < 0 or len(sides) == 2) else 0.08)
    gap_x1 = width / 2 - (ped_w if (sign > 0 or len(sides) == 2) else 0.08)
    middle = p.choice("middle")
    if middle == "drawer" and gap_x1 - gap_x0 > 0.3 and total < 4:
        _hung_drawer(w, top, gap_x0 + 0.02, gap_x1 - 0.02, z_top, depth, mat, handle_mat, handle)
    elif middle == "keyboard_tray" and gap_x1 - gap_x0 > 0.4:
        _keyboard_tray(w, top, gap_x0 + 0.03, gap_x1 - 0.03, z_top, depth, mat)
    _face(w, p)


def _table_apron_drawers(w: ProgramWriter, p: Draws, top: int, width: float, depth: float, z_top: float, mat: int,
                         handle_mat: int, handle: str) -> None:
    """Four legs and, between them under the top, an apron box with 1-2 drawers in its front
    (the table whose drawers real data mistakes for doors)."""
    inset, leg = 0.06, 0.05
    kit.legs(w, top, kit.corners(width / 2 - inset / 2, depth / 2 - inset / 2), z_top, 0.0, leg, mat, round_legs=False)
    apron_h = 0.13
    aw, ad, t = width - 2 * inset, depth - 2 * inset, 0.018
    apron = w.part("apron", kit.carcass(w, aw, ad, apron_h, t, z0=z_top - apron_h), mat, parent=top)
    cols = p.count("table_drawers")
    col_w = aw / cols
    for c in range(cols):
        x0 = -aw / 2 + c * col_w
        kit.drawer(w, apron, x0 + G, x0 + col_w - G, z_top - apron_h + G, z_top - G, -ad / 2, ad - t - 0.01, t, mat,
                   handle_mat, t, handle)


def _hung_drawer(w: ProgramWriter, top: int, x0: float, x1: float, z_top: float, depth: float, mat: int,
                 handle_mat: int, handle: str) -> None:
    """A shallow drawer in a housing hung under the top between the pedestals."""
    h, t, d = 0.1, 0.015, depth - 0.06
    housing = w.part("drawer_housing", kit.carcass(w, x1 - x0, d, h, t, z0=z_top - h, cx=(x0 + x1) / 2), mat,
                     parent=top)
    kit.drawer(w, housing, x0 + G, x1 - G, z_top - h + G, z_top - G, -d / 2, d - t - 0.01, t, mat, handle_mat, t,
               handle, twin=None)


def _keyboard_tray(w: ProgramWriter, top: int, x0: float, x1: float, z_top: float, depth: float, mat: int) -> None:
    """A board running out along -Y between two runners under the top; its front lip is the grip."""
    rail_w, rail_h, board_t = 0.02, 0.07, 0.015
    rail_d = depth * 0.7
    y_rail = -depth / 2 + rail_d / 2 + 0.02
    for x in (x0 + rail_w / 2, x1 - rail_w / 2):
        runner = w.box((rail_w, rail_d, rail_h), (x, y_rail, z_top - rail_h / 2))
        w.part("runner", runner, mat, parent=top, twin="runner")
    bw, bd = x1 - x0 - 2 * rail_w - 2 * G, rail_d - 0.02
    zc = z_top - rail_h + 0.015 + board_t / 2
    board = w.box((bw, bd, board_t), ((x0 + x1) / 2, -depth / 2 + 0.02 + bd / 2, zc))
    lip = w.box((bw, 0.012, 0.025), ((x0 + x1) / 2, -depth / 2 + 0.02 - 0.006, zc + 0.005))
    w.part("keyboard_tray", w.combine(board, lip), mat, parent=top,
                  joint=JointSpec("slide", (0.0, -1.0, 0.0), ((x0 + x1) / 2, -depth / 2 + 0.014, zc),
                                  (0.0, round(0.7 * bd, 4))))


# ---------------------------------------------------------------- faucet with a toggle lever or two handles
TOGGLE_FAUCET_LEVER = Schema("toggle_faucet_lever", (
    K("style", ("mixer", "two_handle")), K("finish", ("chrome", "brushed nickel", "matte black steel", "brass")),
    N("column_radius", 0.012, 0.028), N("column_height", 0.08, 0.25), N("reach", 0.08, 0.22), N("rise", 0.04, 0.14),
    N("lever_length", 0.05, 0.12), N("lift", 0.35, 0.8), N("handle_spread", 0.07, 0.14), N("handle_turn", 1.2, 1.571),
    B("cross_handles", 0.4), B("swivel_spout", 0.5), N("swivel", 0.6, 1.571), B("simple", 0.4), *FACING))


def toggle_faucet_lever(w: ProgramWriter, p: Draws) -> None:
    """A single-lever mixer whose lever lifts about a horizontal axis at its back (the toggle), or
    a deck tap with two handles that each turn a quarter turn about their own vertical axis, its
    spout fixed or swivelling about the column. The spout reaches towards the user (-Y)."""
    style = p.choice("style")
    metal = w.material("Metal", p.choice("finish"))
    rc, height = p.number("column_radius"), p.number("column_height")
    reach, rise = p.number("reach"), p.number("rise")
    simple = p.chance("simple")
    seg = 8 if simple else 20
    if style == "mixer":
        base = w.cylinder(rc * 1.6, 0.012, (0.0, 0.0, 0.006), segments=seg)
        column = w.cylinder(rc, height, (0.0, 0.0, 0.012 + height / 2), segments=seg)
        top = 0.012 + height
        body = w.part("body", w.combine(base, column), metal)
        z_out = 0.012 + 0.6 * height  # the spout leaves the column's front, below the lever
        spout = w.sweep([(0.0, -rc, z_out), (0.0, -reach, z_out + 0.01), (0.0, -reach, z_out - 0.03)],
                        rc * 0.45, segments=12)
        w.part("spout", spout, metal, parent=body)
        hub_r = min(0.012, rc * 0.8)
        pz = top + hub_r + G
        length = p.number("lever_length")
        hub = w.cylinder(hub_r, 2 * hub_r, (0.0, 0.0, pz), "x", segments=seg)
        arm_t = hub_r
        arm = w.box((hub_r * 1.4, length, arm_t), (0.0, -length / 2, pz))
        # + lifts the lever's front end: about -X through the hub, nothing of it behind the pivot
        w.part("lever", w.combine(hub, arm), metal, parent=body,
               joint=JointSpec("hinge", (-1.0, 0.0, 0.0), (0.0, 0.0, pz), (0.0, p.number("lift"))))
        _face(w, p)
        return
    spread = p.number("handle_spread")
    plate_w, plate_d, plate_t = 2 * spread + 0.06, max(0.06, 2 * rc + 0.03), 0.015
    plate = _block(w, (plate_w, plate_d, plate_t), (0.0, 0.0, plate_t / 2), simple)
    column = w.cylinder(rc, height, (0.0, 0.0, plate_t + height / 2), segments=seg)
    top = plate_t + height
    stem_h, stem_r = 0.035, 0.012
    stems = [w.cylinder(stem_r, stem_h, (x, 0.0, plate_t + stem_h / 2), segments=seg) for x in (-spread, spread)]
    body = w.part("body", w.combine(plate, column, *stems), metal)
    drop = 0.8 * rise
    path = [(0.0, 0.0, top), (0.0, 0.0, top + rise * 0.6), (0.0, -reach * 0.3, top + rise),
            (0.0, -reach * 0.8, top + rise * 0.9), (0.0, -reach, top + rise - drop)]
    spout = w.sweep(path, rc * 0.5, segments=12)
    joint = None
    if p.chance("swivel_spout"):
        swivel = p.number("swivel")
        joint = JointSpec("hinge", (0.0, 0.0, 1.0), (0.0, 0.0, top), (-swivel, swivel))
    w.part("spout", spout, metal, parent=body, joint=joint)
    # a handle's arm stays clear of the column whichever way it turns
    arm = min(spread - rc - 0.012, 0.06)
    cross = p.chance("cross_handles")
    turn = p.number("handle_turn")
    for x in (-spread, spread):
        hz = plate_t + stem_h + G
        hub = w.cylinder(stem_r, 0.02, (x, 0.0, hz + 0.01), segments=seg)
        if cross:  # four short spokes over the hub
            spokes = [w.box((2 * arm * 0.6, 0.008, 0.008), (x, 0.0, hz + 0.016)),
                      w.box((0.008, 2 * arm * 0.6, 0.008), (x, 0.0, hz + 0.016))]
        else:  # one lever pointing forward
            spokes = [w.box((0.01, arm, 0.008), (x, -arm / 2, hz + 0.016))]
        axis = (0.0, 0.0, 1.0) if x < 0 else (0.0, 0.0, -1.0)  # both open by turning their front outwards
        w.part("handle", w.combine(hub, *spokes), metal, parent=body, twin="handle",
               joint=JointSpec("hinge", axis, (x, 0.0, hz), (0.0, turn)))
    _face(w, p)


BUILDS: dict[str, tuple[Callable[[ProgramWriter, Draws], None], Schema]] = {
    "button_panel": (button_panel, BUTTON_PANEL),
    "dial_panel": (dial_panel, DIAL_PANEL),
    "lever": (lever, LEVER),
    "sliding_window": (sliding_window, SLIDING_WINDOW),
    "sliding_door_cabinet": (sliding_door_cabinet, SLIDING_DOOR_CABINET),
    "desk_drawers": (desk_drawers, DESK_DRAWERS),
    "toggle_faucet_lever": (toggle_faucet_lever, TOGGLE_FAUCET_LEVER),
}
