"""The reachability model collides only the collision pieces a joint's sweep brings near each other
(jax3dc.physics.dynamics.reachability_model): the same rollouts as colliding every piece pair of the
part pairs in contact, with far fewer pairs for MJX to compile."""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import pytest

from jax3dc.factories import generate_object
from jax3dc.physics import cpu_backend, dynamics
from jax3dc.physics.dynamics import SETTLE_STEPS, reachability_model, tolerated_pairs
from jax3dc.physics.findings import describe
from eval.verdict_accuracy.ground_truth import imported_objects
from jax3dc.physics.sim_model import SimOptions, build_sim_model
from jax3dc.physics.states import check_states
from jax3dc.physics.tolerances import DETACH_TOL_NU, PENETRATION_TOL_NU, RECONTACT_DEPTH_NU
from tests.shared_fixtures import partnet_object


def _objects():
    for category in ("cabinet", "dishwasher", "toilet"):
        obj = generate_object(category, 0)
        yield category, obj.structure, obj.parts, obj.scale_m_per_nu
    safe = next(imported_objects([partnet_object("safe_rotate_101593")]))
    yield "safe", safe.structure, safe.parts, safe.scale


OBJECTS = {name: rest for name, *rest in _objects()}


def _exclude(structure, parts, scale):
    kinematic = build_sim_model(structure, parts, scale, SimOptions(margin_m=DETACH_TOL_NU * scale))
    states = check_states(kinematic)
    distances = cpu_backend.pair_distances(kinematic.model, states.qpos)
    return kinematic, tolerated_pairs(kinematic, distances, PENETRATION_TOL_NU * scale, states, RECONTACT_DEPTH_NU * scale)


def _pair_count(model: mujoco.MjModel) -> int:
    """Collision geom pairs the model may test: explicit pairs, or filtered pairs of different bodies."""
    if model.npair:
        return int(model.npair)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    excluded = {(int(b1), int(b2)) for b1, b2 in zip(model.exclude_signature >> 16, model.exclude_signature & 0xFFFF)}
    count = 0
    for g1 in range(model.ngeom):
        for g2 in range(g1 + 1, model.ngeom):
            b1, b2 = int(model.geom_bodyid[g1]), int(model.geom_bodyid[g2])
            collide = (model.geom_contype[g1] & model.geom_conaffinity[g2]) or (model.geom_contype[g2] & model.geom_conaffinity[g1])
            count += bool(b1 != b2 and collide and (min(b1, b2), max(b1, b2)) not in excluded)
    return count


@pytest.mark.parametrize("name", sorted(OBJECTS))
def test_pruned_pairs_end_the_rollouts_where_all_pairs_do(name):
    structure, parts, scale = OBJECTS[name]
    kinematic, exclude = _exclude(structure, parts, scale)
    full = build_sim_model(structure, parts, scale, SimOptions(actuators=True, exclude=exclude, frictionless=True), kinematic.pieces)
    pruned = reachability_model(structure, parts, scale, exclude, kinematic.pieces)
    assert _pair_count(pruned.model) <= _pair_count(full.model)
    # each joint driven to each limit, the others held at rest: the reachability check's rollouts
    rest = full.model.qpos0
    targets = []
    for k in range(len(full.joint_parts)):
        for end in (0, 1):
            ctrl = rest[full.joint_qpos].copy()
            ctrl[k] = full.joint_range[k, end]
            targets.append(ctrl)
    start = np.repeat(rest[None], len(targets), axis=0)
    a = cpu_backend.final_qpos(full.model, start, np.asarray(targets), SETTLE_STEPS)
    b = cpu_backend.final_qpos(pruned.model, start, np.asarray(targets), SETTLE_STEPS)
    np.testing.assert_allclose(b[:, full.joint_qpos], a[:, full.joint_qpos], atol=1e-3)


def test_safe_compiles_far_fewer_pairs():
    structure, parts, scale = OBJECTS["safe"]
    kinematic, exclude = _exclude(structure, parts, scale)
    full = build_sim_model(structure, parts, scale, SimOptions(actuators=True, exclude=exclude, frictionless=True), kinematic.pieces)
    pruned = reachability_model(structure, parts, scale, exclude, kinematic.pieces)
    assert _pair_count(pruned.model) * 5 < _pair_count(full.model)


def test_contact_pairs_are_frictionless_pairs_only():
    structure, parts, scale = OBJECTS["cabinet"]
    with pytest.raises(ValueError, match="frictionless"):
        build_sim_model(structure, parts, scale, SimOptions(contact_pairs=frozenset()))
    sim = build_sim_model(structure, parts, scale, SimOptions(frictionless=True, contact_pairs=frozenset()))
    data = mujoco.MjData(sim.model)
    mujoco.mj_forward(sim.model, data)
    assert sim.model.npair == 0 and data.ncon == 0


def test_full_turn_wheels_do_not_sag_but_limited_ones_do(monkeypatch):
    # the suitcase settling on the floor rolls its held wheels by ~0.196 rad (C): a wheel's every
    # angle is a pose, so a full-turn hinge is not checked; the same wheel with half a turn of range is
    obj = generate_object("suitcase", 0)
    wheels = [p for p, n in obj.structure.nodes.items() if n.name == "wheel"]
    monkeypatch.setattr(dynamics, "GRAVITY_JOINT_DRIFT", 0.1)
    sagged = {f.joints[0] for f in dynamics.gravity(obj.structure, obj.parts, obj.scale_m_per_nu, None) if f.check == "sag"}
    assert wheels and not sagged & set(wheels)
    nodes = dict(obj.structure.nodes)
    for w in wheels:
        nodes[w] = dataclasses.replace(nodes[w], joint=dataclasses.replace(nodes[w].joint, range=(0.0, 3.0)))
    found = dynamics.gravity(dataclasses.replace(obj.structure, nodes=nodes), obj.parts, obj.scale_m_per_nu, None)
    sagged = {f.joints[0]: f for f in found if f.check == "sag"}
    assert set(wheels) <= set(sagged) and all(sagged[w].depth > 0.1 for w in wheels), found
    assert all(describe(sagged[w]).startswith("sags under gravity") for w in wheels)
