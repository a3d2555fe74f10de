"""``jax3dc physics check object.xml``: the exported MJCF file gives the verdict its structure gives,
and what is checked is the file (jax3dc.physics.exported)."""

from __future__ import annotations

import dataclasses
import json
import re

import numpy as np
import pytest
import trimesh

from jax3dc.factories import generate_object
from jax3dc.physics.exported import load_exported
from eval.verdict_accuracy.ground_truth import GroundTruthObject, factory_objects, imported_objects
from eval.verdict_accuracy.mutations import mutations_of
from jax3dc.physics.verdict import check_object
from jax3dc.cli import main
from jax3dc.export.mjcf import export_mjcf
from jax3dc.structure import parse_structure
from tests.shared_fixtures import partnet_object


def _labelled_box() -> GroundTruthObject:
    """A block, a lid hinged on its back edge and a flat label on the front (a part MuJoCo cannot
    take as a mesh: the file draws it as a box and keeps its surface in meshes/)."""
    base = trimesh.creation.box(extents=[1.0, 0.6, 0.4])
    base.apply_translation([0, 0, -0.2])
    lid = trimesh.creation.box(extents=[1.0, 0.6, 0.05])
    lid.apply_translation([0, 0, 0.025])
    label = trimesh.Trimesh([[-0.2, -0.3, -0.3], [0.2, -0.3, -0.3], [0.2, -0.3, -0.1], [-0.2, -0.3, -0.1]],
                            [[0, 1, 2], [0, 2, 3]], process=False)
    doc = {"materials": {"0": {"family": "Wood", "desc": "pine"}, "1": {"family": "Other", "desc": "paper label"}},
           "nodes": {"1": {"parent": None, "material": 0},
                     "2": {"parent": 1, "material": 0,
                           "joint": {"type": "hinge", "axis": [-1, 0, 0], "pivot": [0, 0.3, 0], "range": [0, 1.8]}},
                     "3": {"parent": 1, "material": 1, "name": "label"}},
           "relations": []}
    parts = {1: base, 2: lid, 3: label}
    return GroundTruthObject("labelled_box", parse_structure(doc, part_ids=parts.keys()), parts, 0.5)


def _flipped_door() -> GroundTruthObject:
    """The cabinet with a door hinged the wrong way: a failing verdict to compare."""
    cabinet = next(factory_objects(["cabinet"], [0]))
    flip = next(m for m in mutations_of(cabinet.structure, cabinet.parts) if m.kind == "flipped axis")
    return dataclasses.replace(cabinet, name="cabinet_flipped", structure=flip.structure)


CASES = {
    "labelled_box": _labelled_box,
    "cabinet_flipped": _flipped_door,
    "faucet": lambda: next(factory_objects(["faucet"], [0])),  # mounted: the file says so
    "door_8877": lambda: next(imported_objects([partnet_object("door_8877")])),  # mounted PartNet-Mobility door
    "drawer_20453": lambda: next(imported_objects([partnet_object("drawer_20453")])),  # a slide
}


def _rounded(value):
    if isinstance(value, float):
        return round(value, 6)
    if isinstance(value, dict):
        return {k: _rounded(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_rounded(v) for v in value]
    return value


@pytest.mark.parametrize("name", sorted(CASES))
def test_the_exported_file_gets_the_structures_verdict(name, tmp_path, capsys):
    obj = CASES[name]()
    # as predict writes object.xml: a free root unless mounted
    xml = export_mjcf(obj.structure, obj.parts, tmp_path / "sim", obj.scale, free=True, mounted=obj.mounted)
    expected = json.loads(json.dumps(check_object(obj.structure, obj.parts, obj.scale, mounted=obj.mounted)))
    assert main(["physics", "check", str(xml), "--out", str(tmp_path / "v.json")]) == 0
    verdict = json.loads(capsys.readouterr().out)
    # the same verdict, reasons and findings; a rollout's end state may differ in its 10th digit (the
    # file holds 9 significant digits)
    assert _rounded(verdict) == _rounded(expected)
    assert json.loads((tmp_path / "v.json").read_text()) == verdict
    if name == "cabinet_flipped":
        assert not verdict["ok"] and verdict["findings"]


def test_the_file_is_checked_as_it_stands(tmp_path):
    cabinet = generate_object("cabinet", 0)
    xml = export_mjcf(cabinet.structure, cabinet.parts, tmp_path, cabinet.scale_m_per_nu)
    read = load_exported(xml, 10 ** 6)
    assert read.scale == cabinet.scale_m_per_nu and not read.mounted
    assert read.structure.relations == cabinet.structure.relations
    for part, node in cabinet.structure.nodes.items():
        got = read.structure.nodes[part]
        assert (got.parent, got.material) == (node.parent, node.material)
        assert np.allclose(read.parts[part].vertices, cabinet.parts[part].vertices, atol=1e-7)
        if node.joint is not None:
            assert got.joint.type == node.joint.type
            assert np.allclose(got.joint.pivot, node.joint.pivot, atol=1e-7)
            assert np.allclose(got.joint.range, node.joint.range, atol=1e-7)
    # a range edited in the file is the range checked
    text = xml.read_text()
    edited = re.sub(r'(<joint name="joint_3" type="hinge" pos="0 0 0" axis="[^"]*" range=")[^ ]+ [^"]+"', r'\g<1>0 2.5"', text)
    assert edited != text
    xml.write_text(edited)
    assert load_exported(xml, 10 ** 6).structure.nodes[3].joint.range == (0.0, 2.5)


def test_a_file_the_exporter_did_not_write_is_refused_in_one_line(tmp_path, capsys):
    plain = tmp_path / "plain.xml"
    plain.write_text('<mujoco><worldbody><body name="b"><geom type="box" size="1 1 1"/></body></worldbody></mujoco>')
    assert main(["physics", "check", str(plain)]) == 1
    assert "not a file written by jax3dc export" in capsys.readouterr().err
    obj = _labelled_box()
    xml = export_mjcf(obj.structure, obj.parts, tmp_path / "sim", obj.scale)
    assert main(["physics", "check", str(xml), "--parts", str(tmp_path)]) == 1  # the file has its meshes
    rotated = tmp_path / "sim" / "rotated.xml"
    rotated.write_text(xml.read_text().replace('<body name="part_2"', '<body name="part_2" quat="0 1 0 0"'))
    assert main(["physics", "check", str(rotated)]) == 1
    assert "rotated" in capsys.readouterr().err
