"""Crossings (jax3dc.physics.crossing): thin convex collision pieces of a one-mesh part are boards too
(with no edge where another piece of the part goes on), and a moving board passing through a part
that stays is caught (and blamed on that part's joint)."""

from __future__ import annotations

import dataclasses

import numpy as np
import trimesh

from jax3dc.factories import generate_object
from crossing_cases import crossings
from jax3dc.physics.crossing import _piece_boards
from eval.verdict_accuracy.ground_truth import imported_objects
from eval.verdict_accuracy.mutations import mutations_of
from jax3dc.physics.tolerances import CROSSING_MARGIN_NU
from jax3dc.physics.verdict import check_object
from jax3dc.geometry.convex_pieces import convex_pieces
from tests.shared_fixtures import partnet_object


def test_bucket_handle_swung_the_wrong_way_passes_through_the_bucket_wall():
    # the bucket is one closed mesh: its wall is no thin component, only its decomposition's pieces are
    obj = next(imported_objects([partnet_object("bucket_swing_100435")]))
    handle = next(p for p, n in obj.structure.nodes.items() if n.joint is not None)
    bucket = obj.structure.nodes[handle].parent
    pieces = {p: convex_pieces(m, 1e-3) for p, m in obj.parts.items()}
    flipped = next(m for m in mutations_of(obj.structure, obj.parts) if m.kind == "flipped axis" and m.part == handle)
    lo, hi = flipped.structure.nodes[handle].joint.range
    sweep = {handle: np.linspace(lo, hi, 9)[np.argsort(np.abs(np.linspace(lo, hi, 9)), kind="stable")]}
    assert handle not in crossings(flipped.structure, obj.parts, sweep)  # the wall is no board as a component
    assert crossings(flipped.structure, obj.parts, sweep, pieces)[handle][0] == bucket
    reasons = check_object(flipped.structure, obj.parts, obj.scale, dynamics=False)["joints"][str(handle)]["reasons"]
    assert any(r.startswith(f"penetrates part {bucket} (passes through it)") for r in reasons), reasons
    # the handle's own range swings it over the rim: clear of every wall piece
    lo, hi = obj.structure.nodes[handle].joint.range
    assert handle not in crossings(obj.structure, obj.parts, {handle: np.linspace(lo, hi, 9)}, pieces)


def test_door_swung_through_a_handle_left_on_the_frame_blames_the_handle():
    # the handle hinged on the frame instead of the leaf: the leaf (a thin board) swings through it,
    # never deeper than its own thickness
    door = generate_object("door", 0)
    leaf = next(p for p, n in door.structure.nodes.items() if n.joint is not None and n.parent in door.structure.roots())
    handle = next(c for c in door.structure.children(leaf) if door.structure.nodes[c].joint is not None)
    nodes = dict(door.structure.nodes)
    nodes[handle] = dataclasses.replace(nodes[handle], parent=door.structure.roots()[0])
    moved = dataclasses.replace(door.structure, nodes=nodes)
    lo, hi = moved.nodes[leaf].joint.range
    assert crossings(moved, door.parts, {leaf: np.linspace(lo, hi, 9)})[leaf][0] == handle
    assert leaf not in crossings(door.structure, door.parts, {leaf: np.linspace(lo, hi, 9)})
    reasons = check_object(moved, door.parts, door.scale_m_per_nu, dynamics=False)["joints"]
    assert any(r.startswith(f"penetrates part {leaf} (passes through it) while joint {leaf}")
               for r in reasons[str(handle)]["reasons"]), reasons
    assert all(j["ok"] for j in check_object(door.structure, door.parts, door.scale_m_per_nu,
                                             dynamics=False)["joints"].values())


def _slab(lo, hi) -> np.ndarray:
    return trimesh.creation.box(bounds=np.asarray([lo, hi], dtype=np.float64)).vertices


def test_a_piece_boards_edge_where_another_piece_goes_on_is_no_edge():
    # a carcass's back wall (thin in y) standing on its floor piece: the wall goes on below its
    # bottom edge, its top and side edges are free
    back = _slab([-0.4, 0.36, -0.234], [0.4, 0.41, 0.234])
    floor = _slab([-0.5, -0.34, -0.31], [0.5, 0.41, -0.235])
    board = _piece_boards([back, floor])[0]
    assert np.allclose(np.abs(board.axes[0]), [0.0, 1.0, 0.0])
    w = int(np.argmax(np.abs(board.axes[2])))  # the board's in-plane axes: x and z, in either order
    z_axis = 1 if w == 2 else 0
    z_low = 0 if board.axes[1 + z_axis] @ [0.0, 0.0, 1.0] > 0 else 1  # which end of the z axis is down
    assert board.inset[z_axis, z_low] == 0.0 and board.inset[z_axis, 1 - z_low] == CROSSING_MARGIN_NU
    assert np.all(board.inset[1 - z_axis] == CROSSING_MARGIN_NU)
    alone = _piece_boards([back])[0]
    assert np.all(alone.inset == CROSSING_MARGIN_NU) and not alone.covered[0].any() and not alone.covered[-1].any()


def test_turntable_swung_off_centre_passes_through_the_back_wall_at_its_floor():
    # a microwave's turntable on a pivot moved to its rim sweeps out through the back wall, right
    # where it stands on the floor: the wall piece's bottom edge is no edge to pass round
    oven = generate_object("microwave", 0)
    table = next(p for p, n in oven.structure.nodes.items() if n.name == "turntable")
    moved = next(m for m in mutations_of(oven.structure, oven.parts) if m.kind == "pivot moved" and m.part == table)
    reasons = check_object(moved.structure, oven.parts, oven.scale_m_per_nu, dynamics=False)["joints"][str(table)]["reasons"]
    body = moved.structure.nodes[table].parent
    assert any(r.startswith(f"penetrates part {body} (passes through it)") for r in reasons), reasons
    assert all(j["ok"] for j in check_object(oven.structure, oven.parts, oven.scale_m_per_nu,
                                             dynamics=False)["joints"].values())
