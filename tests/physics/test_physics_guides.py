"""A slide child carried out of the part it runs in (jax3dc.physics.guides)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from jax3dc.factories import generate_object
from jax3dc.physics.guides import carried_out_of_guide
from jax3dc.physics.tolerances import SLIDE_GUIDE_OVERLAP_NU
from jax3dc.physics.verdict import check_object


@pytest.fixture(scope="module")
def chest():
    return generate_object("drawer_chest", 0)


def _drawers(obj) -> list[int]:
    """Slide-jointed parts from the lowest up."""
    ids = [p for p, n in obj.structure.nodes.items() if n.joint is not None and n.joint.type == "slide"]
    return sorted(ids, key=lambda p: float(obj.parts[p].bounds[0, 2]))


def _reparented(structure, part, parent):
    nodes = dict(structure.nodes)
    nodes[part] = dataclasses.replace(nodes[part], parent=parent)
    return dataclasses.replace(structure, nodes=nodes)


def test_drawers_in_their_carcass_stay_in_it(chest):
    for drawer in _drawers(chest):
        assert carried_out_of_guide(chest.structure, chest.parts, drawer) is None


def test_drawer_hung_on_its_neighbour_is_carried_out_of_its_slot(chest):
    low, upper = _drawers(chest)[:2]
    carcass = chest.structure.nodes[low].parent
    structure = _reparented(chest.structure, upper, low)
    found = carried_out_of_guide(structure, chest.parts, upper)
    assert found is not None
    guide, values = found
    assert guide == carcass and set(values) == {upper, low}
    reasons = check_object(structure, chest.parts, chest.scale_m_per_nu, dynamics=False)["joints"][str(upper)]["reasons"]
    assert any(r.startswith("detached from its guide") for r in reasons), reasons


def test_a_part_held_by_what_it_runs_in_is_not_flagged(chest):
    # the upper drawer parented on the lower one, but shifted into it: the lower drawer now contains
    # it across the axis (a tray in a drawer), so the lower drawer is its guide and carries it along
    low, upper = _drawers(chest)[:2]
    parts = dict(chest.parts)
    rigid = [upper] + [c for c in chest.structure.children(upper) if chest.structure.nodes[c].joint is None]
    shrink = np.diag([0.5, 0.5, 0.5, 1.0])
    shrink[:3, 3] = parts[low].bounds.mean(axis=0) - 0.5 * parts[upper].bounds.mean(axis=0)
    for p in rigid:  # the drawer and its handle, halved and centred in the lower drawer
        parts[p] = parts[p].copy().apply_transform(shrink)
    structure = _reparented(chest.structure, upper, low)
    assert carried_out_of_guide(structure, parts, upper) is None


def test_lever_shorter_than_the_guide_overlap_runs_in_its_slot():
    # a toaster's lever lies alongside the body over all of its own length (less than
    # SLIDE_GUIDE_OVERLAP_NU): slid the wrong way it leaves the top of the body, not a lid lifted off
    toaster = generate_object("toaster", 0)
    lever = next(p for p, n in toaster.structure.nodes.items() if n.joint is not None and n.joint.type == "slide")
    joint = toaster.structure.nodes[lever].joint
    t = np.asarray(toaster.parts[lever].vertices) @ np.asarray(joint.axis, dtype=np.float64)
    assert t.max() - t.min() < SLIDE_GUIDE_OVERLAP_NU  # the case the full-length rule is for
    nodes = dict(toaster.structure.nodes)
    nodes[lever] = dataclasses.replace(nodes[lever], joint=dataclasses.replace(joint, axis=tuple(-np.asarray(joint.axis))))
    flipped = dataclasses.replace(toaster.structure, nodes=nodes)
    reasons = check_object(flipped, toaster.parts, toaster.scale_m_per_nu, dynamics=False)["joints"][str(lever)]["reasons"]
    assert any(r.startswith("detached from parent (slides out of its guide)") for r in reasons), reasons
    assert check_object(toaster.structure, toaster.parts, toaster.scale_m_per_nu,
                        dynamics=False)["joints"][str(lever)]["reasons"] == []
