"""Verdicts of many structures over the same parts (the K candidates of one object, a repair's
alternatives) with their interpenetration sweeps in one compiled MJX launch.

The structures share the part meshes, so their collision pieces come from one decomposition per
part and frame (``convex_pieces``' caches: a candidate that moves no part's frame decomposes
nothing). Each structure's kinematic model, check states and C proximity are built on the CPU as
``verdict.verdict_with_curves`` builds them; the penetration depths of every structure's states
then come from one ``mjx_batch`` launch over the same models read without their detachment margin
(no second model is built), sent to a ``launcher.Launcher``: by default this process's
``LocalLauncher``, which pads to at least ``launcher.start_shapes()`` and to the largest shapes it
has launched, so a run over many objects compiles only when a larger object comes; in a worker
process of a device service (``mjx_service``, as ``physics sweep --backend mjx`` runs it) the
service's client, which launches the requests of all its workers together.
On an accelerator the board-crossing queries of every structure (``verdict.crossing_plan_of``, the
largest CPU share of a C verdict) go with them, to one ``crossing_batch`` launch; on a CPU numpy
answers them faster, in the checks. The checks that read no distances (``DISTANCE_FREE_CHECKS``:
relations, gravity) run in the worker while the service's device measures them.
The rollouts of the dynamic checks run in C, as ``physics sweep --backend mjx`` runs them: each
structure's reachability model has its own contact pairs, which MJX keeps static, so they cannot
share a compiled launch; with the models they build they are about a third of a C verdict, and the
CPU side they leave is what bounds this path's speed against C (note j of the hand-written
benchmark page, ``git show e09c126:docs/BENCHMARKS.md``).

With the same models, states, proximity and rollouts, the verdicts differ from the C path's only
where the two depths of a pair fall on two sides of a tolerance. MJX's is the exact separating-axis
depth; C's convex solver now and then reads a deep pair deeper: 2 of 63 sampled candidates of 12
factory objects (``bench/candidates_mjx.py --records 12``) differed so, e.g. a drawer chest's
drawer at one state of its (perturbed) sweep, 0.033 nu in C against 0.018 nu at that state in MJX and
at its neighbours in both (tolerance 0.025), which changes a reason or a flagged joint of a
candidate that fails anyway; the winners and repairs were the same.
``tests/physics/test_physics_candidate_verdicts.py`` checks winners, verdict lines and repairs.
"""

from __future__ import annotations

import dataclasses
import functools
import time
import warnings
from collections.abc import Sequence

import trimesh

from jax3dc.physics import cpu_backend
from jax3dc.physics.findings import Verdict
from jax3dc.physics.launcher import Launcher, process_launcher
from jax3dc.physics.verdict import (CHECKS, DISTANCE_FREE_CHECKS, CheckRun, KinematicInputs, check_names, crossing_plan_of,
                                    kinematic_inputs, run_checks)
from jax3dc.structure.schema import Structure


def candidate_verdicts(structures: Sequence[Structure], parts: dict[int, trimesh.Trimesh], scale: float, mounted: bool,
                       dynamics: bool = True, threads: int | None = None,
                       timings: dict[str, float] | None = None, crossings: bool | None = None,
                       launcher: Launcher | None = None) -> list[Verdict]:
    """One verdict per structure (in order) over ``parts`` (nu, ``scale`` metres per nu), the
    interpenetration of all of them measured in one MJX launch. ``threads``: C rollout threads;
    ``timings`` gathers seconds per step: the CPU's "kinematic inputs", "penetration arrays",
    "crossing plans" and "checks" (rollouts included), and the launches' phases
    (``mjx_batch.batch_pair_distances``, "crossings"; a service times its own); ``crossings``: answer
    the crossing queries in the launch (default: as ``launcher`` says: a service's worker as its
    service, else on an accelerator); ``launcher``: where the launches go (default:
    ``launcher.process_launcher()``, which pads to the largest shapes this process has launched)."""
    if not structures:
        return []
    names = check_names(None, dynamics)
    clock = _Clock(timings)
    inputs = [kinematic_inputs(s, parts, scale) for s in structures]
    clock.lap("kinematic inputs")
    arrays = _penetration_arrays(inputs)
    clock.lap("penetration arrays")
    launcher = launcher or process_launcher()
    if crossings is None:
        crossings = launcher.crossings
    plans = None
    if crossings and "joints" in names:
        plans = [crossing_plan_of(s, parts, i.sim, i.states) for s, i in zip(structures, inputs)]
        clock.lap("crossing plans")
    replies = launcher.submit(arrays, [i.states.qpos for i in inputs], plans, timings)
    clock.lap()
    rollout = functools.partial(cpu_backend.final_qpos, threads=threads)
    runs = [CheckRun(s, parts, i.sim, i.states, None, i.proximity, rollout, mounted) for s, i in zip(structures, inputs)]
    # the checks that need no distances run while a service's device measures them
    early = [{n: CHECKS[n](run) for n in names if n in DISTANCE_FREE_CHECKS} for run in runs]
    clock.lap("checks")
    distances, first = replies()
    clock.lap()
    crossed = [None] * len(structures) if plans is None else [p.resolve(f) for p, f in zip(plans, first)]
    verdicts = [run_checks(dataclasses.replace(run, distances=d, given_crossings=c), names, done)
                for run, d, c, done in zip(runs, distances, crossed, early)]
    clock.lap("checks")
    return verdicts


def _penetration_arrays(inputs: list[KinematicInputs]) -> list:
    """What the launch reads of each structure: its kinematic model as the same model without the
    detachment margin (``mjx_batch.object_arrays``; no second model is built)."""
    from jax3dc.physics.mjx_batch import object_arrays  # lazy: MJX and jax (0.46 s), for this path only

    with warnings.catch_warnings():  # about MJX's own convex data of large faces, which this path does not use
        warnings.simplefilter("ignore", UserWarning)
        return [object_arrays(i.sim.model, ignore_margin=True) for i in inputs]


class _Clock:
    """Seconds per step into ``timings`` (when given)."""

    def __init__(self, timings: dict[str, float] | None):
        self.timings, self.last = timings, time.perf_counter()

    def lap(self, name: str | None = None) -> None:
        now = time.perf_counter()
        if name is not None and self.timings is not None:
            self.timings[name] = self.timings.get(name, 0.0) + now - self.last
        self.last = now
