"""Records per second per core of `jax3dc data build` on this CPU (448x448 by default).

Run: python3 -m bench.data_build [--objects 16] [--views 3] [--size 448] [--workers 1 2]
Builds the same objects with each worker count into a temporary directory and prints
records/s and records/s/core (the issue's target: >= 8 records/s/core at 448x448).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from data_pipeline.build import BuildConfig, factory_sources, run_build


def measure(objects: int, views: int, size: int, workers: int) -> float:
    config = BuildConfig(views=views, seed=0, size=size, objects_per_shard=2)
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        manifest = run_build(Path(tmp), factory_sources(objects, 0), config, workers, progress=False)
        seconds = time.perf_counter() - start
    records = sum(s["records"] for s in manifest["shards"].values())
    return records / seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--objects", type=int, default=16)
    parser.add_argument("--views", type=int, default=3)
    parser.add_argument("--size", type=int, default=448)
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    args = parser.parse_args()
    for workers in args.workers:
        rate = measure(args.objects, args.views, args.size, workers)
        print(f"workers={workers} size={args.size}: {rate:.2f} records/s, {rate / workers:.2f} records/s/core "
              f"({args.objects} objects x {args.views} views, spawn start-up included)")


if __name__ == "__main__":
    main()
