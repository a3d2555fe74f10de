"""The shipped default model: a small Qwen3-VL trained from scratch by `recipes/release_model.py`.

Pretrained Qwen3-VL weights cannot be fetched at run time, so the package carries its own
stage-2 structure model (bf16, under 24 MiB; SPEC §7). `predict`, `eval run` and `demo` use this
folder when no model folder is given. MODEL_CARD.md beside this file names its data, licence,
training run and measured tables; release_summary.json holds the recipe's own figures.

``stage1/`` holds the shipped stage-1 image network (jax3dc.stage1_net: image I -> a factory's
category and parameters; ``recipes/stage1_net.py``), with its own MODEL_CARD.md: with it,
``predict IMAGE`` needs no ``--stage1``.
"""

from __future__ import annotations

from pathlib import Path

MODEL_DIR = Path(__file__).resolve().parent
"""An HF checkpoint folder (config.json, safetensors shards, tokenizer, processor config)."""

STAGE1_DIR = MODEL_DIR / "stage1"
"""The shipped stage-1 model's folder (image I -> factory parameters), absent until one ships."""


STAGE1_DIR = MODEL_DIR / "stage1"
"""A jax3dc.stage1_net folder (stage1_net.json, model.safetensors): ``load_reader(STAGE1_DIR)``."""


def default_structure_model() -> Path:
    """The folder `--structure-model` / `--checkpoint` fall back to."""
    return MODEL_DIR


def default_stage1_model() -> Path | None:
    """The folder `--stage1-model` falls back to, or None when no stage-1 model ships."""
    return STAGE1_DIR if STAGE1_DIR.is_dir() else None
