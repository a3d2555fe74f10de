"""`jax3dc train` on real shards: the loader feeds the trainer, the run resumes with the loader's
position, and the exported model generates from prompts encoded exactly as in training."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from data_pipeline.examples import ExampleEncoder
from tests.loader.loader_fixtures import CATEGORIES, IMAGE, record, write_dataset
from train.config import TrainConfig


@pytest.fixture(scope="module")
def dataset(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("ds")
    write_dataset(folder, [record(c, s) for s in range(2) for c in CATEGORIES], shards=2)
    write_dataset(folder, [record(c, 7, "val") for c in CATEGORIES[:3]], shards=1, split="val")
    return folder


def config(dataset: Path, out: Path, steps: int, **kw) -> TrainConfig:
    return TrainConfig(init="tiny", data=str(dataset), output_dir=str(out), seq_len=2400, image_size=IMAGE,
                       batch_size=2, grad_accum=1, pack=2, steps=steps, warmup_steps=1, lr=3e-3,
                       compute_dtype="float32", log_every=1, eval_every=2, eval_batches=1, save_every=2,
                       remat="none", freeze=(), **kw)


@pytest.mark.slow
def test_train_on_shards_resume_and_export(dataset: Path, tmp_path: Path) -> None:
    from jax3dc.sampler import Sampler
    from train.loop import run

    whole, losses = [], []
    run(config(dataset, tmp_path / "whole", 4), on_step=lambda s, m: whole.append(m["loss"]))
    assert all(np.isfinite(whole)) and whole[-1] < whole[0]
    # stop after step 2 (its checkpoint holds the loader position), then continue to step 4
    run(config(dataset, tmp_path / "split", 2), on_step=lambda s, m: losses.append(m["loss"]))
    run(config(dataset, tmp_path / "split", 4), on_step=lambda s, m: losses.append(m["loss"]))
    np.testing.assert_allclose(losses, whole, rtol=1e-5)

    generator = Sampler.load(tmp_path / "whole" / "hf", dtype="float32")
    rec = record(CATEGORIES[0], 0)
    prompt = generator.prompt(rec)
    encoder = ExampleEncoder(generator.tokenizer, generator.processor, 2)
    trained = encoder.encode(rec)
    answer_start = int(np.argmax(trained.labels >= 0))
    np.testing.assert_array_equal(prompt.input_ids, trained.input_ids[:answer_start])
    assert generator.config.image_token_id == generator.tokenizer.special.image_pad


def test_time_limit_stops_saves_exports_and_plots(tmp_path: Path) -> None:
    from train.checkpoint import RunCheckpoints
    from train.loop import run

    cfg = TrainConfig(init="tiny", data="synthetic", output_dir=str(tmp_path), seq_len=32, image_size=0,
                      batch_size=2, grad_accum=1, steps=50, warmup_steps=1, time_limit_min=1e-4,
                      log_every=10, eval_every=100, eval_batches=1, save_every=100, remat="none")
    result = run(cfg)
    assert result.final_step == 1  # the compiling first step alone outlasts 6 ms
    ckpt = RunCheckpoints(str(tmp_path / "checkpoints"), 3)
    assert ckpt.latest_step() == 1
    ckpt.close()
    assert (tmp_path / "hf" / "config.json").is_file() and (tmp_path / "loss.png").stat().st_size > 1000


def test_missing_validation_split_stops_before_training(tmp_path: Path) -> None:
    """Shards with train records only: the run refuses before its first step (it used to read the
    repeating records forever at the first validation); with eval_batches=0 it trains."""
    from data_pipeline.loader import LoaderError
    from train.loop import run

    data = write_dataset(tmp_path / "ds", [record(c, 0) for c in CATEGORIES[:2]], shards=1)
    steps: list[int] = []
    with pytest.raises(LoaderError, match=r"validation data: split 'val'.*no usable record.*eval_batches=0"):
        run(config(data, tmp_path / "run", 2), on_step=lambda s, m: steps.append(s))
    assert steps == [] and not (tmp_path / "run" / "checkpoints").exists()
    result = run(dataclasses.replace(config(data, tmp_path / "run", 2), eval_batches=0))
    assert result.final_step == 2 and result.best_val_loss is None
