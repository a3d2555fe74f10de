"""The floor check (jax3dc.physics.floor): joints that drive a part through the floor the object stands on."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest
import trimesh
from scipy.spatial import ConvexHull

from jax3dc.factories import generate_object
from jax3dc.physics.floor import _hull_vertices, first_below_floor
from eval.verdict_accuracy.mutations import mutations_of
from jax3dc.physics.tolerances import FLOOR_TOL_NU
from jax3dc.physics.findings import FAILURE
from jax3dc.physics.verdict import check_object, verdict_with_curves
from jax3dc.structure.schema import Joint, Node, Structure


def _flap(range_, axis=(-1.0, 0.0, 0.0)):
    """A 1 x 1 x 0.1 base on the floor (z = 0) and a 0.5-long flap standing on its back edge, hinged there."""
    base = trimesh.creation.box(extents=[1.0, 1.0, 0.1])
    base.apply_translation([0.0, 0.0, 0.05])
    flap = trimesh.creation.box(extents=[1.0, 0.02, 0.5])
    flap.apply_translation([0.0, 0.51, 0.35])
    nodes = {1: Node(parent=None, material=0),
             2: Node(parent=1, material=0, joint=Joint("hinge", axis, (0.0, 0.52, 0.1), range_))}
    return Structure(materials={}, nodes=nodes), {1: base, 2: flap}


def test_flap_swung_down_behind_its_base_goes_through_the_floor_at_the_closed_form_angle():
    structure, parts = _flap((0.0, 2.5))
    # about -x a positive turn tips the flap's top backwards (+y), off the base: its back tip edge (0.5
    # above the pivot, the pivot 0.1 above the floor) goes below z = -FLOOR_TOL_NU once 0.5 cos q < -(0.1 + FLOOR_TOL_NU)
    values = np.linspace(0.0, 2.5, 251)
    got = first_below_floor(structure, parts, 2, values)
    expect = np.arccos(-(0.1 + FLOOR_TOL_NU) / 0.5)
    assert got == pytest.approx(expect, abs=0.02)
    assert first_below_floor(structure, parts, 2, np.linspace(0.0, 1.5, 51)) is None  # lying flat: on it, not through


def test_slide_out_through_the_bottom_is_caught():
    structure, parts = _flap((0.0, 1.0))
    down = dataclasses.replace(structure.nodes[2].joint, type="slide", axis=(0.0, 0.0, -1.0))
    structure = dataclasses.replace(structure, nodes={**structure.nodes, 2: dataclasses.replace(structure.nodes[2], joint=down)})
    # the flap's bottom starts 0.1 above the floor: it is through once slid more than 0.1 + FLOOR_TOL_NU
    got = first_below_floor(structure, parts, 2, np.linspace(0.0, 1.0, 101))
    assert got == pytest.approx(0.1 + FLOOR_TOL_NU, abs=0.011)


def test_flipped_laptop_screen_penetrates_the_floor_and_the_real_one_passes():
    laptop = generate_object("laptop", 0)
    screen = next(p for p, n in laptop.structure.nodes.items() if n.name == "screen_lid")
    truth = check_object(laptop.structure, laptop.parts, laptop.scale_m_per_nu, dynamics=False)["joints"][str(screen)]
    assert truth["ok"], truth
    flipped = next(m for m in mutations_of(laptop.structure, laptop.parts) if m.kind == "flipped axis" and m.part == screen)
    verdict = verdict_with_curves(flipped.structure, laptop.parts, laptop.scale_m_per_nu, dynamics=False)[0]
    failures = verdict.joint_findings(screen, FAILURE)
    assert any(f.check == "floor" for f in failures), failures
    assert flipped.caught(failures)


def test_subtree_the_object_stands_on_is_not_checked():
    # the flap reaching down to the floor at rest carries the object: turning it tips the object over
    structure, parts = _flap((0.0, 2.5))
    parts[2] = trimesh.creation.box(extents=[1.0, 0.02, 0.6])
    parts[2].apply_translation([0.0, 0.51, 0.3])
    assert first_below_floor(structure, parts, 2, np.linspace(0.0, 2.5, 26)) is None
    parts[2].apply_translation([0.0, 0.0, FLOOR_TOL_NU])  # lifted clear of the floor: checked again
    assert first_below_floor(structure, parts, 2, np.linspace(0.0, 2.5, 26)) is not None


def test_flat_part_keeps_its_outline_without_numpy_warnings():
    """A flat part (a predicted door as one sheet) has a zero-volume hull: its candidate lowest
    points are still every corner of its outline (scipy's 2-D hull), and nothing is printed."""
    rng = np.random.default_rng(0)
    sheet = np.c_[rng.uniform(-0.5, 0.5, (30, 2)), np.full(30, 0.2)]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        kept = _hull_vertices(trimesh.Trimesh(vertices=sheet))
    assert not [w for w in caught if issubclass(w.category, RuntimeWarning)], [str(w.message) for w in caught]
    kept_rows = {tuple(row) for row in kept}
    assert {tuple(row) for row in sheet[ConvexHull(sheet[:, :2]).vertices]} <= kept_rows
    assert kept_rows <= {tuple(row) for row in sheet}
