"""Greedy generation against transformers' ``generate`` on a tiny random Qwen3-VL checkpoint.

The checkpoint is written by transformers' ``save_pretrained`` and read by our real loader, so
the test covers loading, prefill (with the vision tower and DeepStack), the KV cache, rotary
offsets after an image, and the decode loop. Float32 at highest matmul precision.
"""

from __future__ import annotations

import numpy as np
import pytest

import torch
import transformers

import jax  # noqa: E402
from PIL import Image  # noqa: E402

from jax3dc.model.config import Qwen3VLConfig  # noqa: E402
from jax3dc.generate import GenerationConfig  # noqa: E402
from jax3dc.model.params import load_pretrained  # noqa: E402
from jax3dc.processing.processor import ImageProcessorConfig, image_token_counts, preprocess_image  # noqa: E402
from tests.generation import generate  # noqa: E402

NEW_TOKENS = 32


@pytest.fixture(autouse=True)
def highest_precision():
    with jax.default_matmul_precision("highest"):
        yield


@pytest.fixture(scope="module")
def checkpoint(tmp_path_factory):
    config = Qwen3VLConfig.tiny()
    hf_dict = {k: v for k, v in config.to_hf_dict().items() if k not in ("architectures", "model_type", "dtype")}
    torch.manual_seed(0)
    hf = transformers.Qwen3VLForConditionalGeneration(transformers.Qwen3VLConfig(**hf_dict)).eval()
    path = tmp_path_factory.mktemp("tiny_qwen3_vl")
    hf.save_pretrained(path)
    model, loaded = load_pretrained(path)
    assert loaded == config
    return hf, model, config


def hf_greedy(hf, ids: np.ndarray, pixel_values=None, grid=None) -> np.ndarray:
    extra = {}
    if pixel_values is not None:
        extra = dict(pixel_values=torch.tensor(pixel_values), image_grid_thw=torch.tensor(grid),
                     mm_token_type_ids=torch.tensor((ids == hf.config.image_token_id).astype(np.int64)))
    with torch.no_grad():
        out = hf.generate(input_ids=torch.tensor(ids), attention_mask=torch.ones_like(torch.tensor(ids)),
                          max_new_tokens=NEW_TOKENS, min_new_tokens=NEW_TOKENS, do_sample=False,
                          eos_token_id=None, pad_token_id=0, **extra)
    return out[:, ids.shape[1]:].numpy()


def no_stop() -> GenerationConfig:
    return GenerationConfig(max_new_tokens=NEW_TOKENS, stop_ids=(), pad_id=0)


def test_greedy_text_only_matches_transformers(checkpoint) -> None:
    hf, model, config = checkpoint
    ids = np.random.default_rng(0).integers(0, config.vision_start_token_id, (1, 9))
    ours = generate(model, ids, config=no_stop())
    np.testing.assert_array_equal(np.asarray(ours.tokens), hf_greedy(hf, ids))
    assert np.asarray(ours.lengths).tolist() == [NEW_TOKENS]


def test_greedy_with_image_matches_transformers(checkpoint) -> None:
    hf, model, config = checkpoint
    vision = config.vision
    image = Image.fromarray(np.random.default_rng(1).integers(0, 256, (29, 41, 3), dtype=np.uint8))
    processed = preprocess_image(image, ImageProcessorConfig(
        patch_size=vision.patch_size, temporal_patch_size=vision.temporal_patch_size,
        merge_size=vision.spatial_merge_size, min_pixels=16 * 16, max_pixels=32 * 32))
    (pads,) = image_token_counts(processed.image_grid_thw, vision.spatial_merge_size)
    rng = np.random.default_rng(2)
    ids = np.concatenate([
        rng.integers(0, config.vision_start_token_id, 3), [config.vision_start_token_id],
        [config.image_token_id] * pads, [config.vision_end_token_id],
        rng.integers(0, config.vision_start_token_id, 5)])[None]
    expected = hf_greedy(hf, ids, processed.pixel_values, processed.image_grid_thw)
    ours = generate(model, ids, None, processed.pixel_values, processed.image_grid_thw, config=no_stop())
    np.testing.assert_array_equal(np.asarray(ours.tokens), expected)
