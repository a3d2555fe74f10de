"""Loader throughput at the 4B training layout: tokens/s and batches/s with 1, 2 and 8 workers.

Run: python3 -m bench.loader [--data DIR] [--workers 1 2 8] [--batches 12]
Without --data, a dataset of factory objects at 448x448 is built first into a temporary folder.
Layout: Qwen3-VL-4B (patch 16, merge 2; 448 px images -> 196 tokens each, I and S per example),
the Qwen3 tokenizer, rows of 8192 tokens, 16 rows per batch (the effective batch), packing.
Prints real tokens/s (non-padding), row tokens/s (what the trainer computes over) and batches/s
against the trainer's figure given by --trainer-tokens-per-s (default 15,000: the 4B step on
one H100); the issue's bar is >= 20,000 real tokens/s.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

from data_pipeline.build import BuildConfig, factory_sources, run_build
from data_pipeline.loader import LoaderConfig, ShardLoader
from jax3dc.model.config import Qwen3VLConfig
from jax3dc.processing.processor import ImageProcessorConfig
from jax3dc.processing.tokenizer import load_tokenizer


def build_data(folder: Path, objects: int, workers: int) -> None:
    run_build(folder, factory_sources(objects, 0), BuildConfig(views=2, seed=0, size=448, objects_per_shard=4),
              workers, progress=False)


def measure(data: str, workers: int, batches: int, seq_len: int, rows: int, pack: int, pixel_dtype: str) -> dict:
    cfg = LoaderConfig(sources=(data,), seq_len=seq_len, rows=rows, pack=pack, image_size=448, workers=workers, pixel_dtype=pixel_dtype,
                       worker_buffer=2)
    loader = ShardLoader.create(cfg, Qwen3VLConfig.qwen3_vl_4b(), load_tokenizer(), ImageProcessorConfig.qwen3_vl())
    start = time.perf_counter()
    next(loader)  # worker start-up and first batch
    first = time.perf_counter() - start
    real = 0
    start = time.perf_counter()
    for _ in range(batches):
        batch = next(loader)
        real += int(batch["attention_mask"].sum())
    seconds = time.perf_counter() - start
    return {"workers": workers, "first_batch_s": round(first, 2), "batches_per_s": batches / seconds,
            "real_tokens_per_s": real / seconds, "row_tokens_per_s": batches * rows * seq_len / seconds,
            "fill": real / (batches * rows * seq_len), "skipped": dict(loader.skipped)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", help="dataset folder (default: build one)")
    parser.add_argument("--objects", type=int, default=400, help="objects to build without --data")
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2, 8])
    parser.add_argument("--batches", type=int, default=12)
    parser.add_argument("--seq-len", type=int, default=8192)
    parser.add_argument("--rows", type=int, default=16)
    parser.add_argument("--pack", type=int, default=6)
    parser.add_argument("--pixel-dtype", default="bfloat16", help="what the 4B bf16 trainer takes")
    parser.add_argument("--trainer-tokens-per-s", type=float, default=15000.0)
    parser.add_argument("--out", help="also write the figures as JSON here")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        data = args.data
        if data is None:
            data = os.path.join(tmp, "data")
            start = time.perf_counter()
            build_data(Path(data), args.objects, len(os.sched_getaffinity(0)))
            print(f"built {args.objects} objects x 2 views at 448 px in {time.perf_counter() - start:.0f} s")
        results = []
        for workers in args.workers:
            r = measure(data, workers, args.batches, args.seq_len, args.rows, args.pack, args.pixel_dtype)
            results.append(r)
            print(f"workers={workers}: {r['real_tokens_per_s']:,.0f} real tokens/s "
                  f"({r['real_tokens_per_s'] / args.trainer_tokens_per_s:.2f}x the trainer's "
                  f"{args.trainer_tokens_per_s:,.0f}), {r['row_tokens_per_s']:,.0f} row tokens/s, "
                  f"{r['batches_per_s']:.3f} batches/s, rows {100 * r['fill']:.0f}% filled, "
                  f"first batch {r['first_batch_s']} s, skipped {r['skipped']}", flush=True)
    print(f"machine: {len(os.sched_getaffinity(0))} CPUs usable; layout: {args.rows} rows x {args.seq_len} tokens, pack {args.pack}, "
          f"pixels {args.pixel_dtype}")
    if args.out:
        Path(args.out).write_text(json.dumps({"cpus": os.cpu_count(), "results": results}, indent=1))


if __name__ == "__main__":
    main()
