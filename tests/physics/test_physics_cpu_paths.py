"""The C MuJoCo paths of the penetration check agree: the per-state loop (the reference), the same
loop over worker processes, and threaded rollout with a signed-distance sensor per body pair."""

from __future__ import annotations

import numpy as np
import pytest

from jax3dc.factories import generate_object
from jax3dc.physics.cpu_backend import PairDistancePool, RolloutDepths, pair_distances
from jax3dc.physics.sim_model import SimOptions, build_sim_model
from jax3dc.physics.tolerances import PENETRATION_TOL_NU


@pytest.fixture(scope="module")
def cabinet_states():
    obj = generate_object("cabinet", 0)
    sim = build_sim_model(obj.structure, obj.parts, obj.scale_m_per_nu, SimOptions())
    rng = np.random.default_rng(0)
    lo, hi = sim.joint_range[:, 0], sim.joint_range[:, 1]
    qpos = np.repeat(sim.model.qpos0[None], 512, axis=0)
    # half the span beyond each limit: the doors swing into the carcass, the drawer through its back
    qpos[:, sim.joint_qpos] = rng.uniform(lo - 0.5 * (hi - lo), hi + 0.5 * (hi - lo), size=(512, len(lo)))
    return sim, qpos, PENETRATION_TOL_NU * obj.scale_m_per_nu


def test_process_pool_gives_the_loops_distances(cabinet_states):
    sim, qpos, _ = cabinet_states
    with PairDistancePool(sim.xml, sim.assets, workers=2) as pool:
        pool.start(qpos)
        np.testing.assert_array_equal(pool.map(qpos), pair_distances(sim.model, qpos))


def test_rollout_sensors_give_the_loops_penetrations(cabinet_states):
    sim, qpos, tol = cabinet_states
    loop = pair_distances(sim.model, qpos)
    rollout = RolloutDepths(sim.xml, sim.assets)(qpos, threads=2)
    deep = loop < -tol
    assert deep.sum() > 100  # the states do penetrate, so agreement means something
    np.testing.assert_array_equal(rollout < -tol, deep)
    # where both see a penetration, the depths are the same convex-pair depths (within 1 mm here)
    np.testing.assert_allclose(rollout[deep], loop[deep], atol=1e-3)
