"""The dynamic checks (limit reachability, gravity) on MJX rollouts against C MuJoCo's rollouts."""

from __future__ import annotations

import re

import numpy as np

from jax3dc.physics import cpu_backend
from jax3dc.physics.dynamics import SETTLE_STEPS
from jax3dc.physics.mjx_dynamics import mjx_final_qpos
from jax3dc.physics.sim_model import SimOptions, build_sim_model
from jax3dc.physics.verdict import check_object
from jax3dc.structure import parse_structure, to_json
from tests.physics.test_physics_cli_mjx import _box, _lid_box


def _overhang():
    """A column with a heavy arm on top reaching far past its foot: stands only if held up."""
    parts = {1: _box([0.2, 0.2, 0.6], [0, 0, -0.3]), 2: _box([1.0, 0.2, 0.1], [0.4, 0, 0.05])}
    doc = {"materials": {"0": {"family": "Wood", "desc": "pine"}},
           "nodes": {"1": {"parent": None, "material": 0},
                     "2": {"parent": 1, "material": 0,
                           "joint": {"type": "hinge", "axis": [0, -1, 0], "pivot": [-0.1, 0, 0], "range": [0, 0.5]}}},
           "relations": []}
    return parse_structure(doc, part_ids=parts.keys()), parts


def test_mjx_rollouts_end_where_c_rollouts_do():
    """Servo rollouts of the lid box's reachability model towards rest, mid-range and the top limit,
    one row per target: the float32 MJX loop lands within a hundredth of a radian of C's."""
    structure, parts = _lid_box()
    sim = build_sim_model(structure, parts, 0.5, SimOptions(actuators=True, frictionless=True))
    rest = sim.model.qpos0
    targets = np.array([[0.0], [0.9], [1.8]])
    start = np.repeat(rest[None], len(targets), axis=0)
    c = cpu_backend.final_qpos(sim.model, start, targets, SETTLE_STEPS)
    g = mjx_final_qpos(sim.model, start, targets, SETTLE_STEPS)
    assert g.shape == c.shape == (3, sim.model.nq)
    np.testing.assert_allclose(g, c, atol=0.01)
    np.testing.assert_allclose(g[:, 0], targets[:, 0], atol=0.02)  # the servos get there


def _prefixes(verdict: dict) -> dict:
    """Reasons without their measured values (where a joint stopped, how far the root moved)."""
    strip = lambda r: re.sub(r"\s*\(.*\)$|: root moved .*$", "", r)
    return {"ok": verdict["ok"], "gravity": [strip(r) for r in verdict["checks"]["gravity"]],
            "joints": {j: sorted(strip(r) for r in v["reasons"]) for j, v in verdict["joints"].items()}}


def test_both_backends_give_the_same_dynamic_verdicts():
    """``check_object`` with dynamics on C and on MJX: a good lid passes both; a lid whose range was
    doubled (it folds down behind its base) stops short of its limit at nearly the same angle; a
    column carrying an overhanging arm topples in both."""
    lid, lid_parts = _lid_box()
    doubled = parse_structure(to_json(lid).replace('"range":[0.0,1.8]', '"range":[0.0,3.6]'), part_ids=lid_parts.keys())
    overhang, overhang_parts = _overhang()
    verdicts = {}
    for name, structure, parts in (("good", lid, lid_parts), ("doubled", doubled, lid_parts),
                                   ("overhang", overhang, overhang_parts)):
        c = check_object(structure, parts, 0.5, backend="c")
        g = check_object(structure, parts, 0.5, backend="mjx")
        assert _prefixes(g) == _prefixes(c), name
        verdicts[name] = (c, g)
    assert verdicts["good"][0]["ok"]
    stops = [float(re.search(r"stops at q=([-\d.]+)", v["joints"]["2"]["reasons"][0]).group(1))
             for v in verdicts["doubled"]]
    assert _prefixes(verdicts["doubled"][0])["joints"]["2"] == ["limit unreachable: hi"]
    assert 3.1 < stops[0] < 3.5 and abs(stops[0] - stops[1]) < 0.1
    tilts = [float(re.search(r"tilted ([\d.]+) rad", v["checks"]["gravity"][0]).group(1)) for v in verdicts["overhang"]]
    assert min(tilts) > 0.3 and abs(tilts[0] - tilts[1]) < 0.05
    assert verdicts["overhang"][0]["joints"]["2"]["ok"]  # the object falls over; its joint is fine
