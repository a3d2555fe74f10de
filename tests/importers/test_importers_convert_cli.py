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


def test_a_converted_folder_imports_as_its_source(tmp_path):
    """`data import` reads what `data convert` wrote (the form in which a pool travels) and renders
    the records of the source itself; a converted folder's front and units cannot be set again,
    and a structure that names a missing part file is refused with the folder named."""
    from data_pipeline.build import BuildConfig, import_sources, run_build
    from data_pipeline.importers.source import import_object
    from data_pipeline.shards import read_dataset
    from jax3dc.errors import InputFileError
    from jax3dc.render import png_array

    source = partnet_object("door_8877")
    converted = tmp_path / "door_8877"
    assert main(["data", "convert", str(source), "--out", str(converted), "--quiet"]) == 0
    config = BuildConfig(views=2, seed=1, size=48, objects_per_shard=4, split="test")
    records = {}
    for name, path in (("source", source), ("converted", converted)):
        run_build(tmp_path / name, import_sources([path]), config, workers=1, progress=False)
        records[name] = list(read_dataset(tmp_path / name))
    (rest, *moved), (rest_c, *moved_c) = records["source"], records["converted"]
    assert (rest_c.image_png, rest_c.seg_png, rest_c.prompt, rest_c.target) == (
        rest.image_png, rest.seg_png, rest.prompt, rest.target)
    assert rest_c.meta["part_names"] == rest.meta["part_names"] and rest.meta["part_names"]  # stage 1's kinds
    assert len(moved) == len(moved_c) == 1  # moved views: the text's rounding of a pivot may move a pixel
    assert (moved_c[0].key, moved_c[0].seg_png, moved_c[0].target) == (moved[0].key, moved[0].seg_png, moved[0].target)
    changed = np.abs(png_array(moved_c[0].image_png).astype(int) - png_array(moved[0].image_png).astype(int)) > 8
    assert changed.mean() < 0.01
    with pytest.raises(InputFileError, match="front and units"):
        import_object(converted, front="-x")
    max(converted.glob("parts/*.obj"), key=lambda p: int(p.stem)).unlink()
    with pytest.raises(InputFileError, match=str(converted.name)):
        import_object(converted)
