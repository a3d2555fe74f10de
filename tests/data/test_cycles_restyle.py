"""`jax3dc data restyle`: Cycles re-renders I from the record's own camera and pose, keeps the
rest of the record, and the result is a dataset `jax3dc eval run` reads unchanged.

The tests that render need a Python with bpy (``JAX3DC_BLENDER_PYTHON``, which .ci/run sets, or
the checkout's .venv-blender); without one they fail with the setup message, as the other
Blender tests do (tests/blender_env.py): a skipped test checks nothing. The camera convention
itself is checked without Blender, against MuJoCo's S."""

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from data_pipeline.build import BuildConfig, factory_sources, run_build
from data_pipeline.cycles import (BACKGROUNDS, CyclesSettings, background_image, camera_frame, composite, mask_iou,
                                  restyle_dataset, restyle_records, sample_look)
from jax3dc.render import png_array
from data_pipeline.samples import derived_rng
from data_pipeline.shards import read_dataset
from data_pipeline.record_parts import record_parts
from jax3dc.cli import main
from jax3dc.errors import InputFileError, Jax3dcError
from jax3dc.structure import parse_structure

SIZE = 96
CHEAP = CyclesSettings(samples=4, denoise=False, threads=2)


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> Path:
    """Three factory objects, two views each (view 1 has a joint moved), varied look, all in test."""
    out = tmp_path_factory.mktemp("built")
    run_build(out, factory_sources(3, 5), BuildConfig(views=2, seed=5, size=SIZE, objects_per_shard=2,
                                                      split="test", appearance="varied"), workers=1, progress=False)
    return out


