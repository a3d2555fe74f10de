"""The batched MJX penetration check (``jax3dc.physics.mjx_backend``) against plain references:
a brute-force separating-axis test in numpy (every face normal, every edge pair), C MuJoCo on
the same joint states, and itself without the broad phase."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import pytest
from scipy.spatial import ConvexHull
from scipy.spatial.transform import Rotation

from jax3dc.physics import mjx_backend
from jax3dc.physics.mjx_backend import CHUNK_ITEMS, PairDistances, capacity_for, penetration_depth


def _brute_force_depth(a: np.ndarray, b: np.ndarray) -> float:
    """Smallest overlap of two point sets' hulls over all face normals and all edge-pair axes."""
    faces, edges = [], []
    for points in (a, b):
        hull = ConvexHull(points)
        faces.append(hull.equations[:, :3])
        pairs = np.array(sorted({tuple(sorted((s[i], s[(i + 1) % 3]))) for s in hull.simplices for i in range(3)}))
        edges.append(points[pairs[:, 1]] - points[pairs[:, 0]])
    axes = np.concatenate(faces + [np.cross(edges[0][:, None], edges[1][None]).reshape(-1, 3)])
    length = np.linalg.norm(axes, axis=1)
    axes = axes[length > 1e-9] / length[length > 1e-9, None]
    pa, pb = axes @ a.T, axes @ b.T
    return float(np.minimum(pa.max(1) - pb.min(1), pb.max(1) - pa.min(1)).min())


def _hull_arrays(points: np.ndarray) -> dict:
    """Hull data padded to one size for every shape here (32 vertices), as the batched check pads."""
    vert, inner, normals, edge, edge_normals = mjx_backend._hull(points)
    pad = mjx_backend._pad_to
    return {"vert": jnp.asarray(pad(vert, 32), jnp.float32), "inner": jnp.asarray(inner, jnp.float32),
            "face_normal": jnp.asarray(pad(normals, 60), jnp.float32), "edge": jnp.asarray(pad(edge, 90)),
            "edge_face_normal": jnp.asarray(pad(edge_normals, 90), jnp.float32)}


def test_penetration_depth_is_the_separating_axis_depth():
    """Random hulls (blocks and 6–32-point blobs) in random poses: where they interpenetrate the
    depth equals the brute-force SAT depth; where they are apart it is negative."""
    rng = np.random.default_rng(0)
    checked = {"overlap": 0, "apart": 0}
    for trial in range(200):
        shapes = []
        for _ in range(2):
            if rng.random() < 0.3:
                shapes.append(np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
                              * rng.uniform(0.05, 0.5, 3))
            else:
                shapes.append(rng.normal(size=(int(rng.integers(6, 33)), 3)) * rng.uniform(0.1, 0.5, 3))
        poses = [(rng.uniform(-0.4, 0.4, 3), Rotation.random(random_state=trial * 2 + k).as_matrix()) for k in range(2)]
        world = [pos + shape @ rot.T for shape, (pos, rot) in zip(shapes, poses)]
        expected = _brute_force_depth(*world)
        got = float(jax.jit(penetration_depth)(jnp.asarray(poses[0][0], jnp.float32), jnp.asarray(poses[0][1], jnp.float32),
                                      _hull_arrays(shapes[0]),
                                      jnp.asarray(poses[1][0], jnp.float32), jnp.asarray(poses[1][1], jnp.float32),
                                      _hull_arrays(shapes[1])))
        if expected > 0:
            assert got == pytest.approx(expected, abs=2e-5), trial
            checked["overlap"] += 1
        else:
            assert got < 1e-6, trial
            checked["apart"] += 1
    assert min(checked.values()) >= 30, checked


def _cabinet():
    from jax3dc.factories import generate_object
    from jax3dc.physics.sim_model import SimOptions, build_sim_model

    obj = generate_object("cabinet", 0)
    sim = build_sim_model(obj.structure, obj.parts, obj.scale_m_per_nu, SimOptions())
    rng = np.random.default_rng(1)
    qpos = np.repeat(sim.model.qpos0[None], 96, axis=0)
    lo, hi = sim.joint_range[:, 0], sim.joint_range[:, 1]
    span = hi - lo
    # states inside the ranges and up to half a range beyond them (doors swung into the carcass)
    qpos[:, sim.joint_qpos] = rng.uniform(lo - span / 2, hi + span / 2, size=(96, len(lo)))
    return sim, qpos


