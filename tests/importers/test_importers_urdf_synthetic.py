"""URDF features the fixtures lack: screw helper links, geometry-less frames with rpy, primitives,
mesh scale, continuous and floating joints; and the reduction of a kinematic tree to parts."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import trimesh

from data_pipeline.importers.kinematic_tree import Edge, KinematicTree, Link, Motion, reduce_to_parts
from data_pipeline.importers.source import import_object

BOTTLE = """<?xml version="1.0"?>
<robot name="bottle">
  <link name="base"/>
  <link name="body"><visual><origin xyz="0 0 0.5"/><geometry><cylinder radius="0.2" length="1"/></geometry></visual></link>
  <joint name="root" type="fixed"><parent link="base"/><child link="body"/></joint>
  <link name="cap_helper"/>
  <joint name="cap_lift" type="prismatic"><origin xyz="0 0 1"/><axis xyz="0 0 1"/>
    <parent link="body"/><child link="cap_helper"/><limit lower="0" upper="0.1"/></joint>
  <link name="cap"><visual><geometry><mesh filename="meshes/cap.obj" scale="2 2 1"/></geometry></visual></link>
  <joint name="cap_twist" type="continuous"><axis xyz="0 0 1"/><parent link="cap_helper"/><child link="cap"/></joint>
  <link name="mount"/>
  <joint name="mount_fix" type="fixed"><origin xyz="0.2 0 0.5" rpy="0 0 1.5707963267948966"/>
    <parent link="body"/><child link="mount"/></joint>
  <link name="lever"><visual name="lever_rubber"><origin xyz="0.1 0 0" rpy="0 1.5707963267948966 0"/>
    <geometry><box size="0.02 0.02 0.2"/></geometry></visual></link>
  <joint name="lever_hinge" type="revolute"><axis xyz="1 0 0"/>
    <parent link="mount"/><child link="lever"/><limit lower="-0.5" upper="0.5"/></joint>
  <link name="glass_tag"><visual><geometry><sphere radius="0.01"/></geometry></visual></link>
  <joint name="tag_float" type="floating"><origin xyz="0 -0.1 0.3"/><parent link="body"/><child link="glass_tag"/></joint>
</robot>
"""


@pytest.fixture()
def bottle(tmp_path: Path):
    (tmp_path / "meshes").mkdir()
    trimesh.creation.box(extents=(0.1, 0.1, 0.1)).export(tmp_path / "meshes" / "cap.obj")
    (tmp_path / "bottle.urdf").write_text(BOTTLE)
    return import_object(tmp_path)  # the folder holds exactly one URDF


def _attached(obj, parent: int, child: int):
    """(joint, axis, range) between two parts in the source direction, undoing a re-rooting."""
    nodes = obj.structure.nodes
    if nodes[child].parent == parent:
        j = nodes[child].joint
        return j, np.asarray(j.axis), tuple(j.range)
    assert nodes[parent].parent == child
    j = nodes[parent].joint
    return j, np.asarray(j.axis), (-j.range[1], -j.range[0])


def _check(axis, rng, want_axis, want_range):
    if np.dot(axis, want_axis) < 0:
        axis, rng = -axis, (-rng[1], -rng[0])
    np.testing.assert_allclose(axis, want_axis, atol=1e-9)
    np.testing.assert_allclose(rng, want_range, atol=1e-9)


def test_bottle_parts_and_joints(bottle):
    ids = {v: int(k) for k, v in bottle.meta["part_links"].items()}
    assert sorted(ids) == ["body", "cap", "glass_tag", "lever"]  # base, helper, mount folded away
    # bounds: body x,y [-.2,.2] z [0,1]; cap (0.2 x 0.2 x 0.1 after scale) z to 1.05; lever x to 0.21
    size = 1.05
    centre = np.array([0.005, 0.0, 0.525])
    assert bottle.meta["scale"] == pytest.approx(size)
    assert bottle.meta["front"] == "-y"  # not PartNet-Mobility: no turn

    lever = bottle.parts[ids["lever"]].bounds * size + centre
    np.testing.assert_allclose(lever, [[0.19, 0.0, 0.49], [0.21, 0.2, 0.51]], atol=1e-9)
    cap = bottle.parts[ids["cap"]].bounds * size + centre
    np.testing.assert_allclose(cap, [[-0.1, -0.1, 0.95], [0.1, 0.1, 1.05]], atol=1e-9)

    j, axis, rng = _attached(bottle, ids["body"], ids["lever"])
    assert j.type == "hinge"
    _check(axis, rng, np.array([0.0, 1.0, 0.0]), (-0.5, 0.5))  # x of a frame turned 90 deg about z
    pivot = (np.array([0.2, 0.0, 0.5]) - centre) / size
    assert np.linalg.norm(np.cross(np.asarray(j.pivot) - pivot, axis)) < 1e-9

    j, axis, rng = _attached(bottle, ids["body"], ids["cap"])
    assert j.type == "hinge"  # screw: the twist is kept, the lift dropped and reported
    _check(axis, rng, np.array([0.0, 0.0, 1.0]), (-math.pi, math.pi))
    assert any("cap_twist" in w and "cap_lift" in w for w in bottle.meta["warnings"])
    assert bottle.meta["source_joints"][str(ids["cap"])] == ["cap_lift", "cap_twist"]

    tag = bottle.structure.nodes[ids["glass_tag"]]
    assert tag.joint is None and tag.parent == ids["body"]
    assert any("tag_float" in w and "floating" in w for w in bottle.meta["warnings"])
    assert len(bottle.structure.joints()) == 2

    family = {i: bottle.structure.materials[n.material].family for i, n in bottle.structure.nodes.items()}
    assert family[ids["glass_tag"]] == "Glass" and family[ids["lever"]] == "Rubber"
    assert family[ids["body"]] == "Other"


def _box_link(name: str, centre) -> Link:
    mesh = trimesh.creation.box(extents=(0.2, 0.2, 0.2))
    mesh.apply_translation(centre)
    return Link(name, mesh)


def test_reduction_reverses_motions_seen_from_the_new_root():
    """A geometry-less world holds A through a hinge and B through a slide: A becomes the root,
    B hangs on it through both joints, the hinge (seen from A: reversed range) is kept."""
    hinge = Motion("hinge", np.array([0.0, 0.0, 1.0]), np.zeros(3), (0.1, 0.7), "h")
    slide = Motion("slide", np.array([1.0, 0.0, 0.0]), np.zeros(3), (0.0, 0.3), "s")
    tree = KinematicTree(
        Path("x.urdf"), "urdf", "world",
        {"world": Link("world", None), "A": _box_link("A", (0, 0, 0)), "B": _box_link("B", (1, 0, 0))},
        [Edge("world", "A", "h", "revolute", (hinge,)), Edge("world", "B", "s", "prismatic", (slide,))],
    )
    parts, attachments, warnings = reduce_to_parts(tree)
    assert parts == ["A", "B"]
    assert attachments["A"].parent is None
    b = attachments["B"]
    assert b.parent == "A" and b.motion.kind == "hinge" and b.motion.range == (-0.7, -0.1)
    assert b.path_joints == ("h", "s")
    assert any("dropped s (slide)" in w for w in warnings)
