"""The batched penetration check across objects (``jax3dc.physics.mjx_batch``): its own forward
kinematics against C MuJoCo, and padding to size classes and batching many objects against each
object checked alone at its exact sizes, on every factory category and every PartNet-Mobility
fixture: the same distances, hence the same verdicts."""

from __future__ import annotations

import dataclasses
import json

import jax
import mujoco
import numpy as np
import pytest

from eval.verdict_accuracy.ground_truth import factory_objects, imported_objects
from jax3dc.physics.mjx_batch import (EXACT, Shapes, _forward, _needed, _padded, batch_pair_distances, narrow_capacity, object_arrays,
                                      size_class)
from jax3dc.physics.sim_model import SimOptions, build_sim_model
from jax3dc.physics.states import check_states
from jax3dc.physics.tolerances import DETACH_TOL_NU
from jax3dc.physics.verdict import KINEMATIC_CHECKS, CheckRun, kinematic_inputs, penetration_model, run_checks
from tests.physics.test_physics_ground_truth import PARTNET_MOBILITY



def test_size_classes_grow_a_size_by_less_than_half():
    assert [size_class(n) for n in (1, 8, 9, 12, 13, 17, 25, 33, 49, 100)] == [8, 8, 12, 12, 16, 24, 32, 48, 64, 128]
    assert all(n <= size_class(n, 1) < 1.5 * n for n in range(2, 300))
    assert [narrow_capacity(n) for n in (1, 256, 257, 1025, 16385, 40000)] == [256, 256, 1024, 4096, 32768, 65536]


def test_forward_kinematics_equal_c_mujoco():
    """Geom poses at every check state of hinged and sliding objects, a drawer in a drawer chest
    nested below its carcass among them, against mj_kinematics (float32 against float64)."""
    for obj in factory_objects(["cabinet", "drawer_chest", "kettle", "eyeglasses", "window"], [1]):
        model = build_sim_model(obj.structure, obj.parts, obj.scale, SimOptions()).model
        qpos = check_states(build_sim_model(obj.structure, obj.parts, obj.scale, SimOptions())).qpos
        one = object_arrays(model)
        arrays, _ = _padded([one], _needed([one], [qpos]))
        mine = {k: v[0] for k, v in arrays.items()}
        data = mujoco.MjData(model)
        padded = np.zeros((len(qpos), 32), np.float32)
        padded[:, :model.nq] = qpos
        pos, rot = jax.jit(jax.vmap(_forward, in_axes=(None, 0)))(mine, padded)
        for s, q in enumerate(qpos):
            data.qpos[:] = q
            mujoco.mj_kinematics(model, data)
            np.testing.assert_allclose(np.asarray(pos[s, :model.ngeom]), data.geom_xpos, atol=2e-5, err_msg=obj.name)
            np.testing.assert_allclose(np.asarray(rot[s, :model.ngeom]).reshape(-1, 9), data.geom_xmat, atol=2e-5,
                                       err_msg=obj.name)


def test_the_kinematic_model_without_its_margin_is_the_penetration_model():
    """Candidate verdicts read the kinematic model (margin: C's proximity) as the penetration
    model instead of building it: every array is the same; without ``ignore_margin`` the margin is
    refused, since the check measures no distances within it."""
    for obj in factory_objects(["dishwasher", "eyeglasses", "oven"], [0]):
        inputs = kinematic_inputs(obj.structure, obj.parts, obj.scale)
        want = object_arrays(penetration_model(obj.structure, obj.parts, inputs))
        got = object_arrays(inputs.sim.model, ignore_margin=True)
        for field in dataclasses.fields(want):
            a, b = getattr(want, field.name), getattr(got, field.name)
            if field.name == "hulls":
                assert [[len(h) for h in tier] for tier in a] == [[len(h) for h in tier] for tier in b], obj.name
                assert all(np.array_equal(x, y) for ta, tb in zip(a, b) for ha, hb in zip(ta, tb) for x, y in zip(ha, hb))
            else:
                assert np.array_equal(a, b), (obj.name, field.name)
        with pytest.raises(ValueError, match="has margin"):
            object_arrays(inputs.sim.model)


GROUP = 7  # objects per launch
EXACT_EVERY = 4  # objects also checked alone at their exact sizes (a compile each)
# beyond what a group needs, as a sweep pads; the narrow-phase capacity as an accelerator's launches floor it
SWEEP_LIKE = Shapes(objects=8, bodies=48, geoms=192, pairs=1536, nq=48, items=1024, capacity=65536)


def _objects():
    from jax3dc.factories import FACTORIES

    fixtures = sorted(p for p in PARTNET_MOBILITY.iterdir() if (p / "mobility.urdf").is_file())
    return list(factory_objects(sorted(FACTORIES), [0])) + list(imported_objects(fixtures))


def test_padding_and_batching_change_no_verdict():
    """Every factory category and fixture: seven objects a launch, padded to size classes and
    beyond (a sweep pads to the largest shapes it has met), against every EXACT_EVERY-th object
    alone at its exact sizes (each such launch compiles: all 49 alone took ~4 minutes of a 2-core
    suite; MJX's kinematic verdicts are compared with C's in test_physics_mjx_broadphase). Depths
    agree to float32 rounding (0.01 mm), and the kinematic verdicts they give are identical."""
    objects = _objects()
    assert len(objects) >= 45
    sims, states, arrays = [], [], []
    for obj in objects:
        with np.errstate(all="ignore"):
            kinematic = build_sim_model(obj.structure, obj.parts, obj.scale, SimOptions(margin_m=DETACH_TOL_NU * obj.scale))
        bare = build_sim_model(obj.structure, obj.parts, obj.scale, SimOptions(), kinematic.pieces)
        sims.append(kinematic)
        states.append(check_states(kinematic))
        arrays.append(object_arrays(bare.model))

    batched = []
    for start in range(0, len(objects), GROUP):  # groups bound the memory of the broad phase on a CPU
        group = slice(start, start + GROUP)
        distances, shapes = batch_pair_distances(arrays[group], [s.qpos for s in states[group]], SWEEP_LIKE)
        assert shapes.objects == SWEEP_LIKE.objects and shapes.items >= sum(len(s.qpos) for s in states[group])
        assert shapes.capacity >= SWEEP_LIKE.capacity
        batched += distances
    penetrating = 0
    for n in range(0, len(objects), EXACT_EVERY):
        obj, sim, state, one = objects[n], sims[n], states[n], arrays[n]
        (alone,), shapes = batch_pair_distances([one], [state.qpos], EXACT, size_classes=False)
        assert shapes.bodies == one.nbody and shapes.pairs == max(1, len(one.pairs)), obj.name
        # depth in metres, 0 where apart; faces that touch (depth ~1e-8 m) may fall either side of 0 in float32
        depth = [np.minimum(np.where(np.isfinite(d), d, 0.0), 0.0) for d in (alone, batched[n])]
        np.testing.assert_allclose(depth[1], depth[0], atol=1e-5, err_msg=obj.name)  # 0.01 mm: float32 sums in another order
        penetrating += int((depth[0] < -1e-4).sum())
        proximity_stub = np.where(np.isfinite(alone), alone, -1.0)  # every pair touching: the detachment checks stay quiet
        verdicts = [json.dumps(run_checks(CheckRun(obj.structure, obj.parts, sim, state, d, proximity_stub, None, False),
                                          KINEMATIC_CHECKS).to_json())
                    for d in (alone, batched[n])]
        assert verdicts[0] == verdicts[1], obj.name
    assert penetrating > 150, penetrating  # 210 over these 13 objects: the comparison covers real contacts
