"""The accelerator's side of a pool of worker processes that check objects with MJX: ``physics
sweep --backend mjx`` and verified decoding (``verify.pool``, each worker an object's candidates).
The workers prepare objects on the CPU and send their kinematic states here; the main process
gathers the requests that arrive together into one ``mjx_batch`` launch and sends each worker its
distances back.

The CPU work of a check (collision pieces, guides, rollouts) stays in the workers, so the
accelerator is fed by every core while it runs the interpenetration sweep of many objects at once.
A candidate set's board-crossing plans (``crossing.crossing_plan``) come as one request of their
own when the service takes them (``crossings``: on an accelerator), answered by a
``crossing_batch`` launch over every such request of the batch. A batch is closed when
``batch_objects`` requests are in or ``wait_s`` has passed since the first; a failed launch is sent
back to each of its workers as the error. Launches are padded to the largest shapes met so far
(``mjx_batch.Shapes``), so the launches compile only when they grow.
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import queue
import sys
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import mujoco
import numpy as np

from jax3dc.compilation import CompileClock
from jax3dc.physics import launch_start
from jax3dc.physics.launcher import PROCESS_DEVICE, Replies


@dataclass
class ServiceStats:
    """What the device did over a run of the pool: launches, objects, and the XLA compiles among them."""

    launches: int = 0
    objects: int = 0
    items: int = 0
    device_s: float = 0.0
    compiles: int = 0
    compile_s: float = 0.0
    phases: dict[str, float] = field(default_factory=dict)  # seconds per phase of the launches (mjx_batch)
    shapes: object = None  # the shapes the last launch was padded to

    def to_json(self) -> dict[str, float]:
        return {"launches": self.launches, "objects": self.objects, "states": self.items,
                "device_s": round(self.device_s, 2), "compiles": self.compiles, "compile_s": round(self.compile_s, 2),
                "phases_s": {k: round(v, 2) for k, v in self.phases.items()},
                "shapes": None if self.shapes is None else dataclasses.asdict(self.shapes)}


class DeviceService:
    """Queues between a pool's workers (a sweep's, verified decoding's) and the accelerator; ``serve``
    runs in a thread of the main process."""

    def __init__(self, context, workers: int, batch_objects: int = 16, wait_s: float = 0.05,
                 start_shapes: dict | None = None, crossings: bool = False):
        """``start_shapes``: what the first launch is padded to (``mjx_batch.Shapes`` fields;
        default ``launch_start.SWEEP_PENETRATION``; empty: the size classes each launch needs, as on
        a CPU, for the crossing launches too); ``crossings``: the workers send their candidate sets'
        crossing queries here (on a CPU numpy answers them faster in the worker)."""
        self.start_shapes = launch_start.SWEEP_PENETRATION if start_shapes is None else start_shapes
        self.crossings = crossings
        self.requests = context.Queue()
        self.replies = [context.Queue() for _ in range(workers)]
        self.next_worker = context.Value("i", 0)
        self.batch_objects, self.wait_s = batch_objects, wait_s
        self.stats = ServiceStats()

    def worker_args(self) -> tuple:
        """The initializer arguments of a worker process (``init_worker``)."""
        return self.requests, self.replies, self.next_worker, self.crossings

    def serve(self, stop: threading.Event) -> None:
        # lazy: MJX and jax (0.46 s); the CPU physics path imports this module (candidate_verdicts) and loads neither
        from jax3dc.physics.crossing_batch import CrossingShapes
        from jax3dc.physics.mjx_batch import Shapes

        clock = CompileClock()
        # the largest met so far: every launch is padded to it, so compiles happen only as it grows
        shapes = [Shapes(**self.start_shapes),
                  CrossingShapes(**launch_start.CROSSINGS) if self.crossings and self.start_shapes else CrossingShapes()]
        self.stats.shapes = shapes[0]
        while not stop.is_set():
            try:
                batch = [self.requests.get(timeout=0.1)]
            except queue.Empty:
                continue
            deadline = time.monotonic() + self.wait_s
            while len(batch) < self.batch_objects and (left := deadline - time.monotonic()) > 0:
                try:
                    batch.append(self.requests.get(timeout=left))
                except queue.Empty:
                    break
            start = time.perf_counter()
            results = self._launch(batch, shapes)
            self.stats.shapes = shapes[0]
            self.stats.device_s += time.perf_counter() - start
            compiled = clock.elapsed()
            self.stats.compiles, self.stats.compile_s = int(compiled["compiles"]), compiled["xla_s"]
            for (worker, _, _), result in zip(batch, results):
                self.replies[worker].put(result)

    def _launch(self, batch: list[tuple], shapes: list) -> list:
        """The replies to ``batch``'s requests, in its order: one penetration launch for the
        ("sweep", arrays, qpos) requests, one crossing launch for the ("crossings", plans, None) ones;
        a failed launch is each of its requests' reply. ``shapes`` [sweep, crossings] grow in place."""
        # lazy: as in serve (imported there already; this module stays importable without jax)
        from jax3dc.physics.crossing_batch import batch_first_crossings
        from jax3dc.physics.mjx_batch import batch_pair_distances

        results: list = [None] * len(batch)
        sweeps = [i for i, (_, r, _) in enumerate(batch) if r[0] == "sweep"]
        crossing = [i for i, (_, r, _) in enumerate(batch) if r[0] == "crossings"]
        if sweeps:
            try:
                distances, shapes[0] = batch_pair_distances([batch[i][1][1] for i in sweeps], [batch[i][2] for i in sweeps],
                                                            shapes[0], self.stats.phases)
            except Exception as error:  # noqa: BLE001  (sent back: the worker raises it for its object)
                distances = [error] * len(sweeps)
            self.stats.launches += 1
            self.stats.objects += len(sweeps)
            self.stats.items += sum(len(batch[i][2]) for i in sweeps)
            for i, d in zip(sweeps, distances):
                results[i] = d
        if crossing:
            plans = [p for i in crossing for p in batch[i][1][1]]
            try:
                first, shapes[1] = batch_first_crossings(plans, shapes[1], self.stats.phases)
            except Exception as error:  # noqa: BLE001  (as above)
                first = [error] * len(plans)
            at = 0
            for i in crossing:
                n = len(batch[i][1][1])
                answers = first[at:at + n]
                at += n
                errors = [a for a in answers if isinstance(a, Exception)]
                results[i] = errors[0] if errors else answers
        return results


