"""The ground-truth fixes of issue 8: the lamp's shade stays above the desk and stops where it meets
its arm, the faucet lever turns without jamming, and a hinge on a part welded to its parent counts
as attached."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest

from jax3dc.factories import generate_object
from jax3dc.physics.floor import first_below_floor
from jax3dc.physics.kinematics import joint_motion
from jax3dc.physics.tolerances import LIMIT_TOL_HINGE_RAD
from jax3dc.physics.verdict import _pivot_attached, check_object
from jax3dc.structure.schema import Structure


def _pose(structure: Structure, parts, part: int, values: dict[int, float]) -> np.ndarray:
    """The vertices of ``part`` with the given joints set (plain numpy forward kinematics: each
    ancestor joint applied from the part up to the root, rest-frame joint definitions)."""
    points = np.asarray(parts[part].vertices, dtype=np.float64)
    node = part
    while node is not None:
        joint = structure.nodes[node].joint
        if joint is not None:
            points = joint_motion(joint, values.get(node, 0.0), points)
        node = structure.nodes[node].parent
    return points


@pytest.mark.parametrize("seed", range(6))
def test_lamp_shade_stays_above_the_desk_in_every_pose(seed):
    lamp = generate_object("lamp", seed)
    s, parts = lamp.structure, lamp.parts
    floor = min(float(m.vertices[:, 2].min()) for m in parts.values())
    jointed = sorted(s.joints())
    shade = max(jointed)  # the shade hangs at the end of the chain
    grid = {p: np.linspace(*s.nodes[p].joint.range, 5) for p in jointed}
    lowest = min(_pose(s, parts, shade, dict(zip(jointed, combo)))[:, 2].min()
                 for combo in itertools.product(*grid.values()))
    assert lowest >= floor - 1e-6
    for p in jointed:
        assert first_below_floor(s, parts, p, grid[p]) is None


def test_lamp_with_the_old_range_goes_through_the_floor():
    lamp = generate_object("lamp", 0)
    s = lamp.structure
    lower = min(s.joints())
    nodes = dict(s.nodes)
    nodes[lower] = dataclasses.replace(nodes[lower], joint=dataclasses.replace(nodes[lower].joint, range=(-0.6, 0.6)))
    old = dataclasses.replace(s, nodes=nodes)
    assert first_below_floor(old, lamp.parts, lower, np.linspace(-0.6, 0.6, 9)) is not None


@pytest.mark.parametrize("seed", (0, 1))
def test_lamp_shade_reaches_its_stop_at_the_arm_but_not_beyond(seed):
    # the shade tilts towards its own arm until it meets the rod: the old +0.6 rad limit was
    # out of reach for the servo (stops at 0.369 and 0.513 rad)
    lamp = generate_object("lamp", seed)
    shade = next(p for p, n in lamp.structure.nodes.items() if n.name == "shade")
    joint = lamp.structure.nodes[shade].joint
    assert joint.range[1] < 0.6
    verdict = check_object(lamp.structure, lamp.parts, lamp.scale_m_per_nu)
    assert verdict["ok"], verdict
    nodes = dict(lamp.structure.nodes)
    nodes[shade] = dataclasses.replace(nodes[shade], joint=dataclasses.replace(joint, range=(joint.range[0], 0.6)))
    old = check_object(dataclasses.replace(lamp.structure, nodes=nodes), lamp.parts, lamp.scale_m_per_nu)
    # the shade stops at the rod short of the old limit: a limit finding carrying where it stops (0.231
    # rad short at seed 0: a failure; 0.087 at seed 1: a warning), or the sweep drives it into the rod
    stops = [f["reachable"] for f in old["findings"] if f["check"] == "limit" and f["joints"] == [shade] and f["limit"] == "hi"]
    assert (stops and stops[0] < 0.6 - LIMIT_TOL_HINGE_RAD) or any(
        r.startswith("penetrates part") for r in old["joints"][str(shade)]["reasons"]), old


@pytest.mark.parametrize("seed", (0, 1, 2))
def test_faucet_and_stapler_pass(seed):
    for category in ("faucet", "stapler"):
        obj = generate_object(category, seed)
        verdict = check_object(obj.structure, obj.parts, obj.scale_m_per_nu)
        # joints only: a faucet stands on a base narrower than its spout's reach (it is bolted down)
        assert all(j["ok"] for j in verdict["joints"].values()), (category, verdict)


def test_pivot_on_a_welded_sibling_is_attached_but_off_every_part_is_not():
    stapler = generate_object("stapler", 1)
    s, parts = stapler.structure, stapler.parts
    arm = next(iter(s.joints()))
    block = next(p for p, n in s.nodes.items() if n.parent == s.nodes[arm].parent and n.joint is None)
    base = s.nodes[arm].parent
    pivot = np.asarray(s.nodes[arm].joint.pivot)
    # the axis (along x) runs along the block welded to the base, farther from the base itself
    def line_distance(p):
        rel = np.asarray(parts[p].vertices) - pivot
        return float(np.min(np.linalg.norm(rel[:, 1:], axis=1)))
    assert line_distance(block) < line_distance(base)
    assert _pivot_attached(s, parts, arm)
    nodes = dict(s.nodes)
    lifted = dataclasses.replace(s.nodes[arm].joint, pivot=tuple(pivot + np.array([0.0, 0.0, 0.3])))
    nodes[arm] = dataclasses.replace(s.nodes[arm], joint=lifted)
    assert not _pivot_attached(dataclasses.replace(s, nodes=nodes), parts, arm)


# --- a jointed part must touch its parent at rest (REST_CONTACT_TOL_NU) ------------------------

def _surface_gap(a, b) -> float:
    """Nearest distance between surface samples of two meshes (an upper bound of the true gap)."""
    from scipy.spatial import cKDTree
    pa = np.concatenate([a.vertices, a.sample(4000, seed=0)])
    pb = np.concatenate([b.vertices, b.sample(4000, seed=0)])
    return float(cKDTree(pb).query(pa)[0].min())


def test_part_given_a_parent_it_does_not_touch_is_detached_at_rest():
    from eval.verdict_accuracy.ground_truth import changes_motion
    from eval.verdict_accuracy.mutations import mutations_of
    from jax3dc.physics.tolerances import REST_CONTACT_TOL_NU
    dishwasher = generate_object("dishwasher", 0)
    s, parts = dishwasher.structure, dishwasher.parts
    truth = check_object(s, parts, dishwasher.scale_m_per_nu, dynamics=False)
    assert not any(r.startswith("detached from parent at rest") for j in truth["joints"].values() for r in j["reasons"])
    caught = 0
    for m in mutations_of(s, parts):
        if m.kind != "wrong parent" or not changes_motion(s, m, parts):
            continue
        new_parent = m.structure.nodes[m.part].parent
        reasons = check_object(m.structure, parts, dishwasher.scale_m_per_nu, dynamics=False)["joints"][str(m.part)]["reasons"]
        gap = [r for r in reasons if r.startswith("detached from parent at rest")]
        reference = _surface_gap(parts[m.part], parts[new_parent])
        assert bool(gap) == (reference > REST_CONTACT_TOL_NU + 0.01) or abs(reference - REST_CONTACT_TOL_NU) < 0.01
        if gap:  # the simulator's hull distance agrees with the sampled surfaces (hulls can only be closer)
            shown = float(gap[0].split("gap ")[1].split(" ")[0])
            assert REST_CONTACT_TOL_NU < shown <= reference + 1e-3
            caught += 1
    assert caught >= 1
