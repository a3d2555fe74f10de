"""The model plumbing of `predict` with a tiny random Qwen3-VL checkpoint (real tokenizer).

Its output is garbage, so the structure model's text is an invalid structure and the code
model's text an invalid program: both must end in the typed errors with the raw text kept. The
in-memory (I, S) of predict goes through the same sampler as a Record's: its reply is the batched
sample's, without the stop token. (The test with tiny *trained* models is the lead's.)
"""

from __future__ import annotations

from pathlib import Path

import pytest

from predict_cases import CAMERA, write_glb, write_image
from tests.tiny_checkpoint import write_tiny_checkpoint

MAX_NEW_TOKENS = 4


@pytest.fixture(scope="module")
def checkpoint(tmp_path_factory) -> Path:
    return write_tiny_checkpoint(tmp_path_factory.mktemp("tiny_checkpoint"))


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("inputs")
    return write_image(folder / "image.png"), write_glb(folder / "object.glb")


@pytest.mark.slow
def test_in_memory_generation_equals_record_generation(checkpoint, inputs, tmp_path):
    import jax

    from data_pipeline.record import Record
    from jax3dc.decoding import DecodeOptions, Decoding
    from jax3dc.errors import StructureError
    from jax3dc.predict.pipeline import PredictConfig, predict
    from jax3dc.predict.stage1 import Stage1Config
    from jax3dc.sampler import Sampler

    out = tmp_path / "out"
    decoding = Decoding(DecodeOptions(constrained=False), MAX_NEW_TOKENS, "float32")
    with pytest.raises(StructureError):  # a random model, unconstrained, does not write a valid structure
        predict(inputs[0], PredictConfig(Stage1Config(f"mesh:{inputs[1]}"), checkpoint, decoding=decoding,
                                         camera=CAMERA), out)
    raw = (out / "structure_raw.txt").read_text()
    assert (out / "report.html").exists() and not (out / "structure.json").exists()

    sampler = Sampler.load(checkpoint, dtype="float32")
    record = Record("x", inputs[0].read_bytes(), (out / "seg.png").read_bytes(), (out / "prompt.txt").read_text(), "")
    with jax.default_matmul_precision("highest"):
        sample = sampler.generate_batch([sampler.prompt(record)], 1, MAX_NEW_TOKENS, bucket=1,
                                        options=DecodeOptions(constrained=False))[0][0]
    assert sample.reply == raw
    assert sample.text in (raw, raw + "<|im_end|>", raw + "<|endoftext|>")  # eval keeps the stop token


@pytest.mark.slow
def test_code_model_garbage_is_a_program_error_with_the_program_kept(checkpoint, inputs, tmp_path):
    from jax3dc.decoding import Decoding
    from jax3dc.errors import ProgramError
    from jax3dc.predict.pipeline import PredictConfig, predict
    from jax3dc.predict.stage1 import Stage1Config

    config = PredictConfig(Stage1Config("code", code_model_dir=checkpoint), checkpoint,
                           decoding=Decoding(max_new_tokens=MAX_NEW_TOKENS, dtype="float32"))
    with pytest.raises(ProgramError):
        predict(inputs[0], config, tmp_path)
    assert (tmp_path / "program.txt").exists()


def test_a_checkpoint_folder_is_loaded_once(tmp_path, monkeypatch):
    from jax3dc.sampler import Sampler
    from jax3dc.predict.pipeline import Checkpoints

    loads = []
    monkeypatch.setattr(Sampler, "load", classmethod(lambda cls, folder, dtype: loads.append(folder) or object()))
    checkpoints = Checkpoints("float32")
    (tmp_path / "a").mkdir()
    first = checkpoints.get(tmp_path / "a")
    assert checkpoints.get(str(tmp_path / "a")) is first  # the same folder, however it is written
    assert checkpoints.get(tmp_path / "a" / ".." / "a") is first
    assert checkpoints.get(tmp_path / "b") is not first
    assert len(loads) == 2


def test_a_stage1_reader_loads_once_per_folder(tmp_path, monkeypatch):
    from jax3dc.decoding import Decoding
    from jax3dc.predict import pipeline

    loads = []  # the shipped stage-1 network is one: 0.3 s to load and its program to compile
    monkeypatch.setattr(pipeline, "load_reader", lambda folder, settings: loads.append(folder) or (lambda rgb: ""))
    checkpoints = pipeline.Checkpoints("float32")
    first = checkpoints.reader(tmp_path, Decoding())
    assert checkpoints.reader(str(tmp_path / "."), Decoding()) is first and len(loads) == 1
