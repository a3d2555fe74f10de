"""A tiny random Qwen3-VL checkpoint folder for generation tests: its vocabulary covers the real
Qwen special ids, and it is saved with the real tokenizer and an image processor sized for it."""

from __future__ import annotations

import dataclasses
from pathlib import Path


def write_tiny_checkpoint(path: Path) -> Path:
    from flax import nnx

    from jax3dc.processing.chat import VL_CHAT_TEMPLATE
    from jax3dc.model.config import Qwen3VLConfig
    from jax3dc.model.params import save_pretrained
    from jax3dc.processing.processor import ImageProcessorConfig
    from jax3dc.model.qwen3_vl import Qwen3VL
    from jax3dc.processing.tokenizer import QWEN_VL_SPECIAL_IDS, load_tokenizer

    config = dataclasses.replace(
        Qwen3VLConfig.tiny(vocab_size=151936, tie_word_embeddings=True),
        image_token_id=QWEN_VL_SPECIAL_IDS["<|image_pad|>"], video_token_id=151656,
        vision_start_token_id=QWEN_VL_SPECIAL_IDS["<|vision_start|>"],
        vision_end_token_id=QWEN_VL_SPECIAL_IDS["<|vision_end|>"])
    save_pretrained(Qwen3VL(config, rngs=nnx.Rngs(0)), config, path)
    load_tokenizer().save_pretrained(path, chat_template=VL_CHAT_TEMPLATE)
    ImageProcessorConfig(patch_size=config.vision.patch_size, merge_size=config.vision.spatial_merge_size,
                         min_pixels=16 * 16, max_pixels=32 * 32).save_pretrained(path)
    return path


RELEASE_VOCAB = 1408  # the shipped model's BPE (jax3dc/release): the parameters grammar lifts in seconds for it


def write_tiny_release_vocab_checkpoint(path: Path, seed: int = 0) -> Path:
    """A tiny random Qwen3-VL over the shipped model's BPE vocabulary, saved with that tokenizer: a
    stand-in for a stage-1 parameters model (and a structure model) whose decodes the grammars keep valid."""
    import shutil

    from flax import nnx

    from jax3dc.model.config import Qwen3VLConfig
    from jax3dc.model.params import save_pretrained
    from jax3dc.model.qwen3_vl import Qwen3VL
    from jax3dc.processing.processor import ImageProcessorConfig
    from jax3dc.release import MODEL_DIR

    config = dataclasses.replace(Qwen3VLConfig.tiny(vocab_size=RELEASE_VOCAB, tie_word_embeddings=True),
                                 image_token_id=1297, video_token_id=1298, vision_start_token_id=1294,
                                 vision_end_token_id=1295)
    save_pretrained(Qwen3VL(config, rngs=nnx.Rngs(seed)), config, path)
    for name in ("tokenizer.json", "tokenizer_config.json", "chat_template.jinja"):
        shutil.copy(MODEL_DIR / name, path / name)
    ImageProcessorConfig(patch_size=config.vision.patch_size, merge_size=config.vision.spatial_merge_size,
                         min_pixels=16 * 16, max_pixels=32 * 32).save_pretrained(path)
    return path
