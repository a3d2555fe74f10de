"""Physics plausibility checks (jax3dc.physics): ground truth passes, broken articulations are caught."""

from __future__ import annotations

import dataclasses
import json
import warnings

import mujoco
import numpy as np
import pytest
import trimesh

from eval.verdict_accuracy.mutations import mutations_of
from jax3dc.factories import generate_object
from jax3dc.physics.sim_model import SimOptions, build_sim_model
from jax3dc.physics.verdict import check_object
from jax3dc.geometry.convex_pieces import HULL_MAX_VERTICES, convex_pieces


@pytest.fixture(scope="module")
def cabinet():
    return generate_object("cabinet", 0)


@pytest.fixture(scope="module")
def drawer_chest():
    return generate_object("drawer_chest", 0)


def test_concave_carcass_is_decomposed(drawer_chest):
    carcass = drawer_chest.parts[1]  # one closed mesh with five drawer openings
    pieces = convex_pieces(carcass, 1e-3)
    assert len(pieces) > 1
    assert all(3 < len(p) <= HULL_MAX_VERTICES for p in pieces)
    # the pieces stay within the carcass's bounds and leave the drawer cavities mostly empty
    lo, hi = carcass.bounds
    allp = np.concatenate(pieces)
    assert np.all(allp >= lo - 2e-3) and np.all(allp <= hi + 2e-3)
    hull_volume = sum(trimesh.convex.convex_hull(p).volume for p in pieces)
    assert hull_volume < 0.5 * carcass.convex_hull.volume


def test_convex_part_is_one_capped_piece():
    sphere = trimesh.creation.icosphere(subdivisions=3)
    pieces = convex_pieces(sphere, 1e-3)
    assert len(pieces) == 1 and len(pieces[0]) == HULL_MAX_VERTICES


def test_flat_part_is_thickened_and_checked(cabinet):
    """A predicted part may have no thickness (stage 1 meshes a door as one quad): its collision
    piece gets the minimum thickness instead of failing qhull, and the door checks like a thin one."""
    door = next(p for p, node in cabinet.structure.nodes.items() if node.joint is not None)
    lo, hi = cabinet.parts[door].bounds
    front = lo[1]  # the door's outer face (front is -Y)
    quad = trimesh.Trimesh([[lo[0], front, lo[2]], [hi[0], front, lo[2]], [hi[0], front, hi[2]],
                            [lo[0], front, hi[2]]], [[0, 1, 2], [0, 2, 3]])
    parts = {**cabinet.parts, door: quad}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        (piece,) = convex_pieces(quad, 1e-3)
        verdict = check_object(cabinet.structure, parts, cabinet.scale_m_per_nu)
    assert np.ptp(piece[:, 1]) == pytest.approx(1e-3)
    assert trimesh.convex.convex_hull(piece).volume > 0
    assert verdict["ok"], verdict
    # a flat part is expected input: checking it does not print numpy's zero-volume warnings
    assert not [w for w in caught if issubclass(w.category, RuntimeWarning)], [str(w.message) for w in caught]


def test_simulation_model_has_what_the_checks_need(cabinet):
    sim = build_sim_model(cabinet.structure, cabinet.parts, cabinet.scale_m_per_nu,
                          SimOptions(floor=True, free_root=True, actuators=True, visual=True))
    m = sim.model
    assert m.nu == len(sim.joint_parts) == 2
    assert m.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_FILTERPARENT
    assert int(m.jnt_type[0]) == int(mujoco.mjtJoint.mjJNT_FREE)
    assert any(int(t) == int(mujoco.mjtGeom.mjGEOM_PLANE) for t in m.geom_type)
    # inertials from the parts' solids and densities: mass of the metre-scale object is plausible (kg)
    total = float(m.body_subtreemass[1])
    assert 1.0 < total < 500.0
    # visual geoms do not collide
    visual = [g for g in range(m.ngeom) if mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g).startswith("visual_")]
    assert visual and all(m.geom_contype[g] == 0 and m.geom_conaffinity[g] == 0 for g in visual)


def test_gravity_model_meets_the_floor_through_one_hull_per_part(drawer_chest):
    """Parts touch only the floor, each through one massless hull of all its pieces: the same mass and
    inertia as colliding pieces, the same lowest points, and one floor pair per part."""
    obj = drawer_chest
    plain = build_sim_model(obj.structure, obj.parts, obj.scale_m_per_nu, SimOptions(floor=True, free_root=True))
    hulls = build_sim_model(obj.structure, obj.parts, obj.scale_m_per_nu,
                            SimOptions(floor=True, free_root=True, floor_contacts_only=True), plain.pieces)
    m, p = hulls.model, plain.model
    np.testing.assert_allclose(m.body_mass, p.body_mass, rtol=1e-9)
    np.testing.assert_allclose(m.body_inertia, p.body_inertia, rtol=1e-9)
    floor = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "floor")
    touching = [g for g in range(m.ngeom) if g != floor and (m.geom_contype[g] & m.geom_conaffinity[floor]
                                                               or m.geom_contype[floor] & m.geom_conaffinity[g])]
    assert len(touching) == len(obj.parts) < sum(len(v) for v in plain.pieces.values())
    assert not any(m.geom_contype[a] & m.geom_conaffinity[b] for a in touching for b in touching)
    data_p, data_m = mujoco.MjData(p), mujoco.MjData(m)
    mujoco.mj_forward(p, data_p), mujoco.mj_forward(m, data_m)
    for g in touching:  # each hull reaches as low as its part's pieces
        part = int(mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g).rsplit("_", 1)[1])
        body = hulls.part_body[part]
        lowest_piece = min(float((data_p.xmat[body].reshape(3, 3) @ v.T)[2].min()) for v in plain.pieces[part])
        vert = m.mesh_vert[m.mesh_vertadr[m.geom_dataid[g]]:][:m.mesh_vertnum[m.geom_dataid[g]]]
        hull_low = float((data_m.geom_xmat[g].reshape(3, 3) @ vert.T)[2].min() + data_m.geom_xpos[g][2])
        assert abs(hull_low - (lowest_piece + data_p.xpos[body][2])) < 1e-6


