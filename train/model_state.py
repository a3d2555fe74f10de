"""The model as the trainer holds it: a graph definition plus two parameter states, trainable
(master dtype, optimised) and frozen (compute dtype, never differentiated), both placed on the
mesh by their logical axes; and how a batch is scored by it.

The model itself (jax3dc.model) knows nothing about optimisers or data.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from flax import nnx
from jax.sharding import Mesh

from jax3dc.model import params as hf_params
from jax3dc.processing.bpe import config_for_tokenizer
from jax3dc.model.config import Qwen3VLConfig
from jax3dc.model.lora import add_lora
from jax3dc.model.qwen3_vl import Qwen3VL
from jax3dc.model.random_weights import build_random
from jax3dc.processing.chat import VL_CHAT_TEMPLATE
from jax3dc.sharding import model_shardings
from train.config import ConfigError, TrainConfig, lora_spec, sharding_rules
from train.optimizer import trainable_filter
from train.parallel import state_shardings
from train.loss import token_loss
from train.step import cast_floats

PRESETS = ("tiny", "mini", "small", "release", "qwen3_vl_2b", "qwen3_vl_4b", "qwen3_vl_8b")
LOSS_CHUNK = 1024  # sequence positions per logits chunk: bounds the [rows, chunk, vocab] buffer


@dataclass
class ModelState:
    """Everything the trainer needs to run, save and export the model."""

    config: Qwen3VLConfig
    graphdef: nnx.GraphDef
    trainable: Any  # nnx.State
    frozen: Any  # nnx.State
    trainable_sharding: Any
    frozen_sharding: Any

    def merged(self) -> nnx.Module:
        return nnx.merge(self.graphdef, self.trainable, self.frozen)


def model_config(init: str) -> Qwen3VLConfig:
    """Preset name, or an HF checkpoint directory's config.json."""
    if init in PRESETS:
        return getattr(Qwen3VLConfig, init)()
    path = os.path.join(init, "config.json")
    if not os.path.isfile(path):
        raise ConfigError(f"init {init!r} is neither a preset ({', '.join(PRESETS)}) nor a directory "
                          "with config.json")
    with open(path) as f:
        return Qwen3VLConfig.from_hf_dict(json.load(f))


def dtypes(cfg: TrainConfig) -> tuple[jnp.dtype, jnp.dtype]:
    """(compute dtype, master dtype of the trainable parameters)."""
    compute = jnp.dtype(cfg.compute_dtype)
    return compute, (jnp.dtype(jnp.float32) if cfg.master_fp32 else compute)


def _constructor(cfg: TrainConfig, mcfg: Qwen3VLConfig, attention_impl: str | None):
    """The base model's constructor; with LoRA its weights are stored in the compute dtype (they
    are all frozen), which halves their memory next to float32 master weights."""
    compute, master = dtypes(cfg)
    base = compute if cfg.lora_rank else master
    return lambda: Qwen3VL(mcfg, rngs=nnx.Rngs(cfg.seed), dtype=compute, param_dtype=base,
                           attention_impl=attention_impl, remat=cfg.remat, scan_layers=cfg.scan_layers)


def _with_lora(cfg: TrainConfig, model: Qwen3VL) -> Qwen3VL:
    """`model` with the run's adapters (in the master dtype) added, or unchanged without LoRA."""
    if not cfg.lora_rank:
        return model
    _, master = dtypes(cfg)
    return add_lora(model, lora_spec(cfg), rngs=nnx.Rngs(cfg.seed), param_dtype=master)


def _place_adapters(model: Qwen3VL, shardings: Any) -> None:
    """Puts the adapters (built on the host, the same on every process) on their shardings."""
    def place(x, sharding):
        host = np.asarray(x)
        return jax.make_array_from_callback(host.shape, sharding, lambda idx: host[idx])

    nnx.update(model, jax.tree.map(place, nnx.state(model, nnx.LoRAParam), shardings))


def abstract_model(cfg: TrainConfig, mcfg: Qwen3VLConfig, attention_impl: str | None = None) -> Qwen3VL:
    """The model `create` builds (adapters included) as shapes and dtypes, nothing allocated:
    for placing it, and for counting its bytes (bench/train_memory.py)."""
    return nnx.eval_shape(lambda: _with_lora(cfg, _constructor(cfg, mcfg, attention_impl)()))


