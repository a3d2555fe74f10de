"""Stage-1 mesh backend: GLB nodes and OBJ groups give the same parts, and S matches a direct render."""

from __future__ import annotations

import numpy as np
import pytest

from jax3dc.predict.mesh_input import load_segmented_mesh, natural_key
from jax3dc.predict.segmentation import render_segmentation
from jax3dc.predict.stage1 import stage1_from_mesh
from jax3dc.errors import InputFileError
from jax3dc.geometry.parts import normalise_parts
from jax3dc.palette import object_palette
from predict_cases import CAMERA, SIZE, direct_render, factory_object, write_glb, write_obj_groups


@pytest.fixture(scope="module")
def meshes(tmp_path_factory):
    folder = tmp_path_factory.mktemp("meshes")
    return write_glb(folder / "object.glb"), write_obj_groups(folder / "object.obj")


def test_glb_and_obj_groups_give_the_factory_parts(meshes):
    # the backend re-normalises whatever it reads; factory parts are normalised to 4 decimals
    want_parts, want_scale = normalise_parts(factory_object().parts)
    for path in meshes:
        stage1 = stage1_from_mesh(path)
        assert sorted(stage1.parts) == sorted(want_parts), path.suffix
        assert stage1.scale == pytest.approx(want_scale, abs=1e-5)
        for pid, mesh in want_parts.items():
            got = stage1.parts[pid]
            assert len(got.faces) == len(mesh.faces)
            # same triangles: compare the sorted triangle corner coordinates (float32 in GLB)
            want = np.sort(np.asarray(mesh.triangles).reshape(-1, 9), axis=0)
            have = np.sort(np.asarray(got.triangles).reshape(-1, 9), axis=0)
            np.testing.assert_allclose(have, want, atol=1e-5)


def test_segmentation_matches_a_direct_render(meshes):
    palette = object_palette("cabinet", "test")
    _, want = direct_render(palette)
    for path in meshes:
        seg, ids = render_segmentation(stage1_from_mesh(path).parts, CAMERA, palette, SIZE)
        assert seg.shape == want.shape
        assert len(set(np.unique(ids).tolist()) - {0}) >= 3  # the camera sees the object
        assert np.mean(np.all(seg == want, axis=-1)) > 0.995, path.suffix


def test_named_parts_are_numbered_in_natural_order(tmp_path):
    names = {1: "body", 2: "shelf", 3: "door10", 4: "handle", 5: "door2", 6: "handle_b"}
    parts, got_names = load_segmented_mesh(write_glb(tmp_path / "named.glb", names))
    order = sorted(names.values(), key=natural_key)
    assert order.index("door2") < order.index("door10")
    assert got_names == {i + 1: n for i, n in enumerate(order)}
    by_name = {n: pid for pid, n in names.items()}
    for pid, name in got_names.items():
        assert len(parts[pid].faces) == len(factory_object().parts[by_name[name]].faces)
    assert load_segmented_mesh(tmp_path / "named.glb")[1] == got_names  # same on every load


def test_obj_polygons_and_negative_indices(tmp_path):
    path = tmp_path / "quad.obj"
    path.write_text("o lid\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf -4/1 -3/2 -2/3 -1/4\n"
                    "o base\nv 0 0 -1\nv 1 0 -1\nv 0 1 -1\nf 5//1 6//1 7//1\n")
    parts, names = load_segmented_mesh(path)
    assert names == {1: "base", 2: "lid"}
    assert len(parts[2].faces) == 2 and len(parts[2].vertices) == 4
    assert len(parts[1].faces) == 1 and np.allclose(parts[1].vertices[:, 2], -1)


@pytest.mark.parametrize("text, words", [
    ("v 0 0 0\nv 1 0 0\n", "no faces"),
    ("v 0 0 0\nv 1 0 0\nf 1 2 3\n", "line 3"),
    ("v 0 0\n", "line 1"),
])
def test_bad_obj_files_are_input_errors(tmp_path, text, words):
    path = tmp_path / "bad.obj"
    path.write_text(text)
    with pytest.raises(InputFileError, match=words):
        load_segmented_mesh(path)


def test_empty_or_unreadable_glb_is_an_input_error(tmp_path):
    empty = tmp_path / "empty.glb"
    empty.write_bytes(b"")
    with pytest.raises(InputFileError, match="empty.glb"):
        load_segmented_mesh(empty)
    garbage = tmp_path / "garbage.glb"
    garbage.write_bytes(b"glTF" + bytes(range(60)))
    with pytest.raises(InputFileError, match="cannot read|no triangles"):
        load_segmented_mesh(garbage)
    with pytest.raises(InputFileError, match="not found"):
        load_segmented_mesh(tmp_path / "missing.glb")
    with pytest.raises(InputFileError, match="unsupported"):
        load_segmented_mesh(write_text(tmp_path / "x.stl", "solid x"))


def write_text(path, text):
    path.write_text(text)
    return path


def test_own_glb_export_reads_back_with_the_same_ids(tmp_path):
    from jax3dc.predict import PredictConfig, predict
    from jax3dc.predict.stage1 import Stage1Config
    from predict_cases import CAMERA, target_json, write_image

    config = PredictConfig(Stage1Config(f"mesh:{write_glb(tmp_path / 'object.glb')}"),
                           generate_structure=lambda prompt: target_json(), camera=CAMERA)
    first = predict(write_image(tmp_path / "image.png"), config, tmp_path / "first")
    again = stage1_from_mesh(first.out / "object.glb")
    assert sorted(again.parts) == sorted(first.stage1.parts)
    for pid, mesh in first.stage1.parts.items():
        np.testing.assert_allclose(again.parts[pid].bounds, mesh.bounds, atol=1e-4)
