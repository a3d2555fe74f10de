"""`predict` with the parameters backend: a stage-1 model reads image I and writes a factory's
parameters, which the factory runs into parts; the default stage 1 when a stage-1 model ships; and
the images and texts it refuses, each with one clear error line.

The model is a tiny *random* Qwen3-VL over the shipped BPE: its parameter text is nonsense but the
grammar makes it one that runs, so every output after stage 1 must exist. Stage 2 is a stand-in
(every part rigidly on the first), so the test measures stage 1's wiring, not a structure model.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from PIL import Image

from jax3dc import release
from jax3dc.cli import main
from jax3dc.errors import InputFileError
from jax3dc.factories.registry import SCHEMAS, run_parameters
from jax3dc.geometry.parts import load_parts
from jax3dc.parameters import ParameterError, format_parameters, parse_parameters
from jax3dc.decoding import Decoding
from jax3dc.predict import PredictConfig, predict
from jax3dc.predict import stage1 as stage1_module
from jax3dc.predict.stage1 import BACKENDS, PARAMETERS, ReaderKind, Stage1Config, check_object_image, parse_stage1
from predict_cases import CAMERA, write_image
from tests.factory_samples import sample_parameters
from tests.tiny_checkpoint import write_tiny_release_vocab_checkpoint

GOOD = format_parameters(sample_parameters("stapler", 0), SCHEMAS["stapler"])


def rigid_star(prompt: str) -> str:
    """A valid structure for the legend's parts: every part rigidly attached to the first."""
    ids = [int(i) for i in re.findall(r"^(\d+): #", prompt, re.MULTILINE)]
    nodes = {str(i): {"parent": None if i == ids[0] else ids[0], "material": 0} for i in ids}
    return json.dumps({"materials": {"0": {"family": "Wood", "desc": "oak"}}, "nodes": nodes, "relations": []})


def parameters_config(model_dir=None, read=None, **fields) -> PredictConfig:
    """The parameters backend with the model in ``model_dir`` (or the stand-in ``read``) and
    ``rigid_star`` as the structure model."""
    return PredictConfig(Stage1Config(PARAMETERS, model_dir, read_parameters=read), generate_structure=rigid_star,
                         **fields)


def fake_net_folder(folder, monkeypatch, seen: list):
    """A folder with another kind's marker, registered before the language model: its reader records
    the folder it loads and the image it reads, and writes GOOD."""
    folder.mkdir()
    (folder / "stage1_net.json").write_text("{}")

    def load(path, settings):
        seen.append(path)
        return lambda rgb: seen.append(rgb.shape) or GOOD

    readers = (ReaderKind("stage1_net.json", "an image network", load), *stage1_module.READERS)
    monkeypatch.setattr(stage1_module, "READERS", readers)
    return folder


@pytest.fixture(scope="module")
def model(tmp_path_factory):
    return write_tiny_release_vocab_checkpoint(tmp_path_factory.mktemp("stage1_model"))


@pytest.fixture(scope="module")
def image(tmp_path_factory):
    return write_image(tmp_path_factory.mktemp("inputs") / "image.png")


def blank_and_noise(folder):
    rng = np.random.default_rng(0)
    images = {"blank": np.full((96, 96, 3), 255, np.uint8), "noise": rng.integers(0, 256, (96, 96, 3), dtype=np.uint8)}
    paths = {}
    for name, pixels in images.items():
        paths[name] = folder / f"{name}.png"
        Image.fromarray(pixels).save(paths[name])
    return paths


@pytest.fixture
def no_shipped_stage1(monkeypatch, tmp_path):
    monkeypatch.setattr(release, "STAGE1_DIR", tmp_path / "no_stage1_here")


@pytest.mark.slow  # about 20 s on 2 idle cores: the grammar's tables and the decode's compile
def test_parameters_backend_from_the_image(model, image, tmp_path):
    out = tmp_path / "out"
    result = predict(image, parameters_config(model, camera=CAMERA, decoding=Decoding(dtype="float32")), out)
    text = (out / "parameters.txt").read_text()
    obj = run_parameters(parse_parameters(text, SCHEMAS))  # the model's text, run again, is what stage 1 gave
    assert (out / "program.txt").read_text() == obj.program_text
    parts = load_parts(out / "parts")
    assert sorted(parts) == list(range(1, len(obj.parts) + 1)) == sorted(result.stage1.parts)
    assert result.stage1.names == obj.names and result.stage1.scale == obj.scale_m_per_nu
    structure = json.loads((out / "structure.json").read_text())
    assert sorted(map(int, structure["nodes"])) == sorted(parts)
    seg = np.asarray(Image.open(out / "seg.png"))
    assert len(np.unique(seg.reshape(-1, seg.shape[-1]), axis=0)) > 1  # parts drawn over the background
    import mujoco

    mujoco.MjModel.from_xml_path(str(out / "object.xml"))
    for name in ("object.urdf", "object.usda", "object.glb", "object_blender.py", "viewer.html", "report.html"):
        assert (out / name).is_file(), name
    verdict = json.loads((out / "physics.json").read_text())
    assert isinstance(verdict["ok"], bool) and result.verdict.to_json() == verdict


def test_default_stage1_is_the_shipped_model(image, tmp_path, monkeypatch):
    shipped = fake_net_folder(tmp_path / "stage1", monkeypatch, seen := [])
    monkeypatch.setattr(release, "STAGE1_DIR", shipped)
    assert parse_stage1(None) == (BACKENDS[PARAMETERS], None)
    result = predict(image, PredictConfig(generate_structure=rigid_star, camera=CAMERA), tmp_path / "out")
    assert seen[0] == shipped and result.stage1.source == PARAMETERS
    assert (tmp_path / "out" / "parameters.txt").read_text() == GOOD and (tmp_path / "out" / "object.xml").is_file()


