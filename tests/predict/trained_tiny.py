"""Tiny models trained from scratch on one procedural factory, for the end-to-end predict test.

Every object of one factory variant shares one part layout (same part ids, same parent map,
same joint count; only sizes and positions vary with the seed), so a `tiny` model trained for a
few hundred CPU steps learns to write that layout as valid JSON (and, for the code task, a
valid part program). Everything goes through the project's own commands: `jax3dc data build`'s
planner/renderer (data_pipeline.build.run_build, with one category instead of the cycle),
`jax3dc data tokenizer` and `jax3dc train`.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from data_pipeline.build import BuildConfig, SourceSpec, run_build
from data_pipeline.samples import split_of
from jax3dc.cli import main
from jax3dc.factories import object_id

ROOT = Path(__file__).resolve().parents[2]
TRAIN_TIMEOUT_S = 1200
CATEGORY = "stapler"  # 3 parts and 1 hinge for every seed (checked over seeds 0..39 in the test)
RENDER_SIZE = 64
TRAIN_IMAGE = 32  # the tiny preset's 4-pixel patches: 64 patches, 16 merged tokens per image


@dataclass(frozen=True)
class TrainedRun:
    model: Path
    steps: int
    seconds: float
    first_loss: float
    last_loss: float


def sources(train_objects: int, seed_base: int = 7_000) -> tuple[list[SourceSpec], SourceSpec, SourceSpec]:
    """``train_objects`` train-split objects of CATEGORY, then the first val-split object (`jax3dc
    train` validates on the last step) and the first test-split object (the held-out input)."""
    train: list[SourceSpec] = []
    found: dict[str, SourceSpec] = {}
    seed = seed_base
    while len(train) < train_objects or len(found) < 2:
        spec = SourceSpec("factory", object_id(CATEGORY, seed), category=CATEGORY, seed=seed)
        split = split_of(spec.object_id)
        if split == "train" and len(train) < train_objects:
            train.append(spec)
        elif split != "train":
            found.setdefault(split, spec)
        seed += 1
    return train, found["val"], found["test"]


def build_data(out: Path, train_objects: int) -> SourceSpec:
    """Renders the train, val and held-out test objects (1 view each); returns the test object."""
    train, val, held_out = sources(train_objects)
    run_build(out, [*train, val, held_out], BuildConfig(views=1, seed=0, size=RENDER_SIZE, objects_per_shard=64),
              workers=1, progress=False)
    return held_out


def train_tokenizer(data: Path, out: Path, vocab_size: int = 512) -> Path:
    assert main(["data", "tokenizer", "--data", str(data), "--vocab-size", str(vocab_size), "--out", str(out),
                 "--quiet"]) == 0
    return out


def train_model(data: Path, tokenizer: Path, out: Path, task: str, steps: int, lr: float = 3e-3,
                seq_len: int = 512, batch_size: int = 4, end_lr_ratio: float = 0.1) -> TrainedRun:
    """`jax3dc train` of the `tiny` preset from scratch, in its own process as a user runs it: the
    one native crash of a full suite run came while this trained inside the test process, which
    ~1,700 tests had filled with their threads, GL contexts and compiled programs. The HF export
    lands in ``out/hf``."""
    settings = [f"data={data}", f"tokenizer={tokenizer}", f"task={task}", f"image_size={TRAIN_IMAGE}",
                f"seq_len={seq_len}", f"batch_size={batch_size}", "grad_accum=1", "pack=1", f"lr={lr}",
                "warmup_steps=5", f"end_lr_ratio={end_lr_ratio}", "freeze=", "compute_dtype=float32", "remat=none",
                "log_every=10", f"eval_every={steps + 1000}", "eval_batches=1", f"save_every={steps + 1000}"]
    started = time.perf_counter()
    argv = [sys.executable, "-m", "jax3dc.cli", "train", "--init", "tiny", "--output-dir", str(out), "--steps", str(steps)]
    for setting in settings:
        argv += ["--set", setting]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, (str(ROOT), os.environ.get("PYTHONPATH"))))}
    proc = subprocess.run(argv, cwd=ROOT, env=env, capture_output=True, text=True, timeout=TRAIN_TIMEOUT_S)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-4000:]
    seconds = time.perf_counter() - started
    rows = [json.loads(line) for line in (out / "metrics.jsonl").read_text().splitlines()]
    logged = [r for r in rows if r.get("kind") == "train"]
    return TrainedRun(out / "hf", logged[-1]["step"], seconds, logged[0]["loss"], logged[-1]["loss"])
