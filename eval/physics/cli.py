"""``jax3dc physics``: would a predicted articulated object work in a simulator, and why not.

``physics check STRUCTURE.json --parts DIR`` checks one object and prints its JSON verdict
(``physics check object.xml``: the MJCF file ``jax3dc export --format mjcf`` wrote, as it stands);
``physics sweep SHARDS`` checks every object of a data build and writes a report folder.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import json
import math
import multiprocessing as mp
import os
import threading
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from jax3dc.cli import command_group, positive_int
from jax3dc.compilation import DEFAULT_DIR as DEFAULT_CACHE_DIR
from jax3dc.errors import InputFileError, Jax3dcError
from jax3dc.geometry.mesh_size import MAX_PART_FACES, PHYSICS_MAX_FACES

VERDICT_HELP = (
    'The verdict is JSON: {"ok": bool, "joints": {"<part id>": {"ok": bool, "reasons": [...], "warnings": [...]}}, '
    '"checks": {"rest": [...], "combinations": [...], "gravity": [...]}, "findings": [...]}. Reasons (failures) '
    'and warnings are short strings such as "penetrates part 3 at q=1.200", "detached from parent at q=0.400", '
    '"pivot detached", "limit unreachable: hi (stops at q=0.9)", "disagrees with part 5 (symmetric): ..." (its '
    'mirror twin moves otherwise), "unstable under gravity: ..."; a limit a little past where the joint stops is '
    'the warning "limit past contact: hi (stops at q=2.772)". "findings" holds the same as data: check, severity, '
    'joints, parts, depth (nu), state ([[joint, value], ...]), reachable. Only failures fail a joint or the object. '
    "Joint values are radians (hinge) or normalised units (slide). Tolerances: eval/physics/tolerances.py."
)


def register(subparsers: argparse._SubParsersAction) -> None:
    sub = command_group(subparsers, "physics", help="physics plausibility checks of an articulated structure",
                        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    check = sub.add_parser(
        "check", help="check one structure with its part meshes, or an exported MJCF file",
        description="Build a simulation model of STRUCTURE.json with the part meshes in --parts (or take the one of "
                    "an MJCF file written by jax3dc export --format mjcf or predict, object.xml, with its meshes/), "
                    "run the interpenetration, attachment, reachability and gravity checks, print the verdict and "
                    "write it to --out. An exported file gives the verdict its structure gives, unless it was edited: "
                    "its bodies, joints and collision pieces are what is checked. Exit code 0 whatever the verdict; "
                    "1 on unusable input. " + VERDICT_HELP)
    check.add_argument("structure", type=Path, help="structure O as JSON (SPEC §2), or an exported MJCF file (.xml)")
    check.add_argument("--parts", type=Path, help="folder of part meshes <id>.obj|.stl|.ply|.glb (nu); required "
                                                  "with a structure, not with an MJCF file (it has meshes/)")
    check.add_argument("--max-part-faces", type=positive_int, default=MAX_PART_FACES, metavar="N",
                       help="refuse a part mesh file of more triangles (default: %(default)s)")
    check.add_argument("--max-faces", type=positive_int, default=PHYSICS_MAX_FACES, metavar="N",
                       help="refuse an object of more triangles in all: the check's time and memory grow with "
                            "them (default: %(default)s)")
    check.add_argument("--scale", type=float, default=None,
                       help="metres per nu (default: 'scale' of a meta.json beside the structure, else 1; an MJCF "
                            "file carries its own)")
    check.add_argument("--out", type=Path, default=None, help="also write the verdict JSON here")
    check.add_argument("--backend", choices=("c", "mjx"), default="c",
                       help="kinematic checks through C MuJoCo (default; fast on CPU) or MJX (for a GPU)")
    check.add_argument("--mounted", action="store_true",
                       help="the object is fixed in place in use (a faucet, a toilet, a door frame): the gravity "
                            "test holds its root instead of standing it free on a floor (an MJCF file exported "
                            "as mounted is checked so without it)")
    check.set_defaults(func=run_check)
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


def _scale_beside(structure_path: Path) -> float:
    meta = structure_path.with_name("meta.json")
    if not meta.exists():
        return 1.0
    try:
        scale = json.loads(meta.read_text(encoding="utf-8")).get("scale", 1.0)
    except (OSError, ValueError) as e:
        raise InputFileError(meta, f"cannot read the scale: {e}") from None
    return float(scale)


def _checked_scale(scale: float, where: Path) -> float:
    if isinstance(scale, bool) or not (math.isfinite(scale) and scale > 0):
        raise InputFileError(where, f"scale must be a positive number of metres per nu, got {scale!r}")
    return scale


def run_check(args: argparse.Namespace) -> int:
    from eval.physics.exported import is_mjcf, load_exported
    from eval.physics.verdict import check_object
    from jax3dc.geometry.mesh_size import check_object_faces
    from jax3dc.geometry.parts import load_parts
    from jax3dc.structure import parse_structure

    if is_mjcf(args.structure):
        if args.parts is not None or args.scale is not None:
            raise Jax3dcError("--parts and --scale go with a structure: an MJCF file has its meshes and scale")
        exported = load_exported(args.structure, args.max_part_faces)
        check_object_faces(exported.parts, args.max_faces, "the physics check")
        verdict = check_object(exported.structure, exported.parts, exported.scale, backend=args.backend,
                               mounted=args.mounted or exported.mounted, pieces=exported.pieces)
    else:
        if args.parts is None:
            raise Jax3dcError("--parts DIR is required with a structure (the part meshes it articulates)")
        try:
            text = args.structure.read_text(encoding="utf-8")
        except OSError as e:
            raise InputFileError(args.structure, f"cannot read: {e.strerror or e}") from None
        parts = load_parts(args.parts, args.max_part_faces)
        check_object_faces(parts, args.max_faces, "the physics check")
        structure = parse_structure(text, part_ids=parts.keys())
        scale = _checked_scale(args.scale if args.scale is not None else _scale_beside(args.structure), args.structure)
        verdict = check_object(structure, parts, scale, backend=args.backend, mounted=args.mounted)
    text = json.dumps(verdict, indent=1)
    print(text)
    if args.out:
        try:
            args.out.parent.mkdir(parents=True, exist_ok=True)
            args.out.write_text(text + "\n", encoding="utf-8")
        except OSError as e:
            raise InputFileError(args.out, f"cannot write the verdict: {e.strerror or e}") from None
    return 0


def record_scale(meta: dict[str, Any]) -> float:
    """Metres per nu of a record: ``scale_m_per_nu`` as the data build writes it (an older or
    hand-made meta may say ``scale``), else 1."""
    return float(meta.get("scale_m_per_nu", meta.get("scale", 1.0)))


def run_sweep(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from data_pipeline.factories import FACTORIES
    from data_pipeline.shards import read_dataset
    from eval.physics.report import write_report

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
            from eval.physics.mjx_service import DeviceService, init_worker
            from jax3dc.compilation import use_compile_cache

            use_compile_cache(args.compile_cache)
            device = DeviceService(context, args.workers)
            stop = threading.Event()
            server = threading.Thread(target=device.serve, args=(stop,), daemon=True)
            server.start()
            stack.callback(server.join)
            stack.callback(stop.set)
            pool = stack.enter_context(ProcessPoolExecutor(args.workers, mp_context=context, initializer=init_worker,
                                                           initargs=device.worker_args()))
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
    import numpy as np

    from eval.physics.report import plot_penetration
    from eval.physics.verdict import check_object_with_curves
    from jax3dc.errors import Jax3dcError
    from jax3dc.export.simulation import collision_pieces
    from jax3dc.program import run_program
    from jax3dc.structure import parse_structure

    if not job.program:
        return {"object": job.object_id, "why": "no part program in the record"}
    try:
        parts = run_program(job.program).parts
        structure = parse_structure(job.target, part_ids=parts.keys())
    except Jax3dcError as error:
        return {"object": job.object_id, "why": f"{type(error).__name__}: {error}"}
    extra = {}
    if job.backend == "mjx":
        from eval.physics.cpu_backend import final_qpos
        from eval.physics.mjx_service import client

        extra = {"backend": "mjx", "penetration": client(), "rollout": functools.partial(final_qpos, threads=job.threads)}
    start = time.perf_counter()
    with np.errstate(all="ignore"):
        pieces = collision_pieces(structure, parts, job.scale)
    verdict, curves = check_object_with_curves(structure, parts, job.scale, mounted=job.mounted, threads=job.threads,
                                               pieces=pieces, **extra)
    seconds = time.perf_counter() - start
    plot = None
    if curves:
        plot = f"plots/{job.object_id}.png"
        plot_penetration(job.object_id, curves, job.out / plot)
    return {"object": job.object_id, "category": job.category, "verdict": verdict, "plot": plot,
            "cost": {"seconds": round(seconds, 3), "parts": len(parts), "joints": len(verdict["joints"]),
                     "pieces": sum(len(p) for p in pieces.values())}}
