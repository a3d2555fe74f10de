"""Bad inputs end in a typed error naming the problem, and keep every valid output written before it."""

from __future__ import annotations

import json

import pytest

from jax3dc.predict import PredictConfig, predict
from jax3dc.predict.stage1 import Stage1Config
from jax3dc.predict.segmentation import load_camera
from jax3dc.cli import main
from jax3dc.errors import InputFileError, ProgramError, StructureError
from predict_cases import CAMERA, factory_object, target_json, write_glb, write_image

STAGE1_OUTPUTS = ("seg.png", "parts", "report.html", "report.png")
STAGE2_OUTPUTS = ("structure.json", "object.urdf", "object.xml", "object.usda", "object.glb", "object_blender.py", "physics.json")


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("inputs")
    return write_image(folder / "image.png"), write_glb(folder / "object.glb")


def run(image, stage1, out, text="", program=None):
    stage1_config = Stage1Config(stage1, generate_program=None if program is None else (lambda prompt: program))
    return predict(image, PredictConfig(stage1_config, generate_structure=lambda prompt: text, camera=CAMERA), out)


def test_not_an_image(inputs, tmp_path):
    fake = tmp_path / "photo.png"
    fake.write_text("this is not a picture")
    with pytest.raises(InputFileError, match="not an image") as e:
        run(fake, f"mesh:{inputs[1]}", tmp_path / "out")
    assert e.value.path == str(fake)


def test_corrupt_png(inputs, tmp_path):
    broken = tmp_path / "broken.png"
    broken.write_bytes(inputs[0].read_bytes()[:200])
    with pytest.raises(InputFileError, match="broken.png"):
        run(broken, f"mesh:{inputs[1]}", tmp_path / "out")


def test_empty_mesh(inputs, tmp_path):
    empty = tmp_path / "empty.obj"
    empty.write_text("# nothing here\n")
    with pytest.raises(InputFileError, match="no faces"):
        run(inputs[0], f"mesh:{empty}", tmp_path / "out")


@pytest.mark.parametrize("spec", ["mesh:", "meshes:x.glb", "codes", "parts:"])
def test_bad_stage1_spec(inputs, tmp_path, spec):
    with pytest.raises(InputFileError, match="--stage1"):
        run(inputs[0], spec, tmp_path / "out")


def test_missing_parts_dir(inputs, tmp_path):
    with pytest.raises(InputFileError, match="parts directory not found"):
        run(inputs[0], f"parts:{tmp_path / 'nope'}", tmp_path / "out")


def test_program_that_fails_to_parse_names_the_line(inputs, tmp_path):
    lines = factory_object().program_text.splitlines()
    bad = "\n".join(lines[:3] + ["door = box((0.1, 0.1, 0.1)) +"] + lines[3:])
    with pytest.raises(ProgramError) as e:
        run(inputs[0], "code", tmp_path / "out", target_json(), program=bad)
    assert e.value.line == 4 and "line 4" in str(e.value)
    assert (tmp_path / "out" / "program.txt").read_text() == bad  # the program is kept for inspection


def test_code_backend_without_a_code_model(inputs, tmp_path):
    with pytest.raises(InputFileError, match="--code-model"):
        predict(inputs[0], PredictConfig(Stage1Config("code"), generate_structure=lambda prompt: target_json()),
                tmp_path)


@pytest.mark.parametrize("text, rule", [
    ('{"materials": {"0": {"family": "Wood"}}, "nodes": {', None),  # invalid JSON
    ('{"materials": {"0": {"family": "Wood"}}, "nodes": {"1": {"parent": null, "material": 0}}, "relations": []}',
     None),  # valid JSON, but not the parts of S
])
def test_invalid_structure_keeps_raw_text_and_stage1_outputs(inputs, tmp_path, text, rule):
    out = tmp_path / "out"
    with pytest.raises(StructureError) as e:
        run(inputs[0], f"mesh:{inputs[1]}", out, text)
    assert "structure_raw.txt" in str(e.value)
    assert (out / "structure_raw.txt").read_text() == text
    for name in STAGE1_OUTPUTS:
        assert (out / name).exists(), name
    for name in STAGE2_OUTPUTS:
        assert not (out / name).exists(), name
    page = (out / "report.html").read_text()
    assert e.value.rule in page  # the report says why there is no structure
    assert all(f"{pid}</li>" in page for pid in factory_object().parts)


@pytest.mark.parametrize("doc, words", [
    ("not json", "not valid JSON"),
    ({"lookat": [0, 0], "distance": 2, "azimuth": 0, "elevation": 0}, "lookat"),
    ({"lookat": [0, 0, 0], "distance": -1, "azimuth": 0, "elevation": 0}, "positive"),
    ({"lookat": [0, 0, 0], "distance": 2, "azimuth": 0}, "elevation"),
])
def test_bad_camera_files(tmp_path, doc, words):
    path = tmp_path / "camera.json"
    path.write_text(doc if isinstance(doc, str) else json.dumps(doc))
    with pytest.raises(InputFileError, match=words):
        load_camera(path)


def test_camera_file_accepts_a_record_meta(tmp_path):
    path = tmp_path / "meta.json"
    path.write_text(json.dumps({"category": "cabinet", "camera": CAMERA.to_dict()}))
    assert load_camera(path) == CAMERA


def test_cli_error_is_one_line_and_keeps_outputs(inputs, tmp_path, capsys):
    out = tmp_path / "out"
    missing = tmp_path / "no_model"  # the shipped default would succeed: name a model folder that is not there
    code = main(["predict", str(inputs[0]), "--stage1", f"mesh:{inputs[1]}", "--structure-model", str(missing),
                 "--out", str(out)])
    assert code == 1
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("jax3dc predict: error:") and str(missing) in lines[0]
    for name in STAGE1_OUTPUTS:
        assert (out / name).exists(), name
        assert str(out / name) in captured.out  # printed where it is


def test_cli_not_an_image(inputs, tmp_path, capsys):
    fake = tmp_path / "x.png"
    fake.write_bytes(b"\x89PNG\r\n\x1a\n" + b"\0" * 20)
    assert main(["predict", str(fake), "--stage1", f"mesh:{inputs[1]}", "--out", str(tmp_path / "o")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(fake) in err[0]