@pytest.mark.parametrize("category", ["cabinet", "drawer_chest", "microwave", "refrigerator"])
def test_ground_truth_passes(category):
    obj = generate_object(category, 0)
    verdict = check_object(obj.structure, obj.parts, obj.scale_m_per_nu)
    assert verdict["ok"], json.dumps(verdict)
    assert verdict["joints"] and all(j["ok"] for j in verdict["joints"].values())


def _mutation(obj, kind, part):
    return next(m for m in mutations_of(obj.structure, obj.parts) if m.kind == kind and m.part == part)


def test_flipped_door_axis_penetrates(cabinet):
    door = next(p for p, n in cabinet.structure.nodes.items() if n.joint is not None and n.joint.type == "hinge")
    mutated = _mutation(cabinet, "flipped axis", door)
    reasons = check_object(mutated.structure, cabinet.parts, cabinet.scale_m_per_nu)["joints"][str(door)]["reasons"]
    assert any(r.startswith("penetrates") for r in reasons), reasons


def test_moved_pivot_is_detached(cabinet):
    door = next(p for p, n in cabinet.structure.nodes.items() if n.joint is not None and n.joint.type == "hinge")
    mutated = _mutation(cabinet, "pivot moved", door)
    reasons = check_object(mutated.structure, cabinet.parts, cabinet.scale_m_per_nu,
                           dynamics=False)["joints"][str(door)]["reasons"]
    assert "pivot detached" in reasons


def test_drawer_with_doubled_range_detaches(drawer_chest):
    drawer = next(p for p, n in drawer_chest.structure.nodes.items() if n.joint is not None)
    mutated = _mutation(drawer_chest, "range doubled", drawer)
    reasons = check_object(mutated.structure, drawer_chest.parts, drawer_chest.scale_m_per_nu,
                           dynamics=False)["joints"][str(drawer)]["reasons"]
    assert any(r.startswith("detached from parent") for r in reasons), reasons


def test_drawer_pushed_inwards_is_blocked(drawer_chest):
    drawer = next(p for p, n in drawer_chest.structure.nodes.items() if n.joint is not None)
    mutated = _mutation(drawer_chest, "flipped axis", drawer)
    reasons = check_object(mutated.structure, drawer_chest.parts, drawer_chest.scale_m_per_nu)["joints"][str(drawer)]["reasons"]
    assert any(r.startswith("penetrates") for r in reasons), reasons
    assert any(r.startswith("limit unreachable: hi") for r in reasons), reasons


def test_joint_on_far_part_is_detached(cabinet):
    door = next(p for p, n in cabinet.structure.nodes.items() if n.joint is not None)
    mutated = _mutation(cabinet, "attached to a far part", door)
    reasons = check_object(mutated.structure, cabinet.parts, cabinet.scale_m_per_nu, dynamics=False)["joints"][str(door)]["reasons"]
    assert reasons, "a door hinged to a far part must be flagged"


def test_rest_interpenetration_is_reported(cabinet):
    # push a door 0.1 nu into the carcass: a rest-pose problem, not a sweep problem
    door = next(p for p, n in cabinet.structure.nodes.items() if n.joint is not None)
    parts = dict(cabinet.parts)
    moved = parts[door].copy()
    moved.apply_translation([0.0, 0.1, 0.0])
    parts[door] = moved
    verdict = check_object(cabinet.structure, parts, cabinet.scale_m_per_nu, dynamics=False)
    assert not verdict["ok"]
    assert any(f",{door}" in r or f" {door}," in r for r in verdict["checks"]["rest"]), verdict


def test_unsupported_object_is_unstable(cabinet):
    # a cabinet balanced on one small leg-like part falls over
    parts = dict(cabinet.parts)
    root = next(p for p, n in cabinet.structure.nodes.items() if n.parent is None)
    post = trimesh.creation.box(extents=[0.03, 0.03, 0.6])
    lo = min(float(m.bounds[0, 2]) for m in parts.values())
    post.apply_translation([0.45, 0.0, lo - 0.3])
    parts[root] = trimesh.util.concatenate([parts[root], post])
    verdict = check_object(cabinet.structure, parts, cabinet.scale_m_per_nu)
    assert any(r.startswith("unstable under gravity") for r in verdict["checks"]["gravity"]), verdict


def test_mutated_structures_keep_their_schema(cabinet):
    for m in mutations_of(cabinet.structure, cabinet.parts):
        joint = m.structure.nodes[m.part].joint
        if joint is not None:
            assert joint.range[0] <= joint.range[1]
            assert joint.type in ("hinge", "slide")
        assert dataclasses.asdict(m.structure)
