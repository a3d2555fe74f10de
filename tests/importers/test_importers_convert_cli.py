"""`jax3dc data convert`: files written, readable by the project's own loaders; errors exit 1."""

from __future__ import annotations

import json

import numpy as np
import pytest

from jax3dc.cli import main
from tests.shared_fixtures import PARTNET_MOBILITY, partnet_object

FIXTURES = PARTNET_MOBILITY


def test_convert_writes_a_readable_object(tmp_path, capsys):
    from data_pipeline.importers.source import import_object
    from jax3dc.geometry.parts import load_parts
    from jax3dc.structure import load_boxes, parse_structure

    out = tmp_path / "microwave"
    (out / "parts").mkdir(parents=True)
    (out / "parts" / "9.obj").write_text("v 0 0 0\n")  # stale part of an earlier conversion
    assert main(["data", "convert", str(partnet_object("microwave_7119")), "--out", str(out), "--category", "oven"]) == 0
    assert "3 parts, 1 joints (hinge)" in capsys.readouterr().out

    expected = import_object(FIXTURES / "microwave_7119")
    parts = load_parts(out / "parts")
    assert sorted(parts) == [1, 2, 3]
    for i, mesh in parts.items():
        np.testing.assert_allclose(mesh.bounds, expected.parts[i].bounds, atol=1e-5)
    structure = parse_structure((out / "structure.json").read_text(), part_ids=parts)
    assert structure.nodes.keys() == expected.structure.nodes.keys()
    assert {i: n.parent for i, n in structure.nodes.items()} == {i: n.parent for i, n in expected.structure.nodes.items()}
    (child, joint), = structure.joints().items()
    want = expected.structure.joints()[child]
    np.testing.assert_allclose(joint.axis, want.axis, atol=1e-3)
    np.testing.assert_allclose(joint.range, want.range, atol=1e-3)
    boxes = load_boxes(out / "boxes.json")
    assert sorted(boxes) == [1, 2, 3]
    np.testing.assert_allclose(boxes[1].extent, expected.boxes[1].extent, atol=1e-3)
    meta = json.loads((out / "meta.json").read_text())
    assert meta["category"] == "oven" and meta["object_id"] == "microwave_7119"
    assert meta["scale"] == pytest.approx(expected.meta["scale"])
    assert meta["part_names"] == {"1": "door", "2": "rotation_tray", "3": "microwave_body"}


def test_convert_errors_are_one_line(tmp_path, capsys):
    assert main(["data", "convert", str(tmp_path / "nothing"), "--out", str(tmp_path / "o")]) == 1
    err = capsys.readouterr().err.strip()
    assert "nothing" in err and len(err.splitlines()) == 1
    assert main(["data"]) == 2  # no subcommand: usage
