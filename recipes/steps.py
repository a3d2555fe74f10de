"""The steps the trainers share: a ``jax3dc`` command that must succeed, ``--set`` overrides, where
a resumable training run stands, and packaging its weights as the release folders ship them."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import jax.numpy as jnp

from jax3dc.cli import main as jax3dc
from jax3dc.model.params import load_pretrained, save_pretrained

SHARD_BYTES = 12 * 2**20  # files coming back from a device host must stay under 16 MiB each


def call(argv: list[str]) -> None:
    """Run one ``jax3dc`` command in this process; a recipe cannot go on past a failed step, so a
    non-zero exit stops it with the command in the message."""
    print(f"[recipe] jax3dc {' '.join(argv)}", flush=True)
    code = jax3dc(argv)
    if code != 0:
        raise SystemExit(f"`jax3dc {' '.join(argv)}` failed with exit code {code}")


def set_flags(overrides: list[str]) -> list[str]:
    """``jax3dc train``'s ``--set`` flag before each override."""
    return [x for o in overrides for x in ("--set", o)]


def last_step(train_dir: Path) -> int:
    """The last step a training run logged (0 before it starts): recipes resume from it."""
    log = train_dir / "metrics.jsonl"
    if not log.exists():
        return 0
    steps = [json.loads(line).get("step", 0) for line in log.read_text().splitlines() if line.strip()]
    return max(steps, default=0)


def package_weights(train_dir: Path, out: Path) -> None:
    """bf16 weights, sharded, plus tokenizer and processor files of the run."""
    hf = train_dir / "hf"
    model, config = load_pretrained(hf, dtype=jnp.float32)
    out.mkdir(parents=True, exist_ok=True)
    save_pretrained(model, config, out, dtype=jnp.bfloat16, max_shard_bytes=SHARD_BYTES)
    for f in hf.iterdir():
        if f.suffix != ".safetensors" and f.name not in ("config.json", "model.safetensors.index.json"):
            shutil.copy2(f, out / f.name)
