"""Verified decoding of many objects at once: one object per process, the cores shared out.

A verdict is single-threaded Python and numpy for the most part (collision pieces, crossing
checks), so objects run in separate processes; C MuJoCo's rollout threads are divided among
them (``threads`` of ``check_object_with_curves``) so the processes do not oversubscribe the cores.
With backend "mjx" the workers send their candidates' interpenetration sweeps to a device service
in this process (``jax3dc.physics.mjx_service``), which launches the requests of all workers together.
"""

from __future__ import annotations

import contextlib
import multiprocessing as mp
import os
import threading
from collections.abc import Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path

from data_pipeline.record import Record
from data_pipeline.record_parts import record_parts
from jax3dc.physics.candidate_verdicts import start_shapes
from jax3dc.physics.mjx_service import DeviceService, init_worker
from jax3dc.verify.repair import Repaired, repair
from jax3dc.verify.select import Candidate, Choice, choose
from jax3dc.verify.verdicts import Physics, VerdictCache
from jax3dc.structure import boxes_from_dict


@dataclass(frozen=True)
class Job:
    """One object: its record (for the parts, boxes, scale and mounting) and its candidates.

    ``sources``: object id -> source folder, for imported records (see ``record_parts``);
    ``repair``: also repair the winner when its verdict fails.
    """

    record: Record
    candidates: tuple[Candidate, ...]
    sources: Mapping[str, Path] = field(default_factory=dict)
    repair: bool = True


@dataclass(frozen=True)
class Verified:
    key: str
    choice: Choice
    repaired: Repaired | None  # None: not asked, or the winner does not parse or already passes


def verify_many(jobs: Sequence[Job], workers: int, backend: str = "c", dynamics: bool = True) -> list[Verified]:
    """Each job's choice (and repair), in job order, ``workers`` objects at a time.

    Errors (a record whose parts cannot be rebuilt) propagate: the caller decides whether to fall
    back to the likeliest candidate.
    """
    if workers < 1:
        raise ValueError(f"workers must be at least 1, got {workers}")
    threads = max(1, (os.cpu_count() or 1) // workers)
    run = partial(verify_one, backend=backend, dynamics=dynamics, threads=threads)
    # the images stay behind: workers need only the text fields
    light = [replace(job, record=replace(job.record, image_png=b"", seg_png=b"")) for job in jobs]
    with contextlib.ExitStack() as stack:
        if workers > 1 and len(light) > 1:  # spawned: a forked child would inherit the parent's threads and locks
            context = mp.get_context("spawn")
            service = _device_service(stack, context, workers) if backend == "mjx" else {}
            pool = stack.enter_context(ProcessPoolExecutor(workers, mp_context=context, **service))
            return list(pool.map(run, light))
        return [run(job) for job in light]


def _device_service(stack: contextlib.ExitStack, context, workers: int) -> dict:
    """The MJX launches of every worker's candidates gathered in this process (``mjx_service``),
    stopped when ``stack`` closes; the pool's initializer arguments that connect the workers to it."""
    device = DeviceService(context, workers, start_shapes=start_shapes())
    stop = threading.Event()
    server = threading.Thread(target=device.serve, args=(stop,), daemon=True)
    server.start()
    stack.callback(server.join)
    stack.callback(stop.set)
    return {"initializer": init_worker, "initargs": device.worker_args()}


def verify_one(job: Job, backend: str = "c", dynamics: bool = True, threads: int | None = None) -> Verified:
    """One job in this process."""
    parts, scale, mounted = record_parts(job.record, job.sources)
    boxes = boxes_from_dict(job.record.meta["boxes"])
    check = VerdictCache(Physics(parts, scale, mounted, backend, dynamics, threads))  # the repair reuses the choice's verdicts
    choice = choose(job.candidates, boxes.keys(), parts, scale, mounted, boxes, check=check)
    fixed = None
    if job.repair and choice.structure is not None and not choice.rows[choice.index].ok:
        fixed = repair(choice.structure, parts, scale, mounted, boxes, check=check)
    return Verified(job.record.key, choice, fixed)
