"""Building blocks shared by the factories: carcasses, hinged doors, drawers, handles, legs.

All coordinates are metres in the object frame (+Z up, front facing -Y, floor at z = 0);
the writer normalises at the end. Hinge conventions: a door opens towards -Y (outwards);
`axis` and `range` are written so that positive motion within the range is the opening.
"""

from __future__ import annotations

import math


from jax3dc.factories.writer import JointSpec, ProgramWriter, Ref
from jax3dc.parameters import Draws

WOODS = ("light oak veneer", "walnut", "white painted MDF", "pine", "dark stained birch", "ash")
METALS = ("brushed steel", "chrome", "black powder-coated steel", "brass", "aluminium")
PLASTICS = ("white plastic", "black plastic", "grey ABS", "glossy white plastic")
FABRICS = ("grey linen", "blue wool", "beige cotton", "green velvet", "charcoal felt")
GLASSES = ("clear glass", "tinted glass", "frosted glass")

EPS = 0.002  # clearance between moving parts and their housing (m)


def wood(w: ProgramWriter, p: Draws, name: str) -> int:
    """The material of parameter ``name`` (a Choice of WOODS); likewise the four below."""
    return w.material("Wood", p.choice(name))


def metal(w: ProgramWriter, p: Draws, name: str) -> int:
    return w.material("Metal", p.choice(name))


def plastic(w: ProgramWriter, p: Draws, name: str) -> int:
    return w.material("Plastic", p.choice(name))


def fabric(w: ProgramWriter, p: Draws, name: str) -> int:
    return w.material("Fabric", p.choice(name))


def glass(w: ProgramWriter, p: Draws, name: str) -> int:
    return w.material("Glass", p.choice(name))


def carcass(w: ProgramWriter, width: float, depth: float, height: float, t: float, z0: float = 0.0,
            cx: float = 0.0, through: bool = False, extra_cuts: tuple[Ref, ...] = ()) -> Ref:
    """A box open at the front (and at the back when `through`), walls of thickness t.

    `extra_cuts` are further boxes removed with the cavity (e.g. a sink opening in the top).
    """
    outer = w.box((width, depth, height), (cx, 0.0, z0 + height / 2))
    if through:
        inner = w.box((width - 2 * t, depth + 0.02, height - 2 * t), (cx, 0.0, z0 + height / 2))
    else:
        inner = w.box((width - 2 * t, depth - t + 0.01, height - 2 * t), (cx, -(t + 0.01) / 2, z0 + height / 2))
    return w.difference(outer, inner, *extra_cuts)


def open_top_tray(w: ProgramWriter, size, center, t: float) -> Ref:
    sx, sy, sz = size
    cx, cy, cz = center
    outer = w.box(size, center)
    inner = w.box((sx - 2 * t, sy - 2 * t, sz), (cx, cy, cz + t))
    return w.difference(outer, inner)


def bar_handle(w: ProgramWriter, x: float, y_front: float, z: float, length: float, vertical: bool,
               standoff: float = 0.03, radius: float = 0.006) -> Ref:
    """A U-shaped bar standing off a front face at y = y_front."""
    h = length / 2
    y = y_front - standoff
    if vertical:
        path = [(x, y_front, z - h), (x, y, z - h), (x, y, z + h), (x, y_front, z + h)]
    else:
        path = [(x - h, y_front, z), (x - h, y, z), (x + h, y, z), (x + h, y_front, z)]
    return w.sweep(path, radius)


def knob(w: ProgramWriter, x: float, y_front: float, z: float, radius: float, depth: float) -> Ref:
    return w.cylinder(radius, depth, (x, y_front - depth / 2, z), axis="y", segments=16)


