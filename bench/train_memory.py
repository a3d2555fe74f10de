"""Bytes of a training run's resident state — weights, gradients, optimiser state — counted
from the model's abstract tree (jax.eval_shape: nothing allocated, runs on a laptop), for the
precision settings of issue 51. Activations and XLA's temporaries come on top; a GPU run of
bench/train_step.py reports the real peak to hold these against.

    python3 bench/train_memory.py --preset qwen3_vl_4b [--set grad_accum=4 ...]

One row per setting: fp32 master with fp32 moments (the default), fp32 master with bf16 moments
(`moments_dtype=bfloat16`), bf16 master (`master_fp32=false`), and bf16 master rounded
stochastically with stochastically rounded bf16 moments (the same bytes as bf16 master). Gradients are counted as the
step holds them (train/step.py): one tree in the trainable weights' dtype, plus a float32
accumulation buffer when grad_accum > 1.
"""

from __future__ import annotations

import dataclasses
import os
import sys
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from flax import nnx

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from bench.options import add_json_lines, add_preset, append_json_lines, bench_parser  # noqa: E402
from train.config import TrainConfig, apply_overrides  # noqa: E402
from train.model_state import abstract_model, dtypes, model_config  # noqa: E402
from train.optimizer import build_optimizer, trainable_filter  # noqa: E402

SETTINGS = {  # name -> TrainConfig overrides
    "fp32_master_fp32_moments": ("master_fp32=true",),
    "fp32_master_bf16_moments": ("master_fp32=true", "moments_dtype=bfloat16"),
    "bf16_master": ("master_fp32=false",),
    "bf16_master_stochastic": ("master_fp32=false", "moments_dtype=bfloat16", "stochastic_rounding=true"),
}
GB = 1e9


def _bytes(tree: Any) -> int:
    return int(sum(int(np.prod(x.shape)) * x.dtype.itemsize for x in jax.tree.leaves(tree)))


def state_bytes(cfg) -> dict[str, int]:
    """Bytes of trainable weights, frozen weights (held in the compute dtype), gradients and
    optimiser state of a run of `cfg`, and their total."""
    compute, _ = dtypes(cfg)
    model = abstract_model(cfg, model_config(cfg.init))
    _, trainable, frozen = nnx.split(model, trainable_filter(cfg.freeze, adapters_only=cfg.lora_rank > 0), ...)
    n_trainable = sum(x.size for x in jax.tree.leaves(trainable))
    grads = _bytes(trainable) + (4 * n_trainable if cfg.grad_accum > 1 else 0)
    frozen_bytes = sum(x.size for x in jax.tree.leaves(frozen)) * jnp.dtype(compute).itemsize
    row = {"trainable": _bytes(trainable), "frozen": int(frozen_bytes), "grads": grads,
           "optimizer": _bytes(jax.eval_shape(build_optimizer(cfg).init, trainable))}
    return {**row, "total": sum(row.values())}


def main() -> None:
    ap = bench_parser(__doc__)
    add_preset(ap)
    ap.add_argument("--set", action="append", default=[], help="TrainConfig override key=value (as jax3dc train)")
    add_json_lines(ap)
    a = ap.parse_args()
    base = apply_overrides(TrainConfig(init=a.preset, grad_accum=1, batch_size=1), a.set)
    rows = []
    print(f"preset {a.preset}, grad_accum {base.grad_accum}, GB = 1e9 bytes (activations not counted)")
    print(f"{'setting':28s} {'trainable':>9s} {'frozen':>7s} {'grads':>7s} {'optimizer':>9s} {'total':>7s}")
    for name, overrides in SETTINGS.items():
        cfg = apply_overrides(dataclasses.replace(base), overrides)
        b = state_bytes(cfg)
        print(f"{name:28s} {b['trainable'] / GB:9.2f} {b['frozen'] / GB:7.2f} {b['grads'] / GB:7.2f} "
              f"{b['optimizer'] / GB:9.2f} {b['total'] / GB:7.2f}")
        rows.append({"bench": "train_memory", "preset": a.preset, "setting": name, "grad_accum": base.grad_accum,
                     "lora_rank": base.lora_rank, **{f"{k}_bytes": v for k, v in b.items()}})
    append_json_lines(a.json, rows)


if __name__ == "__main__":
    main()
