"""MJCF import of a hand-written cabinet: frames, joints, units, geometry selection, materials."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import trimesh

from data_pipeline.importers.source import import_object
from tests.shared_fixtures import partnet_object


CABINET = """<mujoco model="cabinet">
  <compiler angle="degree" meshdir="meshes"/>
  <asset>
    <texture name="grain" type="2d" file="textures/not_shipped.png"/>
    <material name="oak_wood" texture="grain"/>
    <mesh name="knob" file="knob.obj" scale="0.5 0.5 0.5"/>
  </asset>
  <worldbody>
    <geom name="floor" type="plane" size="5 5 0.1"/>
    <body name="cabinet" pos="0 0 0.5">
      <freejoint/>
      <geom name="carcass" type="box" size="0.4 0.3 0.5" material="oak_wood"/>
      <body name="door" pos="-0.4 -0.32 0" euler="0 -90 0">
        <joint name="door_hinge" type="hinge" axis="1 0 0" range="-10 80" ref="-10"/>
        <geom name="panel" type="box" size="0.5 0.01 0.4" pos="0 0 -0.4"/>
        <body name="knob" pos="0 -0.02 -0.7">
          <geom type="mesh" mesh="knob"/>
        </body>
      </body>
      <body name="drawer" pos="0 -0.1 -0.3">
        <joint name="drawer_slide" type="slide" axis="0 -1 0" range="0 0.4"/>
        <geom name="tray" type="box" size="0.35 0.2 0.08"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


@pytest.fixture()
def cabinet(tmp_path: Path) -> Path:
    (tmp_path / "meshes").mkdir()
    trimesh.creation.box(extents=(0.1, 0.1, 0.1)).export(tmp_path / "meshes" / "knob.obj")
    path = tmp_path / "cabinet.xml"
    path.write_text(CABINET)
    return path


def _joint_of(obj, a: int, b: int):
    """The joint between parts a (parent in the source) and b, as (axis, range) in source direction."""
    nodes = obj.structure.nodes
    if nodes[b].parent == a:
        j = nodes[b].joint
        return j, np.asarray(j.axis), j.range
    assert nodes[a].parent == b
    j = nodes[a].joint
    return j, np.asarray(j.axis), (-j.range[1], -j.range[0])


def _same_motion(axis, rng, want_axis, want_range):
    if np.dot(axis, want_axis) < 0:
        axis, rng = -axis, (-rng[1], -rng[0])
    np.testing.assert_allclose(axis, want_axis, atol=1e-9)
    np.testing.assert_allclose(rng, want_range, atol=1e-9)


def test_cabinet_structure(cabinet):
    obj = import_object(cabinet)
    ids = {v: int(k) for k, v in obj.meta["part_links"].items()}
    assert sorted(ids) == ["cabinet", "door", "drawer", "knob"]  # the world's floor plane is no part
    assert obj.meta["format"] == "mjcf" and obj.meta["object_id"] == "cabinet"

    # World bounds: carcass x[-.4,.4] y[-.3,.3] z[0,1]; knob reaches y = -0.34 - 0.025.
    centre = np.array([0.0, (-0.365 + 0.3) / 2, 0.5])
    size = 1.0
    assert obj.meta["scale"] == pytest.approx(size)
    np.testing.assert_allclose(obj.meta["normalisation"]["centre"], centre, atol=1e-9)
    knob = obj.parts[ids["knob"]].bounds
    np.testing.assert_allclose(knob, [np.array([0.275, -0.365, 0.475]) - centre,
                                      np.array([0.325, -0.315, 0.525]) - centre], atol=1e-6)

    door, axis, rng = _joint_of(obj, ids["cabinet"], ids["door"])
    assert door.type == "hinge"
    # door frame turned -90 deg about Y: its x axis is world +Z; range [-10, 80] deg minus ref -10
    _same_motion(axis, rng, np.array([0.0, 0.0, 1.0]), (0.0, math.pi / 2))
    pivot = np.array([-0.4, -0.32, 0.5]) - centre
    assert np.linalg.norm(np.cross(np.asarray(door.pivot) - pivot, [0, 0, 1])) < 1e-9

    drawer, axis, rng = _joint_of(obj, ids["cabinet"], ids["drawer"])
    assert drawer.type == "slide"
    _same_motion(axis, rng, np.array([0.0, -1.0, 0.0]), (0.0, 0.4 / size))

    assert obj.structure.nodes[ids["knob"]].joint is None
    assert obj.structure.nodes[ids["knob"]].parent == ids["door"]
    family = {i: obj.structure.materials[n.material].family for i, n in obj.structure.nodes.items()}
    assert family[ids["cabinet"]] == "Wood" and family[ids["door"]] == "Other"
    assert len(obj.structure.joints()) == 2