@pytest.mark.slow
def test_batched_check_matches_c_mujoco_and_needs_no_pair_the_broad_phase_drops(monkeypatch):
    from jax3dc.physics.cpu_backend import pair_distances

    sim, qpos = _cabinet()
    check = PairDistances(sim.model)
    got = np.asarray(check(qpos), dtype=np.float64)
    c = pair_distances(sim.model, qpos)
    # C's EPA overestimates by up to ~0.6 mm here (a handle seated 0.06 mm deep reads 0.1–0.65 mm),
    # so pairs are compared with a margin: deeper than 2 mm in one means deeper than 1 mm in the other
    deep_c, deep_g = c < -2e-3, got < -2e-3
    assert deep_c.sum(axis=(1, 2)).any() and not deep_c.any(axis=(1, 2)).all()
    assert np.all(got[deep_c] < -1e-3) and np.all(c[deep_g] < -1e-3)
    both = np.isfinite(c) & np.isfinite(got)
    np.testing.assert_allclose(got[both], c[both], atol=1e-3)
    # the broad phase keeps far fewer pairs than there are, and dropping them changes nothing
    assert check.survivors(qpos) < 0.5 * len(qpos) * len(check.pairs)
    monkeypatch.setattr(mjx_backend, "BOX_SLACK_M", 1e6)  # every pair reaches the narrow phase
    everything = PairDistances(sim.model)
    assert everything.survivors(qpos) == len(qpos) * len(everything.pairs)
    np.testing.assert_array_equal(np.asarray(everything(qpos)), got)


def test_capacity_covers_the_count_in_whole_chunks():
    assert capacity_for(0) == 0
    for count in (1, 255, 257, 5000, CHUNK_ITEMS, CHUNK_ITEMS + 1, 10 * CHUNK_ITEMS + 7):
        capacity = capacity_for(count)
        assert capacity >= count
        assert capacity % min(CHUNK_ITEMS, capacity) == 0
        assert capacity < 2 * count + 256


def test_non_mesh_collision_geoms_are_refused_by_name():
    model = mujoco.MjModel.from_xml_string("""
        <mujoco><worldbody><geom name="floor" type="plane" size="1 1 1"/>
          <body><joint type="slide" axis="0 0 1"/><geom name="block" type="box" size=".1 .1 .1"/></body>
        </worldbody></mujoco>""")
    with pytest.raises(ValueError, match="'floor'"):
        PairDistances(model)


def test_objects_of_one_structure_share_the_narrow_phase_compile():
    """A lid box at two scales: same bodies, pairs and padded hull sizes, other numbers; the second
    compiles no new narrow phase, and each gives its own (C-checked) answer."""
    from jax3dc.physics.cpu_backend import pair_distances
    from jax3dc.physics.sim_model import SimOptions, build_sim_model
    from tests.physics.test_physics_cli_mjx import _lid_box

    structure, parts = _lid_box()
    qpos = np.random.default_rng(0).uniform(-1.8, 1.8, size=(48, 1))
    compiled = []
    for scale in (0.5, 0.8):
        sim = build_sim_model(structure, parts, scale, SimOptions())
        got = np.asarray(PairDistances(sim.model)(qpos), dtype=np.float64)
        compiled.append(mjx_backend._narrow_phase._cache_size())
        c = pair_distances(sim.model, qpos)
        deep = c < -2e-3 * scale
        assert deep.any() and np.array_equal(deep, got < -2e-3 * scale)
        np.testing.assert_allclose(got[deep], c[deep], atol=1e-3)
    assert compiled[1] == compiled[0]


def test_both_backends_give_the_same_kinematic_verdicts():
    """``check_object`` on C MuJoCo and on the batched MJX check: a good lid and one hinged the
    wrong way (it swings into its base), same verdicts and reasons."""
    from jax3dc.physics.verdict import check_object
    from jax3dc.structure import parse_structure, to_json
    from tests.physics.test_physics_cli_mjx import _lid_box

    structure, parts = _lid_box()
    flipped = parse_structure(to_json(structure).replace('"axis":[-1.0,0.0,0.0]', '"axis":[1.0,0.0,0.0]'),
                              part_ids=parts.keys())
    verdicts = {}
    for name, doc in (("good", structure), ("flipped", flipped)):
        c = check_object(doc, parts, 0.5, backend="c", dynamics=False)
        g = check_object(doc, parts, 0.5, backend="mjx", dynamics=False)
        assert g == c, name
        verdicts[name] = c["joints"]["2"]
    assert verdicts["good"]["ok"] and not verdicts["flipped"]["ok"]
    assert any(r.startswith("penetrates part 1") for r in verdicts["flipped"]["reasons"])
