"""``jax3dc physics sweep SHARDS``: checks every object of a data build and writes a report folder.

The sweep reads data builds (``data_pipeline``), so it lives beside evaluation and adds itself to the
core's ``jax3dc physics`` group (``jax3dc.physics.cli``).
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import json
import multiprocessing as mp
import os
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from data_pipeline.shards import read_dataset
from eval.physics_report import plot_penetration, write_report
from jax3dc.cli_args import command_group, positive_int
from jax3dc.compilation import DEFAULT_DIR as DEFAULT_CACHE_DIR, use_compile_cache
from jax3dc.errors import Jax3dcError
from jax3dc.export.simulation import collision_pieces
from jax3dc.physics.cli import VERDICT_HELP
from jax3dc.physics.cpu_backend import final_qpos
from jax3dc.physics.mjx_service import client, serve_workers
from jax3dc.physics.verdict import verdict_with_curves
from jax3dc.program import run_program
from jax3dc.structure import parse_structure


def register(subparsers: argparse._SubParsersAction) -> None:
    sub = command_group(subparsers, "physics")
    sweep = sub.add_parser(
        "sweep", help="check every object of a data build and write a report",
        description="Check the first rest-pose record of every object in a data build (ArrayRecord shards: "
                    "target structure + part program) and write OUT/verdicts.jsonl, OUT/summary.json, "
                    "OUT/index.md and OUT/plots/<object>.png (deepest penetration against each joint's value). "
                    "Records without a part program (imports), or whose program or target structure fails, are listed "
                    "as skipped with the reason, and the sweep goes on. Objects of a factory "
                    "category mounted in use (faucet, toilet, door, window) are checked as --mounted. " + VERDICT_HELP)
    sweep.add_argument("shards", type=Path, help="data build folder (manifest.json + *.array_record)")
    sweep.add_argument("--out", type=Path, default=Path("physics_report"), help="report folder (default: %(default)s)")
    sweep.add_argument("--limit", type=int, default=None, help="check at most this many objects")
    sweep.add_argument("--workers", type=positive_int, default=1,
                       help="objects checked at once in separate processes (default %(default)s; the cores are "
                            "shared among them for the rollouts)")
    sweep.add_argument("--backend", choices=("c", "mjx"), default="c",
                       help="interpenetration sweeps through C MuJoCo in each worker (default) or batched on the "
                            "accelerator through MJX: the workers prepare objects and send their joint states to one "
                            "device launch per batch of objects; proximity and rollouts stay in C MuJoCo (the "
                            "rollouts compile per structure in MJX). The verdicts file is the same format")
    sweep.add_argument("--compile-cache", default=DEFAULT_CACHE_DIR, metavar="DIR",
                       help="with --backend mjx: keep the compiled checks here for the next sweep (default: "
                            "%(default)s; '' turns it off; JAX_COMPILATION_CACHE_DIR wins)")
    sweep.set_defaults(func=run_sweep)


def record_scale(meta: dict[str, Any]) -> float:
    """Metres per nu of a record: ``scale_m_per_nu`` as the data build writes it (an older or
    hand-made meta may say ``scale``), else 1."""
    return float(meta.get("scale_m_per_nu", meta.get("scale", 1.0)))


def run_sweep(args: argparse.Namespace) -> int:
    from jax3dc.factories import FACTORIES  # lazy: 28 ms after `jax3dc --help`, which imports this module

    chosen: dict[str, Any] = {}
    for record in read_dataset(args.shards):
        object_id = record.meta.get("object_id", record.key)
        if object_id in chosen or record.meta.get("moved_joint") is not None or record.meta.get("augmentation"):
            continue
        chosen[object_id] = record
        if args.limit and len(chosen) >= args.limit:
            break
    threads = max(1, (os.cpu_count() or 1) // args.workers)
    jobs = []
    for object_id, record in chosen.items():
        category = record.meta.get("category")
        mounted = category in FACTORIES and FACTORIES[category].mounted
        jobs.append(_SweepJob(object_id, category, record.program, record.target, record_scale(record.meta),
                              mounted, threads, args.out, args.backend))
    device = None
    with contextlib.ExitStack() as stack:
        context = mp.get_context("spawn")  # spawned: a forked child would inherit the loader's threads and locks
        if args.backend == "mjx":
            use_compile_cache(args.compile_cache)
            device, service = serve_workers(stack, context, args.workers)
            pool = stack.enter_context(ProcessPoolExecutor(args.workers, mp_context=context, **service))
            done = pool.map(_check_job, jobs)
        elif args.workers > 1:
            pool = stack.enter_context(ProcessPoolExecutor(args.workers, mp_context=context))
            done = pool.map(_check_job, jobs)
        else:
            done = map(_check_job, jobs)
        outcomes = list(tqdm(done, total=len(jobs), desc="physics sweep", unit="object"))
    results = [o for o in outcomes if "verdict" in o]
    skipped = [o for o in outcomes if "why" in o]
    summary = write_report(results, skipped, args.out, device.stats.to_json() if device else None)
    print(json.dumps(summary, indent=1))
    return 0


@dataclass(frozen=True)
class _SweepJob:
    """What a worker needs to check one object of a sweep (not the record: its images stay behind)."""

    object_id: str
    category: str | None
    program: str | None
    target: str
    scale: float
    mounted: bool
    threads: int
    out: Path  # the report folder: the object's plot goes to out/plots/<object>.png
    backend: str = "c"  # "mjx": the interpenetration sweep goes to the main process's device service


def _check_job(job: _SweepJob) -> dict[str, Any]:
    """One object's verdict and its plot of penetration against joint values, or why it was skipped:
    a record whose program or structure is unusable is reported with the error, and the sweep goes on."""
    if not job.program:
        return {"object": job.object_id, "why": "no part program in the record"}
    try:
        parts = run_program(job.program).parts
        structure = parse_structure(job.target, part_ids=parts.keys())
    except Jax3dcError as error:
        return {"object": job.object_id, "why": f"{type(error).__name__}: {error}"}
    extra = {}
    if job.backend == "mjx":
        extra = {"backend": "mjx", "penetration": client(), "rollout": functools.partial(final_qpos, threads=job.threads)}
    start = time.perf_counter()
    with np.errstate(all="ignore"):
        pieces = collision_pieces(structure, parts, job.scale)
    verdict, curves = verdict_with_curves(structure, parts, job.scale, mounted=job.mounted, threads=job.threads,
                                          pieces=pieces, **extra)
    seconds = time.perf_counter() - start
    plot = None
    if curves:
        plot = f"plots/{job.object_id}.png"
        plot_penetration(job.object_id, curves, job.out / plot)
    return {"object": job.object_id, "category": job.category, "verdict": verdict, "plot": plot,
            "cost": {"seconds": round(seconds, 3), "parts": len(parts), "joints": len(verdict.joint_parts),
                     "pieces": sum(len(p) for p in pieces.values())}}