def test_cli_without_a_shipped_stage1_model_names_what_to_pass(image, tmp_path, capsys, no_shipped_stage1):
    assert main(["predict", str(image), "--out", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "no stage-1 model ships" in err and "--stage1 `parameters`" in err and "--stage1-model" in err


def test_cli_default_reads_the_shipped_folder(image, tmp_path, capsys, monkeypatch):
    shipped = tmp_path / "stage1"
    shipped.mkdir()  # a shipped folder that holds no model: the error shows where the default looked
    monkeypatch.setattr(release, "STAGE1_DIR", shipped)
    assert main(["predict", str(image), "--out", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and str(shipped) in err and "not a stage-1 model folder" in err


def test_parameters_without_a_model_folder(image, tmp_path, no_shipped_stage1):
    with pytest.raises(InputFileError, match="--stage1-model"):
        predict(image, parameters_config(), tmp_path)


@pytest.mark.parametrize("kind", ["blank", "noise"])
def test_blank_and_noise_images_give_one_error_line_before_any_model(kind, tmp_path, capsys):
    path = blank_and_noise(tmp_path)[kind]
    empty = tmp_path / "empty_model"
    empty.mkdir()  # were a model read first, the error would be about this folder
    for stage1 in (["--stage1", "parameters", "--stage1-model", str(empty)], ["--stage1", "code"]):
        assert main(["predict", str(path), *stage1, "--out", str(tmp_path / "out")]) == 1
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and "no object found" in err and str(path) in err, err
        assert {"blank": "one flat colour", "noise": "is noise"}[kind] in err


def test_too_small_image(tmp_path):
    path = tmp_path / "tiny.png"
    Image.fromarray(np.full((20, 40, 3), 90, np.uint8)).save(path)
    with pytest.raises(InputFileError, match="40x20 px, too small"):
        predict(path, parameters_config(read=lambda rgb: GOOD), tmp_path / "out")


def test_the_check_accepts_a_render_and_refuses_what_holds_no_object(image, tmp_path):
    check_object_image(np.asarray(Image.open(image).convert("RGB")), "render")  # no error
    paths = blank_and_noise(tmp_path)
    with pytest.raises(InputFileError, match="one flat colour"):
        check_object_image(np.asarray(Image.open(paths["blank"])), "blank")
    with pytest.raises(InputFileError, match="noise"):
        check_object_image(np.asarray(Image.open(paths["noise"])), "noise")


def test_a_text_that_does_not_run_names_the_entry_and_is_kept(image, tmp_path):
    bad = GOOD.replace("length=0.", "length=9.")
    with pytest.raises(ParameterError, match="length"):
        predict(image, parameters_config(read=lambda rgb: bad), tmp_path)
    assert (tmp_path / "parameters.txt").read_text() == bad and not (tmp_path / "parts").exists()


def test_another_reader_plugs_in_by_its_marker(image, tmp_path, monkeypatch):
    """A folder with another kind's marker file is read by that kind (the image network's entry will be one)."""
    folder = fake_net_folder(tmp_path / "net", monkeypatch, seen := [])
    result = predict(image, parameters_config(folder, camera=CAMERA), tmp_path / "out")
    assert seen == [folder, (96, 96, 3)]
    assert result.stage1.program == run_parameters(parse_parameters(GOOD, SCHEMAS)).program_text
    with pytest.raises(InputFileError, match="stage1_net.json .*config.json"):
        stage1_module.load_reader(tmp_path, None)  # holds neither marker


def test_a_category_fixed_in_place_is_mounted_unless_told(image, tmp_path):
    """A faucet from stage 1 is checked with its root held and exported with its base fixed; an
    explicit choice wins, and a category that stands free stays free."""
    faucet = format_parameters(sample_parameters("faucet", 0), SCHEMAS["faucet"])
    runs = {"default": (faucet, None), "told": (faucet, False), "stapler": (GOOD, None)}
    mounted = {name: predict(image, parameters_config(read=lambda rgb, t=text: t, camera=CAMERA, mounted=flag),
                             tmp_path / name).mounted
               for name, (text, flag) in runs.items()}
    assert mounted == {"default": True, "told": False, "stapler": False}
    assert "<freejoint" not in (tmp_path / "default" / "object.xml").read_text()
    assert "<freejoint" in (tmp_path / "told" / "object.xml").read_text()


def test_stage_2_is_told_the_joints_of_stage_1s_object_as_in_training(image, tmp_path, monkeypatch):
    monkeypatch.setattr(release, "STAGE1_DIR", fake_net_folder(tmp_path / "stage1", monkeypatch, []))
    prompts: list[str] = []

    def star(prompt: str) -> str:
        prompts.append(prompt)
        return rigid_star(prompt)

    predict(image, PredictConfig(generate_structure=star, camera=CAMERA), tmp_path / "a")
    joints = len(run_parameters(parse_parameters(GOOD, SCHEMAS)).structure.joints())
    assert joints >= 1 and f"Joints: {joints}" in prompts[0].splitlines()
    predict(image, PredictConfig(generate_structure=star, camera=CAMERA, num_joints=5), tmp_path / "b")
    assert "Joints: 5" in prompts[1].splitlines()  # the caller's count wins
    predict(image, PredictConfig(Stage1Config(f"parts:{tmp_path / 'a' / 'parts'}"), generate_structure=star,
                                 camera=CAMERA), tmp_path / "c")
    assert not any(line.startswith("Joints") for line in prompts[2].splitlines())  # a parts folder names no count
