"""Best-of-K + repair verification (issue 50): seconds per object with backend "mjx" (one device,
the candidates' interpenetration sweeps of every worker's objects launched together by a device
service, ``jax3dc.physics.mjx_service``) beside C MuJoCo, each with ``--workers`` processes for the
CPU side of the checks, in the same call; the ratio and whether the winners agree.

Objects: factory objects (the categories in turn, seeds 0, 1, ...), and their candidates sampled by
perturbing the reference's joints: flipped axis, moved pivot, wrong type
(``eval/verdict_accuracy/candidates.py``); a winner that fails is repaired (pivots moved, the
default kinds). Objects and candidates are made before timing. The collision pieces and crossing
boards of every candidate are found into the disk cache first (untimed, printed), as a repeated run
finds them, so the timed runs measure verification; the repairs' alternatives decompose in
whichever run meets them first, and MJX runs first, so that cost falls on it. ``--phases`` adds where a candidate set's time goes, measured in
this process over a few objects (MJX: CPU steps and launch phases).

python3 bench/candidates_mjx.py --records 200 --workers 16          (a GPU host: MJX on one GPU, C on 16 cores)
python3 bench/candidates_mjx.py --records 6 --workers 2 --phases 2  (a CPU: MJX on the CPU backend)
"""

from __future__ import annotations

import argparse
import contextlib
import json
import multiprocessing as mp
import os
import time
import warnings
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from functools import partial
from pathlib import Path

from eval.verdict_accuracy.candidates import sampled_candidates
from eval.verdict_accuracy.ground_truth import factory_objects
from jax3dc.export.simulation import collision_pieces
from jax3dc.factories import FACTORIES
from jax3dc.geometry.parts import part_boxes
from jax3dc.physics.candidate_verdicts import candidate_verdicts
from jax3dc.physics.launcher import device_crossings, start_shapes
from jax3dc.physics.mjx_service import serve_workers
from jax3dc.physics.verdict import crossing_plan_of, kinematic_inputs
from jax3dc.structure import to_json
from jax3dc.verify.select import parse_candidate
from jax3dc.verify.verified import ObjectParts, verify_object


@dataclass(frozen=True)
class _Job:
    name: str
    obj: object  # eval.verdict_accuracy.ground_truth.GroundTruthObject
    candidates: tuple
    repair: bool


def _verify(job: _Job, backend: str, threads: int) -> dict:
    """One object's choice and repair; what the comparison needs of it."""
    warnings.filterwarnings("ignore")
    obj = job.obj
    start = time.perf_counter()
    done = verify_object(job.name, job.candidates, ObjectParts(obj.parts, obj.scale, obj.mounted, part_boxes(obj.parts)),
                         job.repair, backend, threads=threads)
    choice = done.choice
    final = done.repaired.structure if done.repaired is not None else choice.structure
    return {"name": job.name, "winner": choice.index, "final": None if final is None else to_json(final),
            "lines": [r.verdict.to_json()["joints"] if r.parsed else r.rule for r in choice.rows],
            "seconds": time.perf_counter() - start}


