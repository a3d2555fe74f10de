"""AdamW with linear warm-up and cosine decay, gradient clipping, and the freezing filter.

Freezing is a filter on parameter paths: the optimiser is built over the trainable parameters
only, so frozen ones have no optimiser state and no gradient is ever computed for them.
"""

from __future__ import annotations

import re
from typing import Sequence

import jax
import optax
from flax import nnx

from train.adam_moments import scale_by_adam_stored_in
from train.config import TrainConfig


def learning_rate(cfg: TrainConfig) -> optax.Schedule:
    """0 -> lr linearly over warmup_steps, then cosine down to lr * end_lr_ratio at `steps`."""
    return optax.warmup_cosine_decay_schedule(
        init_value=0.0, peak_value=cfg.lr, warmup_steps=cfg.warmup_steps,
        decay_steps=cfg.steps, end_value=cfg.lr * cfg.end_lr_ratio)


def _decays(params):
    """Weight decay on matrices only; norms' scales and biases are left alone."""
    return jax.tree.map(lambda p: p.ndim >= 2, params)


def _scale_by_adam(cfg: TrainConfig) -> optax.GradientTransformation:
    """optax's Adam scaling (moments in the trainable parameters' dtype), or with `moments_dtype`
    both moments stored in that dtype (train/adam_moments.py)."""
    if not cfg.moments_dtype:
        return optax.scale_by_adam(b1=cfg.b1, b2=cfg.b2, eps=cfg.eps)
    return scale_by_adam_stored_in(cfg.moments_dtype, cfg.b1, cfg.b2, cfg.eps, seed=cfg.seed)


def build_optimizer(cfg: TrainConfig) -> optax.GradientTransformation:
    """Clip the global norm, then AdamW. The AdamW part is optax.adamw's own chain (Adam scaling,
    decoupled weight decay, learning rate) with the Adam scaling chosen by `_scale_by_adam`, so the
    optimiser state keeps optax.adamw's layout and older checkpoints still restore."""
    return optax.chain(
        optax.clip_by_global_norm(cfg.clip_norm),
        optax.chain(_scale_by_adam(cfg), optax.add_decayed_weights(cfg.weight_decay, _decays),
                    optax.scale_by_learning_rate(learning_rate(cfg))))


def path_name(path: Sequence) -> str:
    """'visual/blocks/0/attn/qkv/kernel' for an nnx path."""
    return "/".join(str(getattr(p, "key", getattr(p, "idx", p))) for p in path)


def trainable_filter(freeze: Sequence[str], adapters_only: bool = False) -> nnx.filterlib.Filter:
    """nnx filter: Params whose path matches none of the `freeze` regexes; with `adapters_only`
    (LoRA) only the adapters (nnx.LoRAParam) among them, so every base weight is frozen."""
    patterns = [re.compile(p) for p in freeze]

    def is_frozen(path, _value) -> bool:
        name = path_name(path)
        return any(p.search(name) for p in patterns)

    return nnx.All(nnx.LoRAParam if adapters_only else nnx.Param, nnx.Not(is_frozen))