def create(cfg: TrainConfig, mesh: Mesh, attention_impl: str | None = None, tokenizer=None) -> ModelState:
    """Build the model on the mesh: random weights for a preset (sized to `tokenizer` when one
    is given), else the HF checkpoint's; with LoRA, fresh adapters on it (B = 0: the model's
    output is the base model's until the first update)."""
    mcfg = model_config(cfg.init)
    if tokenizer is not None and cfg.init in PRESETS:
        mcfg = config_for_tokenizer(mcfg, tokenizer)  # vocabulary and special ids of the run's tokenizer
    compute, _ = dtypes(cfg)
    build = _constructor(cfg, mcfg, attention_impl)
    is_trainable = trainable_filter(cfg.freeze, adapters_only=cfg.lora_rank > 0)
    abstract = abstract_model(cfg, mcfg, attention_impl)
    graphdef, abs_train, abs_frozen = nnx.split(abstract, is_trainable, ...)
    rules = sharding_rules(cfg)
    train_sh, frozen_sh = state_shardings(abs_train, mesh, rules), state_shardings(abs_frozen, mesh, rules)
    if not jax.tree.leaves(abs_train):
        raise ConfigError(f"freeze patterns {cfg.freeze} leave no parameter to train")

    if cfg.init in PRESETS:
        # One small fill program per parameter shape: a jitted 4B initialiser compiles for minutes.
        model = build_random(build, seed=cfg.seed, shardings=model_shardings(nnx.eval_shape(build), mesh, rules))
    else:
        model = _load_hf(cfg, mesh, attention_impl)
    model = _with_lora(cfg, model)
    _place_adapters(model, state_shardings(nnx.state(abstract, nnx.LoRAParam), mesh, rules))
    _, t, f = nnx.split(model, is_trainable, ...)
    cast = jax.jit(lambda t, f: (t, cast_floats(f, compute)), out_shardings=(train_sh, frozen_sh))
    trainable, frozen = cast(t, f)
    return ModelState(mcfg, graphdef, trainable, frozen, train_sh, frozen_sh)


def _load_hf(cfg: TrainConfig, mesh: Mesh, attention_impl: str | None) -> Qwen3VL:
    compute, master = dtypes(cfg)
    model, _ = hf_params.load_pretrained(cfg.init, dtype=compute if cfg.lora_rank else master, mesh=mesh,
                                         rules=sharding_rules(cfg), compute_dtype=compute,
                                         attention_impl=attention_impl, remat=cfg.remat,
                                         scan_layers=cfg.scan_layers)
    return model


def export_hf(state: ModelState, directory: str, tokenizer=None, processor=None, pivot_frame=None) -> None:
    """Write the model as an HF directory (safetensors + config.json, and the tokenizer and
    image-processor files the run used, so generation encodes prompts exactly as training did).
    LoRA adapters are merged into their kernels: the directory holds a plain model.

    With several processes every process must call this (each tensor is gathered from all of
    them, one at a time); only process 0 writes."""
    model = state.merged()
    hf_params.save_pretrained(model, model.config, directory)
    if jax.process_index() != 0:
        return
    if tokenizer is not None:
        tokenizer.save_pretrained(directory, chat_template=VL_CHAT_TEMPLATE)
    if processor is not None:
        processor.save_pretrained(directory)
    if pivot_frame is not None and pivot_frame.name != "absolute":
        pivot_frame.save(directory)


def count_params(tree: Any) -> int:
    return int(sum(np.prod(x.shape) for x in jax.tree.leaves(tree)))


def model_inputs(micro: dict[str, jax.Array]) -> dict[str, Any]:
    """Batch-protocol arrays -> the model's keyword arguments.

    Rows own their images (1 or k each, all of one size): each image attends in its own vision
    window, and with k images per row the model places features per row (packed rows may leave
    image slots unused)."""
    pixel_values, grid = micro.get("pixel_values"), micro.get("image_grid_thw")
    images_per_row = window = None
    if pixel_values is not None:
        per_row = 1 if grid.ndim == 2 else grid.shape[1]
        window = pixel_values.shape[1] // per_row
        images_per_row = per_row if grid.ndim == 3 else None
        pixel_values = pixel_values.reshape(-1, pixel_values.shape[-1])
        grid = grid.reshape(-1, 3)
    position_ids = micro.get("position_ids")
    if position_ids is not None:  # protocol [rows, 3, L] -> model [3, rows, L]
        position_ids = jnp.transpose(position_ids, (1, 0, 2))
    return dict(input_ids=micro["input_ids"], attention_mask=micro.get("attention_mask"),
                pixel_values=pixel_values, image_grid_thw=grid, position_ids=position_ids,
                segment_ids=micro.get("segment_ids"), images_per_row=images_per_row, vision_window=window)


def score(model: Qwen3VL, micro: dict[str, jax.Array]) -> tuple[jax.Array, jax.Array]:
    """(sum of masked token NLL, number of correct predictions) for one micro-batch; the LM head
    is applied LOSS_CHUNK positions at a time and split over the mesh (train/loss.py)."""
    hidden = model(**model_inputs(micro), return_hidden=True)
    length = hidden.shape[1]
    chunk = LOSS_CHUNK if length % LOSS_CHUNK == 0 else length
    return token_loss(hidden.astype(model.dtype), model.output_head(), micro["labels"], micro["loss_mask"], chunk)


def vision_params(state: ModelState) -> int:
    """Parameters of the vision tower and its mergers (run forward only when frozen)."""
    visual = nnx.state(state.merged(), lambda path, _: path and path[0] == "visual")
    return count_params(visual)
