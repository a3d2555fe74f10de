"""`jax3dc train`: fine-tune (or train from scratch) per a TrainConfig with key=value overrides."""

from __future__ import annotations

import argparse

from jax3dc.compilation import use_compile_cache
from jax3dc.xla_flags import TRAINING_GPU_FLAGS, apply_gpu_defaults
from train.config import TrainConfig, apply_overrides, describe_fields, validate
from train.distributed import initialize_from_env


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "train", help="fine-tune Qwen3-VL on structure data (sharded over all devices)",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Train from an HF checkpoint directory (--init DIR) or a preset with random\n"
                    "weights (--init tiny|small|qwen3_vl_4b) on the dataset folders named by\n"
                    "--set data=DIR[,DIR...] (from 'jax3dc data build' / 'jax3dc data import'; required).\n"
                    "The vision tower is frozen; the run resumes from the latest checkpoint in\n"
                    "--output-dir if there is one.",
        epilog="Any setting can be changed with --set NAME=VALUE (repeatable), e.g.\n"
               "  jax3dc train --init small --output-dir runs/small --set data=runs/data --set lr=1e-3\n"
               "  jax3dc train --init tiny --set data=synthetic --set seq_len=64 --set mesh.fsdp=4"
               "   (speed test on built-in counting sequences)\n"
               "  jax3dc train --init DIR --set data=runs/data --set lora_rank=16 --set lr=1e-4"
               "   (LoRA: adapters only, bf16 base; hf/ export merged)\n\n"
               "Settings (name (type) = default):\n" + "\n".join(describe_fields()))
    p.add_argument("--init", help="preset name or HF checkpoint directory")
    p.add_argument("--output-dir", help="run directory: checkpoints, metrics.jsonl, hf/ export")
    p.add_argument("--steps", type=int, help="optimiser steps")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help="override a setting")
    p.set_defaults(func=_run)


def _run(args) -> int:
    overrides = list(args.set)
    for name, value in (("init", args.init), ("output_dir", args.output_dir), ("steps", args.steps)):
        if value is not None:
            overrides.insert(0, f"{name}={value}")
    cfg = apply_overrides(TrainConfig(), overrides)
    validate(cfg)  # bad settings (no data, say) stop here: before jax starts or anything is written

    apply_gpu_defaults(TRAINING_GPU_FLAGS)  # before the backend starts
    initialize_from_env()
    use_compile_cache(cfg.compile_cache)
    from train.loop import run  # lazy: the trainer (0.47 s after `jax3dc --help`, which imports this module)

    result = run(cfg)
    print(f"trained to step {result.final_step}: loss {result.last_loss:.4f}, run in {result.output_dir}")
    return 0
