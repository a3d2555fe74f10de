"""`jax3dc train` keeps its compiled programs in the persistent cache its `compile_cache` names
(so a resumed run loads them instead of compiling), unless the environment names its own; its
first logged step says where the compile time went, and later rows how long saves blocked."""

import json

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
RUN = ("--init", "tiny", "--steps", "2", "--set", "data=synthetic", "--set", "seq_len=32", "--set", "image_size=16",
       "--set", "batch_size=2", "--set", "grad_accum=1", "--set", "warmup_steps=1", "--set", "eval_batches=0",
       "--set", "export_hf=false", "--set", "compute_dtype=float32", "--set", "save_every=1", "--set", "log_every=1")


def train(tmp_path: Path, cache: Path, **env_extra: str) -> list[dict]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("JAX_COMPILATION_CACHE")}
    env.update(PYTHONPATH=str(ROOT), JAX_PLATFORMS="cpu", JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS="0", **env_extra)
    proc = subprocess.run([sys.executable, "-m", "jax3dc.cli", "train", "--output-dir", str(tmp_path / "run"), *RUN,
                           "--set", f"compile_cache={cache}"], env=env, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return [json.loads(line) for line in (tmp_path / "run" / "metrics.jsonl").read_text().splitlines()]


def test_the_run_fills_its_compile_cache_and_the_environment_wins(tmp_path):
    cache, own = tmp_path / "cache", tmp_path / "own"
    first, second = train(tmp_path, cache)
    assert cache.is_dir() and any(cache.iterdir())
    assert first["compiles"] >= 1 and first["cache_hits"] == 0 and first["trace_s"] > 0 and first["lower_s"] > 0
    assert 0 < first["xla_s"] < first["compile_s"]
    assert 0 < second["save_s"] < 60  # step 1's asynchronous save, logged with the interval it held up
    again = train(tmp_path / "again", cache)[0]  # a new run on the filled cache: XLA compiles nothing
    assert again["compiles"] == 0 and again["cache_hits"] >= 1 and again["trace_s"] > 0
    assert again["xla_s"] < first["xla_s"]  # loading the executable, not compiling it
    train(tmp_path / "second", tmp_path / "unused", JAX_COMPILATION_CACHE_DIR=str(own))
    assert not (tmp_path / "unused").exists() and any(own.iterdir())
