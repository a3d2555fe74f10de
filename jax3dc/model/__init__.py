"""Qwen3-VL in Flax NNX: the model (qwen3_vl.py), its config (config.py) and HF checkpoint
conversion both ways (params.py). Cache API for generation: see qwen3_vl.py's docstring."""

from jax3dc.model.config import Qwen3VLConfig, TextConfig, VisionConfig
from jax3dc.model.params import load_pretrained, save_pretrained
from jax3dc.model.qwen3_vl import KVCache, Qwen3VL

__all__ = ["KVCache", "Qwen3VL", "Qwen3VLConfig", "TextConfig", "VisionConfig", "load_pretrained",
           "save_pretrained"]
