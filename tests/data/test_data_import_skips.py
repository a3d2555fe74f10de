"""`jax3dc data import`: an object that fails to load or render is skipped, not the build; and a
part whose mesh inertia is physically impossible (a zero-thickness panel) still renders."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import trimesh

from jax3dc.render import Lighting, PartRenderer, sample_camera
from data_pipeline.shards import load_manifest, read_dataset
from jax3dc.cli import main

URDF = """<?xml version="1.0"?>
<robot name="{name}">
  <link name="body"><visual><geometry><box size="0.6 0.4 0.5"/></geometry></visual></link>
  <link name="lid"><visual><geometry><mesh filename="{mesh}"/></geometry></visual></link>
  <joint name="hinge" type="revolute"><origin xyz="0 0.2 0.25"/><axis xyz="1 0 0"/>
    <parent link="body"/><child link="lid"/><limit lower="0" upper="1.5"/></joint>
</robot>
"""


def _object(root: Path, name: str, lid_obj: str | None) -> Path:
    """A two-part URDF object (box body, hinged mesh lid) in ``root/name``; ``lid_obj`` None: the
    lid's mesh file is missing."""
    folder = root / name
    folder.mkdir()
    if lid_obj is not None:
        (folder / "lid.obj").write_text(lid_obj)
    (folder / "mobility.urdf").write_text(URDF.format(name=name, mesh="lid.obj"))
    return folder


def _lid_obj() -> str:
    lid = trimesh.creation.box(extents=(0.6, 0.4, 0.03))
    lid.apply_translation((0.0, -0.2, 0.015))
    return trimesh.exchange.obj.export_obj(lid)


def test_import_skips_objects_that_fail_and_writes_the_rest(tmp_path, capsys):
    good = _object(tmp_path, "good_box", _lid_obj())
    # its only mesh is a single triangle (MuJoCo needs 4 vertices): the piece is dropped, no geometry is left
    unrenderable = _object(tmp_path, "bad_triangle", "v 0 0 0\nv 0.3 0 0\nv 0 0.3 0\nf 1 2 3\n")
    unloadable = _object(tmp_path, "bad_missing_mesh", None)  # the URDF names a mesh that is not there
    out = tmp_path / "out"

    code = main(["data", "import", str(unrenderable), str(good), str(unloadable), "--out", str(out),
                 "--views", "2", "--size", "32", "--split", "train"])
    captured = capsys.readouterr()
    assert code == 0, captured.err

    records = list(read_dataset(out))
    assert {r.meta["object_id"] for r in records} == {"good_box"}
    assert len(records) == 2
    manifest = load_manifest(out)
    assert manifest["complete"]
    assert sorted(manifest["shards"]) == ["train-00000.array_record"]  # the shard of all three is written
    assert manifest["shards"]["train-00000.array_record"]["records"] == 2
    assert sorted(manifest["skipped"]) == ["bad_missing_mesh", "bad_triangle"]
    assert "at least 4 vertices" in manifest["skipped"]["bad_triangle"]
    assert "lid.obj" in manifest["skipped"]["bad_missing_mesh"]
    assert all("\n" not in message for message in manifest["skipped"].values())

    warnings = [line for line in captured.err.splitlines() if line.startswith("warning: skipped")]
    assert len(warnings) == 2
    (triangle,) = [w for w in warnings if "bad_triangle" in w]
    assert str(unrenderable.resolve()) in triangle and "at least 4 vertices" in triangle
    (missing,) = [w for w in warnings if "bad_missing_mesh" in w]
    assert str(unloadable.resolve()) in missing and "lid.obj" in missing
    assert "2 records in 1 shards" in captured.out and "2 objects skipped" in captured.out

    # resuming the finished build keeps the list; JSON on disk says the same
    assert main(["data", "import", str(unrenderable), str(good), str(unloadable), "--out", str(out),
                 "--views", "2", "--size", "32", "--split", "train", "--quiet"]) == 0
    assert json.loads((out / "manifest.json").read_text())["skipped"] == manifest["skipped"]


def test_skips_cross_the_worker_pool(tmp_path, capsys):
    good = _object(tmp_path, "good_box", _lid_obj())
    bad = _object(tmp_path, "bad_triangle", "v 0 0 0\nv 0.3 0 0\nv 0 0.3 0\nf 1 2 3\n")
    out = tmp_path / "out"
    assert main(["data", "import", str(good), str(bad), "--out", str(out), "--views", "1", "--size", "32",
                 "--split", "train", "--objects-per-shard", "1", "--workers", "2", "--quiet"]) == 0
    manifest = load_manifest(out)
    assert list(manifest["skipped"]) == ["bad_triangle"]
    assert sorted(s["records"] for s in manifest["shards"].values()) == [0, 1]
    assert "warning: skipped bad_triangle" in capsys.readouterr().err


def test_import_of_only_broken_objects_exits_1(tmp_path, capsys):
    bad = _object(tmp_path, "bad_missing_mesh", None)
    assert main(["data", "import", str(bad), "--out", str(tmp_path / "out"), "--views", "1", "--size", "32",
                 "--quiet"]) == 1
    err = capsys.readouterr().err
    assert "warning: skipped bad_missing_mesh" in err and "every object was skipped" in err


def test_a_zero_thickness_panel_renders():
    """Shell inertia of a flat panel in a tilted plane breaks A + B >= C by rounding (as parts of
    PartNet-Mobility safes do); MuJoCo refused such scenes before the render compiled them with
    balanceinertia."""
    panel = trimesh.creation.box(extents=(1.0, 0.5, 0.0))
    rng = np.random.default_rng(0)
    for _ in range(18):  # the 18th rotation of this generator gives the refused panel
        rotation = trimesh.transformations.random_rotation_matrix(rng.uniform(size=3))
    panel.apply_transform(rotation)
    body = trimesh.creation.box(extents=(0.3, 0.3, 0.3))
    body.apply_translation((0.0, 0.0, -0.6))
    parts = {1: body, 2: panel}
    renderer = PartRenderer(parts, {1: (0.8, 0.2, 0.2, 1.0), 2: (0.2, 0.8, 0.2, 1.0)},
                            Lighting(ambient=0.3, headlight=0.5, key_dir=(0.3, 0.4, -0.8), key_strength=0.4), 48)
    try:
        lo = np.min([m.bounds[0] for m in parts.values()], axis=0)
        hi = np.max([m.bounds[1] for m in parts.values()], axis=0)
        camera = sample_camera(np.random.default_rng(1), centre=(lo + hi) / 2.0,
                               radius=float(np.linalg.norm(hi - lo)) / 2.0)
        _, seg = renderer.render({}, camera)
    finally:
        renderer.close()
    assert set(np.unique(seg)) >= {1, 2}