def test_visual_geoms_win_over_collision_geoms(tmp_path):
    """Infinigen-Sim style: a visual-only geom and a larger collision geom in one body."""
    text = """<mujoco><worldbody><body name="lamp">
      <geom name="shade_visual" type="box" size="0.1 0.1 0.2" contype="0" conaffinity="0" group="1"/>
      <geom name="shade_collision" type="box" size="0.3 0.3 0.3"/>
      <body name="arm" pos="0 0 0.2"><joint name="swing" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.02" contype="0" conaffinity="0"/>
      </body></body></worldbody></mujoco>"""
    path = tmp_path / "lamp.xml"
    path.write_text(text)
    obj = import_object(path)
    ids = {v: int(k) for k, v in obj.meta["part_links"].items()}
    # visual geoms span z -0.2 .. 0.22 (arm capsule radius 0.02); the collision box would give 0.6
    assert obj.meta["scale"] == pytest.approx(0.42)
    joint = obj.structure.joints()
    assert len(joint) == 1
    (child, j), = joint.items()
    assert j.type == "hinge"
    assert j.range == pytest.approx((-math.pi, math.pi))  # unlimited hinge: one turn either way
    assert {child, obj.structure.nodes[child].parent} == {ids["lamp"], ids["arm"]}


def test_several_joints_in_one_body_keep_the_hinge(tmp_path):
    text = """<mujoco><compiler angle="radian"/><worldbody><body name="base">
      <geom type="box" size="0.5 0.5 0.1"/>
      <body name="cap" pos="0 0 0.2">
        <joint name="lift" type="slide" axis="0 0 1" range="0 0.05"/>
        <joint name="twist" type="hinge" axis="0 0 1" range="0 6"/>
        <geom type="cylinder" size="0.1 0.05"/></body></body></worldbody></mujoco>"""
    path = tmp_path / "screw.xml"
    path.write_text(text)
    obj = import_object(path)
    (child, j), = obj.structure.joints().items()
    assert j.type == "hinge" and j.range == pytest.approx((0.0, 6.0))
    assert any("twist" in w and "lift" in w for w in obj.meta["warnings"])


@pytest.mark.parametrize("name", ["microwave_7119", "drawer_20453", "safe_rotate_101593"])
def test_round_trip_through_the_mjcf_exporter(tmp_path, name):
    """PartNet-Mobility object -> structure + parts -> jax3dc's MJCF export -> this importer."""
    from jax3dc.export.mjcf import export_mjcf

    first = import_object(partnet_object(name))
    xml = export_mjcf(first.structure, first.parts, tmp_path, scale=first.meta["scale"], model_name="obj")
    second = import_object(xml)
    assert second.meta["scale"] == pytest.approx(first.meta["scale"], rel=1e-3)
    # bodies are named part_<id>[_<name>] by the exporter: map the new ids back to the first ones
    back = {int(k): int(v.split("_")[1]) for k, v in second.meta["part_links"].items()}
    assert sorted(back.values()) == sorted(first.structure.nodes)
    for new_id, old_id in back.items():
        np.testing.assert_allclose(second.boxes[new_id].centroid, first.boxes[old_id].centroid, atol=2e-3)
        old, new = first.structure.nodes[old_id], second.structure.nodes[new_id]
        assert (None if new.parent is None else back[new.parent]) == old.parent
        assert (new.joint is None) == (old.joint is None)
        if old.joint is not None:
            assert new.joint.type == old.joint.type
            np.testing.assert_allclose(new.joint.axis, old.joint.axis, atol=1e-6)
            np.testing.assert_allclose(new.joint.range, old.joint.range, atol=1e-6)
            offset = np.asarray(new.joint.pivot) - np.asarray(old.joint.pivot)
            assert np.linalg.norm(np.cross(offset, old.joint.axis)) < 2e-3


def test_mirrored_and_repeated_parts_become_relations(tmp_path):
    """Two equal handles mirrored across x = 0 (plane yz) and two equal feet off-centre in x."""
    text = """<mujoco><worldbody><body name="chest"><geom type="box" size="0.5 0.3 0.4"/>
      <body name="handle_left" pos="-0.3 -0.32 0.2"><geom type="box" size="0.08 0.02 0.02"/></body>
      <body name="handle_right" pos="0.3 -0.32 0.2"><geom type="box" size="0.08 0.02 0.02"/></body>
      <body name="foot_a" pos="0.1 0 -0.45"><geom type="cylinder" size="0.05 0.05"/></body>
      <body name="foot_b" pos="0.3 0 -0.45"><geom type="cylinder" size="0.05 0.05"/></body>
    </body></worldbody></mujoco>"""
    path = tmp_path / "chest.xml"
    path.write_text(text)
    obj = import_object(path)
    ids = {v: int(k) for k, v in obj.meta["part_links"].items()}
    got = {(r.type, r.a, r.b, r.plane) for r in obj.structure.relations}
    left, right = sorted((ids["handle_left"], ids["handle_right"]))
    a, b = sorted((ids["foot_a"], ids["foot_b"]))
    assert got == {("symmetric", left, right, "yz"), ("instance", a, b, None)}
