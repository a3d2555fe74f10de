"""The gravity test's object-level verdict on ground truth: objects that stand free stand, objects
mounted in use are checked with their root held, and one that falls over is still caught."""

from __future__ import annotations

import json

import numpy as np
import pytest

from jax3dc.factories import FACTORIES, generate_object
from jax3dc.physics.dynamics import gravity
from jax3dc.physics.findings import describe
from eval.verdict_accuracy.ground_truth import factory_objects
from jax3dc.physics.tolerances import GRAVITY_TILT_RAD


def test_free_standing_faucet_falls_over_but_passes_mounted():
    # a faucet's spout overhangs its narrow body: stood free on a floor it falls onto its side
    obj = generate_object("faucet", 0)
    assert FACTORIES["faucet"].mounted
    free = gravity(obj.structure, obj.parts, obj.scale_m_per_nu, None)
    assert [f.check for f in free] == ["gravity"] and describe(free[0]).startswith("unstable under gravity"), free
    assert free[0].tilt > 2 * GRAVITY_TILT_RAD, free  # it fell onto another face, not a rock onto a nearby support
    assert gravity(obj.structure, obj.parts, obj.scale_m_per_nu, None, mounted=True) == []


def test_mounted_object_still_gets_the_sag_test(monkeypatch):
    # the spout's hinge is held by its servo: with no tolerance for the servo's give, the held
    # root does not stop the sag test from reporting it
    obj = generate_object("faucet", 0)
    monkeypatch.setattr("jax3dc.physics.dynamics.GRAVITY_JOINT_DRIFT", -1.0)
    found = gravity(obj.structure, obj.parts, obj.scale_m_per_nu, None, mounted=True)
    jointed = {p for p, n in obj.structure.nodes.items() if n.joint is not None}
    assert jointed and {f.joints[0] for f in found if f.check == "sag"} == jointed, found
    assert all(describe(f).startswith("sags under gravity") for f in found), found


@pytest.mark.parametrize("category", ["eyeglasses", "kitchen_unit"])
def test_free_standing_ground_truth_stands(category):
    # eyeglasses rock back onto their temple ends; a kitchen unit stands on feet behind its plinth
    obj = next(factory_objects([category], [1]))
    assert not obj.mounted
    problems = [f for f in gravity(obj.structure, obj.parts, obj.scale, None) if f.check == "gravity"]
    assert problems == [], problems


def test_kitchen_unit_stands_on_feet_not_on_its_plinth():
    obj = generate_object("kitchen_unit", 1)
    floor = min(float(m.bounds[0, 2]) for m in obj.parts.values())
    touching = {obj.names[p] for p, m in obj.parts.items() if float(m.bounds[0, 2]) < floor + 1e-6}
    assert touching == {"plinth", "foot"}, touching
    feet = [m for p, m in obj.parts.items() if obj.names[p] == "foot"]
    centre = np.mean([m.center_mass for m in obj.parts.values()], axis=0)
    xy = np.array([m.bounds.mean(axis=0)[:2] for m in feet])
    assert np.all(xy.min(axis=0) < centre[:2]) and np.all(centre[:2] < xy.max(axis=0)), json.dumps(xy.tolist())


def test_cli_mounted_flag_holds_the_root(tmp_path, capsys):
    # a bracket sticking out of a thin wall plate, with a flap on its end: it cannot stand free
    # (it falls onto the plate's face) but is fine fixed to a wall
    import trimesh

    from jax3dc.cli import main
    from jax3dc.geometry.parts import save_parts
    from jax3dc.structure import parse_structure, to_json

    def box(extents, centre):
        mesh = trimesh.creation.box(extents=extents)
        mesh.apply_translation(centre)
        return mesh

    parts = {1: box([0.4, 0.05, 0.6], [0, 0, 0]), 2: box([0.1, 0.8, 0.1], [0, -0.425, 0.2]),
             3: box([0.3, 0.02, 0.2], [0.1, -0.835, 0.2])}
    doc = {"materials": {"0": {"family": "Metal", "desc": "steel"}},
           "nodes": {"1": {"parent": None, "material": 0}, "2": {"parent": 1, "material": 0},
                     "3": {"parent": 2, "material": 0,
                           "joint": {"type": "hinge", "axis": [0, 0, -1], "pivot": [-0.05, -0.825, 0.2], "range": [0, 1.0]}}},
           "relations": []}
    save_parts(parts, tmp_path / "parts")
    (tmp_path / "o.json").write_text(to_json(parse_structure(doc, part_ids=parts.keys())))
    args = ["physics", "check", str(tmp_path / "o.json"), "--parts", str(tmp_path / "parts"), "--scale", "0.5"]
    assert main(args) == 0
    free = json.loads(capsys.readouterr().out)
    assert not free["ok"] and free["checks"]["gravity"][0].startswith("unstable under gravity"), free
    assert main(args + ["--mounted"]) == 0
    held = json.loads(capsys.readouterr().out)
    assert held["ok"] and held["checks"]["gravity"] == [], held