@dataclass
class DeviceClient:
    """A worker's handle on the service: ``(model, qpos) -> [S, nbody, nbody]`` like
    ``padded_pair_distances``, and a ``launcher.Launcher`` (``submit``)."""

    worker: int
    requests: object
    reply: object
    crossings: bool = False  # the service answers crossing queries (``submit``'s plans)

    def __call__(self, model: mujoco.MjModel, qpos: np.ndarray) -> np.ndarray:
        return self.many([model], [qpos])[0]

    def many(self, models: list[mujoco.MjModel], qpos: list[np.ndarray]) -> list[np.ndarray]:
        """Several models' distances (a candidate set's): all sent before the first reply is awaited,
        so the service can put them in one launch; replies come back in request order."""
        from jax3dc.physics.mjx_batch import object_arrays  # lazy: as in DeviceService.serve (0.50 s)

        return self.submit([object_arrays(m) for m in models], qpos)()[0]

    def submit(self, arrays: Sequence, qpos: Sequence[np.ndarray], plans: Sequence | None = None,
               timings: dict[str, float] | None = None) -> Callable[[], Replies]:
        """Send the distances of ``arrays`` (``mjx_batch.ObjectArrays``) at ``qpos`` and, with
        ``plans`` (``crossing.CrossingPlan``), the first crossing states of their queries; the
        returned function waits for the replies, so the caller can work while the device does.
        ``timings`` stays as it is: the launches' phases are the service's (``ServiceStats.phases``)."""
        for a, q in zip(arrays, qpos):
            self.requests.put((self.worker, ("sweep", a), np.asarray(q)))
        if plans is not None:  # in one message: the boards the plans share are pickled once
            self.requests.put((self.worker, ("crossings", list(plans)), None))

        def wait() -> Replies:
            results = self._replies(len(arrays) + (plans is not None))
            return (results[:-1], results[-1]) if plans is not None else (results, None)

        return wait

    def _replies(self, n: int) -> list:
        results = [self.reply.get() for _ in range(n)]
        for result in results:
            if isinstance(result, Exception):
                raise result
        return results


def init_worker(requests, replies, next_worker, crossings: bool = False) -> None:
    """Pool initializer: this process's client (``launcher.PROCESS_DEVICE.client``, which then takes
    the process's launches), and JAX kept off the accelerator (the workers build arrays; only the
    main process launches)."""
    os.environ["JAX_PLATFORMS"] = "cpu"
    if "jax" in sys.modules:  # imported already (by the job's module): its backends start only on first use
        sys.modules["jax"].config.update("jax_platforms", "cpu")
    with next_worker.get_lock():
        worker = next_worker.value
        next_worker.value += 1
    PROCESS_DEVICE.client = DeviceClient(worker, requests, replies[worker], crossings)


def serve_workers(stack: contextlib.ExitStack, context, workers: int, **service) -> tuple[DeviceService, dict]:
    """A DeviceService for ``workers`` processes of ``context``, served from a thread of this
    process until ``stack`` closes, and the ``ProcessPoolExecutor`` arguments that connect each
    worker to it; ``service``: DeviceService's settings. Enter the pool on ``stack`` after this
    call, so that it closes first and the service outlives its last request."""
    device = DeviceService(context, workers, **service)
    stop = threading.Event()
    server = threading.Thread(target=device.serve, args=(stop,), daemon=True)
    server.start()
    stack.callback(server.join)
    stack.callback(stop.set)
    return device, {"initializer": init_worker, "initargs": device.worker_args()}


def client() -> DeviceClient:
    """This process's client, installed by a pool's ``init_worker``."""
    installed = PROCESS_DEVICE.client
    if not isinstance(installed, DeviceClient):
        raise RuntimeError("no device service in this process: init_worker was not run")
    return installed
