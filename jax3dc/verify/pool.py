"""Verified decoding of many objects at once: one object per process, the cores shared out.

A verdict is single-threaded Python and numpy for the most part (collision pieces, crossing
checks), so objects run in separate processes; C MuJoCo's rollout threads are divided among
them (``threads`` of the verdict) so the processes do not oversubscribe the cores. With backend
"mjx" the workers send their candidates' interpenetration sweeps to a device service in this
process (``jax3dc.physics.mjx_service``), which launches the requests of all workers together.

Each job names its object by a ``source`` that the caller's ``load`` turns into the meshes in the
worker (evaluation passes a shard record and rebuilds its parts there), so that meshes are never
pickled between processes.
"""

from __future__ import annotations

import contextlib
import multiprocessing as mp
import os
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from functools import partial
from typing import Any

from jax3dc.physics.launcher import device_crossings, start_shapes
from jax3dc.physics.mjx_service import serve_workers
from jax3dc.verify.select import Candidate
from jax3dc.verify.verified import ObjectParts, Verified, verify_object

Load = Callable[[Any], ObjectParts]
"""A job's ``source`` -> its object; a module-level function (or a partial of one), so it pickles."""


@dataclass(frozen=True)
class Job:
    """One object: its key, its candidates, what ``load`` rebuilds it from, and whether a failing
    winner is repaired."""

    key: str
    candidates: tuple[Candidate, ...]
    source: Any
    repair: bool = True


def verify_many(jobs: Sequence[Job], load: Load, workers: int, backend: str = "c",
                dynamics: bool = True) -> list[Verified]:
    """Each job's choice (and repair), in job order, ``workers`` objects at a time.

    Errors (an object ``load`` cannot rebuild) propagate: the caller decides whether to fall back
    to the likeliest candidate.
    """
    if workers < 1:
        raise ValueError(f"workers must be at least 1, got {workers}")
    threads = max(1, (os.cpu_count() or 1) // workers)
    run = partial(verify_one, load=load, backend=backend, dynamics=dynamics, threads=threads)
    with contextlib.ExitStack() as stack:
        if workers > 1 and len(jobs) > 1:  # spawned: a forked child would inherit the parent's threads and locks
            context = mp.get_context("spawn")
            service = (serve_workers(stack, context, workers, start_shapes=start_shapes(), crossings=device_crossings())[1]
                       if backend == "mjx" else {})
            pool = stack.enter_context(ProcessPoolExecutor(workers, mp_context=context, **service))
            return list(pool.map(run, jobs))
        return [run(job) for job in jobs]


def verify_one(job: Job, load: Load, backend: str = "c", dynamics: bool = True, threads: int | None = None) -> Verified:
    """One job in this process."""
    return verify_object(job.key, job.candidates, load(job.source), job.repair, backend, dynamics, threads)