@pytest.fixture(scope="module")
def restyled(built: Path, tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("cycles")
    restyle_dataset(built, out, split="test", limit=0, settings=CHEAP)
    return out


def project(points: np.ndarray, frame: dict, size: int) -> np.ndarray:
    """Pixel (column, row) of world points through a Blender-convention camera frame."""
    rotation, location = np.asarray(frame["rotation"]), np.asarray(frame["location"])
    local = (points - location) @ rotation  # columns: right, up, backward
    f = size / 2.0 / np.tan(np.deg2rad(frame["fovy"]) / 2.0)
    return np.stack([size / 2.0 + f * local[:, 0] / -local[:, 2], size / 2.0 - f * local[:, 1] / -local[:, 2]], axis=1)


def test_camera_frame_is_the_mujoco_camera(built: Path):
    """Part vertices projected through camera_frame land on S's object: the bounding box of the
    projection is the bounding box of S's part pixels to within 2 px, for a rest and a moved view."""
    records = list(read_dataset(built))
    assert any(r.meta["moved_joint"] is not None for r in records)
    for record in records:
        frame = camera_frame(record.meta["camera"])
        rotation = np.asarray(frame["rotation"])
        np.testing.assert_allclose(rotation.T @ rotation, np.eye(3), atol=1e-9)
        assert np.linalg.det(rotation) == pytest.approx(1.0)
        parts, _, _ = record_parts(record)
        px = project(np.concatenate([np.asarray(m.vertices) for m in parts.values()]), frame, SIZE)
        seg = png_array(record.seg_png)
        rows, cols = np.nonzero(np.any(seg != 0, axis=-1))
        want = np.array([cols.min(), rows.min(), cols.max() + 1, rows.max() + 1], dtype=float)
        have = np.array([*px.min(axis=0), *px.max(axis=0)])
        visible = np.clip(have, 0, SIZE)  # parts may leave the frame
        assert np.abs(visible - want).max() <= 2.0, (record.key, visible, want)


def test_restyled_records_change_only_the_image(built: Path, restyled: Path):
    before = {r.key: r for r in read_dataset(built)}
    after = {r.key: r for r in read_dataset(restyled)}
    assert sorted(after) == sorted(before) and len(after) == 6
    for key, new in after.items():
        old = before[key]
        assert (new.seg_png, new.prompt, new.target, new.program) == (old.seg_png, old.prompt, old.target, old.program)
        assert new.image_png != old.image_png
        a, b = png_array(new.image_png), png_array(old.image_png)
        assert a.shape == b.shape == (SIZE, SIZE, 3)
        assert np.abs(a.astype(int) - b.astype(int)).mean() > 10.0  # another look, not a re-encode
        assert new.meta["renderer"] == "cycles" and new.meta["cycles"]["samples"] == CHEAP.samples
        assert new.meta["cycles"]["mask_iou"] >= 0.9, key  # Cycles' object is where S's parts are
        assert {k: v for k, v in new.meta.items() if k not in ("renderer", "appearance", "cycles")} == \
            {k: v for k, v in old.meta.items() if k != "appearance"}


def test_a_record_with_another_camera_is_refused(built: Path):
    """The mask check can fail: the same record with the camera aimed 0.3 nu off is refused."""
    record = next(iter(read_dataset(built)))
    lookat = np.add(record.meta["camera"]["lookat"], (0.3, 0.0, 0.3)).tolist()
    camera = dict(record.meta["camera"], lookat=lookat)
    with pytest.raises(Jax3dcError, match="IoU"):
        restyle_records([replace(record, meta=dict(record.meta, camera=camera))], CHEAP)


def test_eval_run_scores_the_restyled_shards(restyled: Path, tmp_path: Path):
    out = tmp_path / "report"
    assert main(["eval", "run", "--data", str(restyled), "--reference-as-prediction", "--out", str(out),
                 "--overlays", "0"]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["counts"]["objects"] == 6
    assert metrics["parse"] == pytest.approx(100.0) and metrics["success"] == pytest.approx(100.0)


def test_restyle_limit_resume_and_bad_output(built: Path, restyled: Path, tmp_path: Path):
    out = tmp_path / "two"
    manifest = restyle_dataset(built, out, limit=3, settings=CHEAP)
    assert sum(s["records"] for s in manifest["shards"].values()) == 3
    again = restyle_dataset(built, out, limit=3, settings=CHEAP)  # resumes: nothing re-rendered
    assert again["restyle"]["seconds"] == manifest["restyle"]["seconds"]
    assert again["shards"] == manifest["shards"]
    with pytest.raises(InputFileError, match="other settings"):
        restyle_dataset(built, out, limit=3, settings=replace(CHEAP, samples=8))
    with pytest.raises(InputFileError, match="source dataset"):
        restyle_dataset(built, built, settings=CHEAP)
    with pytest.raises(InputFileError, match="manifest"):
        restyle_dataset(tmp_path / "nothing", tmp_path / "x", settings=CHEAP)


def test_restyle_cli_errors_are_one_line(built: Path, tmp_path: Path, capsys):
    assert main(["data", "restyle", "--from", str(built), "--out", str(tmp_path / "o"), "--samples", "0",
                 "--quiet"]) == 1
    assert "--samples" in capsys.readouterr().err


def test_looks_are_per_record_and_reproducible(built: Path):
    record = next(iter(read_dataset(built)))
    structure = parse_structure(record.target)
    look = sample_look(structure, derived_rng(5, record.key, "cycles"))
    assert look == sample_look(structure, derived_rng(5, record.key, "cycles"))
    assert look != sample_look(structure, derived_rng(5, record.key + "x", "cycles"))
    assert set(look["parts"]) == set(structure.nodes)


@pytest.mark.parametrize("kind", BACKGROUNDS)
def test_backgrounds_fill_the_frame_and_composite(kind: str):
    bg = background_image(kind, 7, 32)
    assert bg.shape == (32, 32, 3) and np.all((bg >= 0) & (bg <= 1)) and bg.std() > 0.01
    rgba = np.zeros((32, 32, 4), dtype=np.uint8)
    rgba[8:24, 8:24] = (200, 10, 10, 255)
    out = composite(rgba, bg)
    assert np.all(out[8:24, 8:24] == (200, 10, 10))
    np.testing.assert_array_equal(out[0, 0], np.round(bg[0, 0] * 255).astype(np.uint8))
    seg = np.zeros((32, 32, 3), dtype=np.uint8)
    seg[8:24, 8:20] = (0, 0, 255)
    assert mask_iou(rgba[..., 3], seg) == pytest.approx(12 / 16)
