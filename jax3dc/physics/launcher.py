"""Where a process's candidate launches go, as objects rather than process globals.

A ``Launcher`` takes the penetration arrays of many structures (``mjx_batch.ObjectArrays``) with
their joint states and, optionally, their board-crossing plans, and returns a function that waits
for the answers. Two kinds exist: a device service's client in a worker of a pool
(``mjx_service.DeviceClient``, whose service launches the requests of all workers together), and
``LocalLauncher``, which launches in this process. A ``LocalLauncher`` keeps the largest shapes it
has launched, so that every launch pads to them and a run over many objects compiles only when a
larger object comes; that state lives on the object, so a caller (or a test) can hold its own.

``process_launcher()`` is the one accessor for the launcher of this process: the client a pool's
initializer installed (``ProcessDevice.client``, set by ``mjx_service.init_worker``), else the
process's ``LocalLauncher``. Nothing here imports jax or MJX at import time: the CPU physics path
imports this module and loads neither.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

import numpy as np

from jax3dc.physics import launch_start

if TYPE_CHECKING:
    from jax3dc.physics.crossing import CrossingPlan
    from jax3dc.physics.crossing_batch import CrossingShapes
    from jax3dc.physics.mjx_batch import ObjectArrays, Shapes

Replies = tuple[list[np.ndarray], list[list[int | None]] | None]
"""Per structure its [S, nbody, nbody] distances, and with plans each plan's first crossing states."""


def jax_on_cpu() -> bool:
    """JAX's default backend is the CPU."""
    import jax  # lazy: jax (0.39 s) stays out of the CPU physics path, which loads none of it

    return jax.default_backend() == "cpu"


def start_shapes() -> dict:
    """What a process's first candidate launch is padded to on this platform (``mjx_batch.Shapes``
    fields): ``launch_start.CANDIDATE_PENETRATION`` on an accelerator, so that the shapes seldom grow;
    none on a CPU, where padding costs compute in proportion (8 cabinet candidates: 2.7 s of broad
    phase padded so, on 2 cores), so launches start at the size classes they need and grow."""
    return {} if jax_on_cpu() else launch_start.CANDIDATE_PENETRATION


def device_crossings() -> bool:
    """Whether this platform's launches answer the crossing queries too: on an accelerator (on a
    CPU numpy answers them faster: 1.6 s against 4.3 s for 19 candidates' 736 queries, warm)."""
    return not jax_on_cpu()


class Launcher(Protocol):
    """What ``candidate_verdicts`` sends its launches to."""

    crossings: bool  # whether this launcher is meant to answer crossing plans (the caller's default)

    def submit(self, arrays: Sequence[ObjectArrays], qpos: Sequence[np.ndarray],
               plans: Sequence[CrossingPlan] | None = None,
               timings: dict[str, float] | None = None) -> Callable[[], Replies]:
        """Start the distances of ``arrays`` at ``qpos`` (and with ``plans`` their first crossing
        states); the returned function waits for them, so the caller can work meanwhile."""
        ...


class LocalLauncher:
    """Launches in this process, each padded to the largest shapes this launcher has launched.

    ``penetration`` and ``crossing`` are those shapes (None before the first launch); a lock keeps
    two threads from launching at once, as they would race on the shapes."""

    def __init__(self) -> None:
        self.penetration: Shapes | None = None
        self.crossing: CrossingShapes | None = None
        self._lock = threading.Lock()

    @property
    def crossings(self) -> bool:
        return device_crossings()

    def submit(self, arrays: Sequence[ObjectArrays], qpos: Sequence[np.ndarray],
               plans: Sequence[CrossingPlan] | None = None,
               timings: dict[str, float] | None = None) -> Callable[[], Replies]:
        """Launch now (returning when done); ``timings`` gathers the launches' phases
        (``mjx_batch.batch_pair_distances``, "crossings")."""
        # lazy: MJX and jax (0.46 s), for a launch in this process only
        from jax3dc.physics.crossing_batch import CrossingShapes, batch_first_crossings
        from jax3dc.physics.mjx_batch import Shapes, batch_pair_distances

        first = None
        with self._lock:
            at_least = self.penetration or Shapes(**start_shapes())
            distances, self.penetration = batch_pair_distances(list(arrays), list(qpos), at_least, timings)
            if plans is not None:
                least = CrossingShapes() if jax_on_cpu() else CrossingShapes(**launch_start.CROSSINGS)
                first, self.crossing = batch_first_crossings(plans, self.crossing or least, timings)
        return lambda: (distances, first)


@dataclass
class ProcessDevice:
    """This process's launchers: the local one, and a device service's client once a pool's
    initializer (``mjx_service.init_worker``) installs one, which then takes every launch."""

    local: LocalLauncher = field(default_factory=LocalLauncher)
    client: Launcher | None = None

    def launcher(self) -> Launcher:
        return self.client if self.client is not None else self.local


PROCESS_DEVICE = ProcessDevice()
"""The one ``ProcessDevice`` of this process (a worker's initializer sets its client)."""


def process_launcher() -> Launcher:
    """The launcher of this process: the installed service client, else the local launcher."""
    return PROCESS_DEVICE.launcher()
