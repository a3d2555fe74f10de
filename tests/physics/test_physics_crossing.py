"""Thin boards driven through each other (jax3dc.physics.crossing), on hand-built plates."""

from __future__ import annotations

import numpy as np
import trimesh

from crossing_cases import crossings
from jax3dc.physics.crossing import _mesh_boards, _path
from jax3dc.physics.kinematics import joint_motion
from jax3dc.structure.schema import Joint, Node, Structure


def _plate(extents, centre) -> trimesh.Trimesh:
    box = trimesh.creation.box(extents=extents)
    box.apply_translation(centre)
    return box


def _box_with_lid(pin: trimesh.Trimesh | None = None):
    """A 0.02-thick base plate (part 1) and a lid plate (part 2) lying on it, hinged on the x axis at
    the base's back edge (y = 0.4); opening is a positive turn about -x."""
    base = _plate([0.8, 0.8, 0.02], [0.0, 0.0, 0.0])
    lid = _plate([0.8, 0.8, 0.02], [0.0, 0.0, 0.03])
    if pin is not None:
        lid = trimesh.util.concatenate([lid, pin])
    nodes = {1: Node(parent=None, material=0),
             2: Node(parent=1, material=0, joint=Joint("hinge", (-1.0, 0.0, 0.0), (0.0, 0.4, 0.02), (0.0, 1.5)))}
    return Structure(materials={}, nodes=nodes), {1: base, 2: lid}


def test_lid_swung_the_wrong_way_passes_through_its_base():
    structure, parts = _box_with_lid()
    # the wrong way, the lid's front edge dives through the base: at most 0.02 deep as a contact
    wrong = -np.linspace(0.0, 1.5, 9)
    hit = crossings(structure, parts, {2: wrong})
    assert 2 in hit and hit[2][0] == 1
    # it crosses once the lid's far edge is more than the margin below the base: sin(q) * 0.8 > 0.05
    assert 0.05 < -hit[2][1] < 0.3
    assert crossings(structure, parts, {2: np.linspace(0.0, 1.5, 9)}) == {}  # opening: never crosses


def test_part_that_crosses_at_rest_is_left_alone():
    # a pin through the base at rest (it turns with the lid): interlocked by design, not a new crossing
    pin = _plate([0.03, 0.03, 0.3], [0.0, 0.37, 0.0])
    structure, parts = _box_with_lid(pin)
    assert crossings(structure, parts, {2: np.linspace(0.0, 0.3, 5)}) == {}


def test_path_poses_points_as_joint_motion_does_one_value_at_a_time():
    # the whole path at once must be the per-value motion (scipy's rotation), for both joint kinds
    points = np.random.default_rng(0).uniform(-1.0, 1.0, (50, 3))
    values = np.linspace(-2.0, 2.0, 7)
    for joint in (Joint("hinge", (0.3, -1.0, 0.2), (0.1, 0.4, -0.2), (-2.0, 2.0)),
                  Joint("slide", (0.0, 0.0, 2.0), (0.0, 0.0, 0.0), (-2.0, 2.0))):
        path = _path(joint, values, points)
        for v, posed in zip(values, path):
            np.testing.assert_allclose(posed, joint_motion(joint, float(v), points), atol=1e-12)


def test_boards_shared_between_calls_are_read_only_and_give_the_same_answer():
    # the K candidates of an object share its parts' boards: a cached board must not be writable,
    # and the second call (a hit) must answer as the first (computed)
    structure, parts = _box_with_lid()
    wrong = -np.linspace(0.0, 1.5, 9)
    first = crossings(structure, parts, {2: wrong})
    boards = _mesh_boards(parts[1])
    assert boards and not boards[0].covered.flags.writeable and not boards[0].centre.flags.writeable
    assert crossings(structure, parts, {2: wrong}) == first
    # a copy of the mesh moved by a hair is another key: its boards are its own
    moved = parts[1].copy()
    moved.apply_translation([0.0, 0.0, 1e-6])
    assert _mesh_boards(moved)[0].centre[2] != boards[0].centre[2]


def _board_arrays(boards) -> list:
    return [(b.centre, b.axes, b.half, b.covered, b.inset) for b in boards]


def test_boards_come_from_the_disk_in_a_new_process_and_a_torn_entry_is_a_miss(tmp_path, monkeypatch):
    """With the disk cache on, a process that has not seen the part reads its boards and surface
    points back exactly, finding none; an entry that is not boards is found again and rewritten."""
    import jax3dc.physics.crossing as crossing

    monkeypatch.setenv("JAX3DC_PIECE_CACHE", str(tmp_path / "cache"))
    structure, parts = _box_with_lid()
    crossing._cache.clear()
    wrong = {2: -np.linspace(0.0, 1.5, 9)}
    first = crossings(structure, parts, wrong)
    boards, surface = _board_arrays(_mesh_boards(parts[1])), crossing._cached_surface(parts[1]).copy()
    entries = sorted((tmp_path / "cache").rglob("*.npz"))
    assert len(entries) == 5  # two meshes' boards and surfaces, and the boards of no pieces (one entry for both)

    def refuse(*_):
        raise AssertionError("found again")

    crossing._cache.clear()  # as a new process starts
    with monkeypatch.context() as m:
        m.setattr(crossing, "_boards", refuse)
        m.setattr(crossing, "_surface", refuse)
        assert crossings(structure, parts, wrong) == first
        again = _mesh_boards(parts[1])
        assert all(np.array_equal(x, y) and x.dtype == y.dtype for a, b in zip(boards, _board_arrays(again)) for x, y in zip(a, b))
        assert np.array_equal(crossing._cached_surface(parts[1]), surface)
        assert not again[0].covered.flags.writeable
    for entry in entries:
        entry.write_bytes(b"not an entry")
    crossing._cache.clear()
    assert crossings(structure, parts, wrong) == first
    assert all(e.read_bytes() != b"not an entry" for e in entries)
    crossing._cache.clear()
