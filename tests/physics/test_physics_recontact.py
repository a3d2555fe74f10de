"""A servo stopped by a contact its own sweep makes anew (jax3dc.physics.dynamics.tolerated_pairs)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from jax3dc.factories import generate_object
from jax3dc.physics.dynamics import tolerated_pairs
from jax3dc.physics.sim_model import SimOptions, build_sim_model
from jax3dc.physics.states import check_states
from jax3dc.physics import cpu_backend
from jax3dc.physics.tolerances import DETACH_TOL_NU, PENETRATION_TOL_NU, RECONTACT_DEPTH_NU
from eval.verdict_accuracy.ground_truth import imported_objects
from jax3dc.physics.verdict import check_object
from tests.shared_fixtures import partnet_object


@pytest.fixture(scope="module")
def cabinet():
    return generate_object("cabinet", 0)


def _door(obj) -> int:
    return next(p for p, n in obj.structure.nodes.items() if n.joint is not None and n.joint.type == "hinge")


def _with_hi(structure, part, hi):
    nodes = dict(structure.nodes)
    joint = dataclasses.replace(nodes[part].joint, range=(nodes[part].joint.range[0], hi))
    nodes[part] = dataclasses.replace(nodes[part], joint=joint)
    return dataclasses.replace(structure, nodes=nodes)


def _kept(structure, parts, scale) -> frozenset:
    sim = build_sim_model(structure, parts, scale, SimOptions(margin_m=DETACH_TOL_NU * scale))
    states = check_states(sim)
    distances = cpu_backend.pair_distances(sim.model, states.qpos)
    tolerated = tolerated_pairs(sim, distances, PENETRATION_TOL_NU * scale, states, RECONTACT_DEPTH_NU * scale)
    ids = sorted(structure.nodes)
    return frozenset((a, b) for i, a in enumerate(ids) for b in ids[i + 1:]) - tolerated


def test_door_opened_round_its_carcass_corner_cannot_reach_its_limit(cabinet):
    door = _door(cabinet)
    carcass = cabinet.structure.nodes[door].parent
    # 225 degrees: past lying flat beside the carcass the door folds back round its side wall,
    # never deeper than its own thickness (below the sweep's penetration tolerance)
    structure = _with_hi(cabinet.structure, door, 1.25 * np.pi)
    assert (min(door, carcass), max(door, carcass)) in _kept(structure, cabinet.parts, cabinet.scale_m_per_nu)
    reasons = check_object(structure, cabinet.parts, cabinet.scale_m_per_nu)["joints"][str(door)]["reasons"]
    assert any(r.startswith("limit unreachable: hi") for r in reasons), reasons
    assert not any(r.startswith("penetrates") for r in reasons), reasons  # only the stop finds it


def test_door_opened_short_of_its_carcass_reaches_its_limit(cabinet):
    door = _door(cabinet)
    twin = next(p for p, n in cabinet.structure.nodes.items()
                if p != door and n.joint is not None and n.joint.type == "hinge")
    # both doors of the mirrored pair, or the relation check flags the pair as moving differently
    structure = _with_hi(_with_hi(cabinet.structure, door, 0.5 * np.pi), twin, 0.5 * np.pi)
    reasons = check_object(structure, cabinet.parts, cabinet.scale_m_per_nu)["joints"][str(door)]["reasons"]
    assert reasons == []


def test_sash_grazing_its_rail_along_its_travel_is_no_stop():
    # the sash slides along a frame rail it grazes at rest (7 mm deep); the sampled hulls taper, so
    # the graze deepens to 16 mm at the top: deeper than RECONTACT_DEPTH_NU (10 mm here) but only 8 mm
    # deeper than at rest, a slide along its guide and not a new contact (MJX, whose contact normal
    # follows the tapered face, would wedge the sash there)
    window = generate_object("window", 0)
    sash = next(p for p, n in window.structure.nodes.items() if n.joint is not None)
    frame = window.structure.nodes[sash].parent
    assert (min(sash, frame), max(sash, frame)) not in _kept(window.structure, window.parts, window.scale_m_per_nu)


def test_handle_interlocked_with_its_lugs_is_no_stop():
    # the bucket's handle runs through its lugs: 4-8 cm deep over the whole swing, never grazing, so
    # however that depth varies along the sweep the pair is the rest check's business, not a stop
    bucket = next(imported_objects([partnet_object("bucket_swing_100435")]))
    handle = next(p for p, n in bucket.structure.nodes.items() if n.joint is not None)
    body = bucket.structure.nodes[handle].parent
    assert (min(handle, body), max(handle, body)) not in _kept(bucket.structure, bucket.parts, bucket.scale)
