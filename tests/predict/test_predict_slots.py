"""`jax3dc predict IMAGE --stage1 slots --slots-model DIR`: a tiny random slots network runs end to
end into box parts, seg.png and slots.json; a blank image is refused in one line before the network
runs, and a network that keeps no slot ends in one clear line with the outputs written so far."""

from __future__ import annotations

import json

import numpy as np
import pytest
from flax import nnx

from jax3dc.cli import main
from jax3dc.geometry.parts import load_parts
from jax3dc.render import png_bytes
from jax3dc.stage1_slots import KINDS, SlotsNet, SlotsNetConfig, save_slots
from predict_cases import write_image


def _network(folder, exists_bias: float):
    """A tiny random network whose every slot exists (bias +8) or none does (bias -8)."""
    model = SlotsNet(SlotsNetConfig.tiny(slots=4), nnx.Rngs(0))
    model.exists.bias[...] = np.full((1,), exists_bias, np.float32)
    model.exists.kernel[...] = np.zeros_like(model.exists.kernel[...])
    return save_slots(folder, model)


@pytest.fixture(scope="module")
def image(tmp_path_factory):
    return write_image(tmp_path_factory.mktemp("inputs") / "image.png")


def _predict(image, model, out, tmp_path) -> int:
    missing = tmp_path / "no_structure_model"  # stage 2 stops the run: stage 1's outputs are what is tested
    return main(["predict", str(image), "--stage1", "slots", "--slots-model", str(model),
                 "--structure-model", str(missing), "--out", str(out)])


def test_slots_give_box_parts_segmentation_and_slots_json(image, tmp_path, capsys):
    out = tmp_path / "out"
    assert _predict(image, _network(tmp_path / "net", 8.0), out, tmp_path) == 1
    assert "no_structure_model" in capsys.readouterr().err  # stopped at stage 2, not before
    parts = load_parts(out / "parts")
    assert sorted(parts) == [1, 2, 3, 4]
    lo = np.min([m.bounds[0] for m in parts.values()], axis=0)
    hi = np.max([m.bounds[1] for m in parts.values()], axis=0)
    assert (hi - lo).max() == pytest.approx(1.0, abs=1e-6)  # the normalised frame
    doc = json.loads((out / "slots.json").read_text())
    assert len(doc["parts"]) == 4 and {p["kind"] for p in doc["parts"]} <= set(KINDS)
    names = json.loads((out / "prediction.json").read_text())["names"]
    assert sorted(names) == ["1", "2", "3", "4"]
    assert (out / "seg.png").is_file() and (out / "prompt.txt").is_file()


def test_a_blank_image_is_refused_in_one_line(tmp_path, capsys):
    blank = tmp_path / "blank.png"
    blank.write_bytes(png_bytes(np.full((64, 64, 3), 200, np.uint8)))
    assert _predict(blank, _network(tmp_path / "net", 8.0), tmp_path / "out", tmp_path) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no object found" in err[0], err
    assert not (tmp_path / "out" / "slots.json").exists()


def test_no_slot_kept_is_one_clear_line_and_keeps_the_outputs(image, tmp_path, capsys):
    out = tmp_path / "out"
    assert _predict(image, _network(tmp_path / "net", -8.0), out, tmp_path) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "found no part" in err[0] and "Traceback" not in err[0], err
    assert (out / "image.png").is_file() and json.loads((out / "slots.json").read_text())["parts"] == []


def test_slots_without_a_model_folder_names_the_flag(image, tmp_path, capsys):
    assert main(["predict", str(image), "--stage1", "slots", "--out", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--slots-model" in err[0], err