def _jobs(records: int, k: int, repair: bool) -> list[_Job]:
    categories = sorted(FACTORIES)
    jobs = []
    for n in range(records):
        obj = next(factory_objects([categories[n % len(categories)]], [n // len(categories)]))
        jobs.append(_Job(obj.name, obj, tuple(sampled_candidates(obj.structure, obj.parts, k, seed=n)), repair))
    return jobs


def _warm_pieces(job: _Job) -> int:
    """Decompose every candidate's collision pieces, and find its crossing boards, into the disk
    cache; how many candidates."""
    warnings.filterwarnings("ignore")
    boxes = part_boxes(job.obj.parts)
    for candidate in job.candidates:
        with contextlib.suppress(Exception):  # an unparsable candidate has no pieces
            structure = parse_candidate(candidate.text, boxes.keys(), boxes)
            collision_pieces(structure, job.obj.parts, job.obj.scale)
            inputs = kinematic_inputs(structure, job.obj.parts, job.obj.scale)
            crossing_plan_of(structure, job.obj.parts, inputs.sim, inputs.states)
    return len(job.candidates)


def _run(jobs: list[_Job], backend: str, workers: int, context) -> tuple[list[dict], float, dict | None]:
    """Every job with ``workers`` processes (and, for MJX, the device service in this process):
    results in job order, wall seconds, the service's statistics."""
    threads = max(1, (os.cpu_count() or 1) // workers)
    run = partial(_verify, backend=backend, threads=threads)
    with contextlib.ExitStack() as stack:
        device = None
        kwargs = {}
        if backend == "mjx":
            device, kwargs = serve_workers(stack, context, workers, batch_objects=16, start_shapes=start_shapes(),
                                           crossings=device_crossings())
        start = time.perf_counter()
        pool = stack.enter_context(ProcessPoolExecutor(workers, mp_context=context, **kwargs))
        results = list(pool.map(run, jobs))
        wall = time.perf_counter() - start
    return results, wall, device.stats.to_json() if device else None


def _phases(jobs: list[_Job]) -> dict[str, float]:
    """Seconds per step of ``candidate_verdicts`` summed over ``jobs``' candidate sets (in this process)."""
    timings: dict[str, float] = {}
    for job in jobs:
        boxes = part_boxes(job.obj.parts)
        structures = []
        for candidate in job.candidates:
            with contextlib.suppress(Exception):
                structures.append(parse_candidate(candidate.text, boxes.keys(), boxes))
        candidate_verdicts(structures, job.obj.parts, job.obj.scale, job.obj.mounted, threads=1, timings=timings)
    return {k: round(v, 2) for k, v in timings.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--records", type=int, default=200, help="objects to verify (default %(default)s)")
    parser.add_argument("--k", type=int, default=8, help="candidates per object (default %(default)s)")
    parser.add_argument("--workers", type=int, default=16, help="processes for the CPU side of each backend (default %(default)s)")
    parser.add_argument("--backend", choices=("both", "c", "mjx"), default="both", help="what to time (default %(default)s)")
    parser.add_argument("--no-repair", action="store_true", help="time the choice alone")
    parser.add_argument("--mjx-runs", type=int, default=1,
                        help="time MJX this many times in a row; the last is a repeated run's figure, its launches "
                        "compiled already (default %(default)s)")
    parser.add_argument("--phases", type=int, default=0, help="also time the steps of this many objects' candidate sets in this process")
    parser.add_argument("--out", type=Path, help="write the figures as JSON here")
    args = parser.parse_args()
    if args.records < 1 or args.workers < 1 or args.k < 1 or args.mjx_runs < 1:
        parser.error("--records, --workers, --k and --mjx-runs must be at least 1")
    warnings.filterwarnings("ignore")
    context = mp.get_context("spawn")  # spawned: a forked child would inherit JAX's threads and locks

    import jax  # lazy: each spawned worker re-imports this module, and none of them needs jax (0.34 s)

    t0 = time.perf_counter()
    jobs = _jobs(args.records, args.k, not args.no_repair)
    made = time.perf_counter() - t0
    t0 = time.perf_counter()
    with ProcessPoolExecutor(args.workers, mp_context=context) as pool:
        candidates = sum(pool.map(_warm_pieces, jobs))
    warm = time.perf_counter() - t0
    print(f"{len(jobs)} objects, {candidates} candidates: made in {made:.1f} s, pieces and boards found in {warm:.1f} s "
          f"(untimed below); device: {jax.devices()[0].device_kind} ({jax.default_backend()})", flush=True)
    report: dict = {"records": len(jobs), "candidates": candidates, "k": args.k, "workers": args.workers,
                    "repair": not args.no_repair, "device": jax.devices()[0].device_kind}
    runs = {}
    order = ["mjx"] * args.mjx_runs + ["c"] if args.backend == "both" else [args.backend] * (args.mjx_runs if args.backend == "mjx" else 1)
    for n, backend in enumerate(order):
        results, wall, stats = _run(jobs, backend, args.workers, context)
        name = backend if n == 0 or backend == "c" else "mjx_repeated"
        runs[backend] = results
        report[name] = {"wall_s": round(wall, 2), "s_per_object": round(wall / len(jobs), 3),
                        "object_s_sum": round(sum(r["seconds"] for r in results), 2), "device": stats}
        print(f"{name}: {wall:.1f} s for {len(jobs)} objects, {wall / len(jobs):.3f} s per object "
              f"({args.workers} workers)", flush=True)
    if len(runs) == 2:
        same = [m["winner"] == c["winner"] and m["final"] == c["final"] for m, c in zip(runs["mjx"], runs["c"])]
        lines = [x == y for m, c in zip(runs["mjx"], runs["c"]) for x, y in zip(m["lines"], c["lines"])]
        report["speedup_mjx_over_c"] = round(report["c"]["wall_s"] / report["mjx"]["wall_s"], 2)
        if "mjx_repeated" in report:
            report["speedup_repeated_mjx_over_c"] = round(report["c"]["wall_s"] / report["mjx_repeated"]["wall_s"], 2)
        report["same_winners_and_repairs"] = f"{sum(same)}/{len(same)}"
        report["same_candidate_verdict_lines"] = f"{sum(lines)}/{len(lines)}"
        report["differing"] = {m["name"]: [i for i, (x, y) in enumerate(zip(m["lines"], c["lines"])) if x != y]
                               for m, c in zip(runs["mjx"], runs["c"]) if m != {**c, "seconds": m["seconds"]}}
        print(f"C / MJX: {report['speedup_mjx_over_c']}x per object; same winners and repairs: "
              f"{report['same_winners_and_repairs']} objects; same verdict lines: "
              f"{report['same_candidate_verdict_lines']} candidates", flush=True)
    if args.phases:
        report["mjx_phases_s"] = _phases(jobs[:args.phases])
        print(f"MJX steps over {args.phases} objects' candidate sets: {report['mjx_phases_s']}")
    if args.out:
        args.out.write_text(json.dumps(report, indent=1))
    print(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