def hinged_door(w: ProgramWriter, parent: int, x0: float, x1: float, z0: float, z1: float, y_front: float,
                t: float, side: str, material: int, handle_material: int, opening: float,
                name: str = "door", twin: str | None = "door", handle: str = "bar") -> tuple[int, int]:
    """A door on a vertical hinge at its `side` edge ("left" / "right"), with a handle part."""
    door = w.box((x1 - x0, t, z1 - z0), ((x0 + x1) / 2, y_front - t / 2, (z0 + z1) / 2))
    hinge_x = x0 if side == "left" else x1
    axis = (0.0, 0.0, -1.0) if side == "left" else (0.0, 0.0, 1.0)
    joint = JointSpec("hinge", axis, (hinge_x, y_front, (z0 + z1) / 2), (0.0, opening))
    door_id = w.part(name, door, material, parent=parent, joint=joint, twin=twin)
    free_x = x1 - 0.05 if side == "left" else x0 + 0.05
    zc = (z0 + z1) / 2
    if handle == "bar":
        mesh = bar_handle(w, free_x, y_front - t, zc, min(0.3, 0.4 * (z1 - z0)), vertical=True)
    else:
        mesh = knob(w, free_x, y_front - t, zc, 0.015, 0.025)
    handle_id = w.part("handle", mesh, handle_material, parent=door_id)
    return door_id, handle_id


def drawer(w: ProgramWriter, parent: int, x0: float, x1: float, z0: float, z1: float, y_front: float,
           depth: float, t: float, material: int, handle_material: int, wall: float,
           handle: str = "bar", twin: str | None = "drawer") -> tuple[int, int]:
    """A drawer (front panel over [x0, x1] x [z0, z1] + open tray) sliding out along -Y, with a handle.

    The tray is inset from the front panel by the housing's `wall` thickness plus clearance on
    every side, so it clears the carcass walls at rest and while sliding, and equal fronts give
    equal drawers (copies of one design).
    """
    xc, zc = (x0 + x1) / 2, (z0 + z1) / 2
    front = w.box((x1 - x0, t, z1 - z0), (xc, y_front - t / 2, zc))
    tx0, tx1 = x0 + wall + 0.006, x1 - wall - 0.006
    tz0, tz1 = z0 + wall + 0.006, z1 - wall - 0.02
    tray_h = max(tz1 - tz0, 0.02)
    tray = open_top_tray(w, (tx1 - tx0, depth - 0.01, tray_h), ((tx0 + tx1) / 2, y_front + (depth - 0.01) / 2,
                                                                 tz0 + tray_h / 2), 0.01)
    mesh = w.combine(front, tray)
    joint = JointSpec("slide", (0.0, -1.0, 0.0), (xc, y_front - t / 2, zc), (0.0, 0.8 * depth))
    drawer_id = w.part("drawer", mesh, material, parent=parent, joint=joint, twin=twin)
    if handle == "bar":
        grip = bar_handle(w, xc, y_front - t, zc, min(0.2, 0.5 * (x1 - x0)), vertical=False)
    else:
        grip = knob(w, xc, y_front - t, zc, 0.015, 0.025)
    handle_id = w.part("handle", grip, handle_material, parent=drawer_id)
    return drawer_id, handle_id


def rod(w: ProgramWriter, a, b, radius: float, segments: int = 12) -> Ref:
    """A cylinder between two points (a straight sweep)."""
    return w.sweep([tuple(a), tuple(b)], radius, segments=segments)


def legs(w: ProgramWriter, parent: int, positions, z_top: float, z_bottom: float, thickness: float,
         material: int, round_legs: bool, name: str = "leg") -> list[int]:
    """Vertical legs at (x, y) positions, one part each, marked as copies of one design."""
    ids = []
    h = z_top - z_bottom
    for x, y in positions:
        if round_legs:
            mesh = w.cylinder(thickness / 2, h, (x, y, z_bottom + h / 2), segments=16)
        else:
            mesh = w.box((thickness, thickness, h), (x, y, z_bottom + h / 2))
        ids.append(w.part(name, mesh, material, parent=parent, twin=name))
    return ids


def corners(half_x: float, half_y: float) -> list[tuple[float, float]]:
    return [(-half_x, -half_y), (half_x, -half_y), (-half_x, half_y), (half_x, half_y)]


def full_turn() -> tuple[float, float]:
    return (0.0, round(2 * math.pi, 3))
