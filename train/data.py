"""What a run reads: its tokenizer, image processor settings and a loader per split.

``data=synthetic`` gives the built-in counting sequences (for speed and sharding tests);
anything else names dataset folders that the grain loader reads. There is no default: an empty
``data`` is a ConfigError (train.config.NO_DATA). The tokenizer and processor
settings are also written next to the exported model, so generation encodes prompts exactly
as training did.
"""

from __future__ import annotations

import os
from typing import Iterator

import jax

from jax3dc.model.config import Qwen3VLConfig
from jax3dc.processing.processor import ImageProcessorConfig
from jax3dc.processing.tokenizer import Tokenizer, load_tokenizer
from jax3dc.structure.box_frame import PivotFrame
from train.batch import ImageLayout, SyntheticBatches
from train.config import ConfigError, TrainConfig, require_data


def run_tokenizer(cfg: TrainConfig) -> Tokenizer:
    """cfg.tokenizer, else the init checkpoint's tokenizer.json, else the packaged Qwen3 one."""
    if cfg.tokenizer:
        return load_tokenizer(cfg.tokenizer, check_special_ids=False)
    if os.path.isfile(os.path.join(cfg.init, "tokenizer.json")):
        return load_tokenizer(cfg.init)
    return load_tokenizer()


def run_processor(cfg: TrainConfig, model: Qwen3VLConfig) -> ImageProcessorConfig:
    """The init checkpoint's preprocessor settings; for a preset, Qwen3-VL's normalisation with
    the model's patches and the area pinned to image_size², so inference sees what training saw."""
    if os.path.isfile(os.path.join(cfg.init, "preprocessor_config.json")):
        return ImageProcessorConfig.from_pretrained(cfg.init)
    v = model.vision
    patches = dict(patch_size=v.patch_size, temporal_patch_size=v.temporal_patch_size, merge_size=v.spatial_merge_size)
    if not cfg.image_size:
        return ImageProcessorConfig(**patches)
    return ImageProcessorConfig(**patches, min_pixels=cfg.image_size**2, max_pixels=cfg.image_size**2)


def _synthetic(cfg: TrainConfig, model: Qwen3VLConfig, split: str, padding: bool) -> SyntheticBatches:
    image = None
    if cfg.image_size:
        v = model.vision
        side, unit = cfg.image_size // v.patch_size, v.spatial_merge_size
        if cfg.image_size % (v.patch_size * unit):
            raise ConfigError(f"image_size {cfg.image_size} is not a multiple of patch x merge = {v.patch_size * unit}")
        image = ImageLayout(model.vision_start_token_id, model.image_token_id, model.vision_end_token_id,
                            (side, side), unit, v.patch_dim)
    text_vocab = min(model.text.vocab_size, model.vision_start_token_id, model.image_token_id)
    return SyntheticBatches(vocab=model.text.vocab_size, text_vocab=text_vocab, seq_len=cfg.seq_len,
                            global_rows=cfg.batch_size, seed=cfg.seed + (0 if split == "train" else 1000),
                            image=image, process_index=jax.process_index(), process_count=jax.process_count(),
                            padding=padding)


def run_pivot_frame(cfg: TrainConfig) -> PivotFrame:
    """cfg.pivot_frame, else the frame the init checkpoint was trained with, else absolute."""
    if cfg.pivot_frame:
        try:
            return PivotFrame(cfg.pivot_frame)
        except ValueError as e:
            raise ConfigError(f"--set pivot_frame={cfg.pivot_frame}: {e}") from None
    return PivotFrame.load(cfg.init) if os.path.isdir(cfg.init) else PivotFrame()


def make_loader(cfg: TrainConfig, model: Qwen3VLConfig, split: str, tokenizer: Tokenizer | None = None,
                processor: ImageProcessorConfig | None = None, padding: bool = True) -> Iterator:
    """This process's loader for `split` ('train' or 'val')."""
    require_data(cfg)
    if cfg.data == "synthetic":
        return _synthetic(cfg, model, split, padding)
    # lazy: grain's shard loader, 0.06 s on top of train.loop; synthetic runs (tests, benchmarks) never use it
    from data_pipeline.loader import LoaderConfig, ShardLoader

    sources = cfg.val_data if split == "val" and cfg.val_data else cfg.data
    train = split == "train"
    if jax.process_count() > 1 and cfg.batch_size % jax.process_count():
        raise ConfigError(f"batch_size {cfg.batch_size} does not split over {jax.process_count()} processes")
    loader_cfg = LoaderConfig(
        sources=tuple(s for s in sources.split(",") if s), seq_len=cfg.seq_len,
        rows=cfg.batch_size // jax.process_count(), split=split, task=cfg.task,
        tasks=cfg.data_tasks if sources == cfg.data else (),
        weights=cfg.data_weights if sources == cfg.data else (), pack=cfg.pack, image_size=cfg.image_size,
        pixel_dtype="bfloat16" if cfg.compute_dtype == "bfloat16" else "float32", seed=cfg.seed, shuffle=train, workers=cfg.loader_workers if train else 0,
        process_index=jax.process_index(), process_count=jax.process_count(), pivot_frame=run_pivot_frame(cfg),
        score_placeholder_materials=cfg.score_placeholder_materials)
    return ShardLoader.create(loader_cfg, model, tokenizer or run_tokenizer(cfg), processor or run_processor(cfg, model))
