"""C MuJoCo evaluation of the checks: the default path on machines without an accelerator.

Kinematic checks need only ``mj_kinematics`` + ``mj_collision`` per state (one MjData per thread
or worker process); dynamic checks use ``mujoco.rollout`` (threaded C rollouts). For the
penetration check alone, rollout with distance sensors is the path without the GIL
(``RolloutDepths``; ``bench/physics.py`` times it against the processes).
"""

from __future__ import annotations

import multiprocessing as mp
import os
from concurrent.futures import ThreadPoolExecutor

import mujoco
import numpy as np
from mujoco import rollout


def pair_distances(model: mujoco.MjModel, qpos: np.ndarray, threads: int = 1) -> np.ndarray:
    """[S, nbody, nbody] smallest contact signed distance per body pair (metres; +inf: none within margin)."""
    out = np.full((len(qpos), model.nbody, model.nbody), np.inf)
    geom_body = model.geom_bodyid

    def run(rows: range) -> None:
        data = mujoco.MjData(model)
        for s in rows:
            data.qpos[:] = qpos[s]
            mujoco.mj_kinematics(model, data)
            mujoco.mj_collision(model, data)
            n = data.ncon
            if n:
                con = data.contact
                b1, b2, dist = geom_body[con.geom1[:n]], geom_body[con.geom2[:n]], con.dist[:n]
                np.minimum.at(out[s], (b1, b2), dist)
                np.minimum.at(out[s], (b2, b1), dist)

    chunks = [range(i, len(qpos), threads) for i in range(threads)]
    if threads == 1:
        run(chunks[0])
    else:
        with ThreadPoolExecutor(threads) as pool:
            list(pool.map(run, chunks))
    return out


def final_qpos(model: mujoco.MjModel, qpos: np.ndarray, ctrl: np.ndarray, nstep: int,
               threads: int | None = None) -> np.ndarray:
    """[S, nq] positions after ``nstep`` steps from rest velocities at ``qpos`` under constant ``ctrl``."""
    threads = threads or os.cpu_count() or 1
    data = mujoco.MjData(model)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    init = np.zeros((len(qpos), mujoco.mj_stateSize(model, spec)))
    for s, q in enumerate(qpos):
        mujoco.mj_resetData(model, data)
        data.qpos[:] = q
        mujoco.mj_getState(model, data, init[s], spec)
    controls = np.repeat(ctrl[:, None, :], nstep, axis=1)
    datas = [mujoco.MjData(model) for _ in range(threads)]
    with rollout.Rollout(nthread=threads) as r:
        state, _ = r.rollout(model, datas, init, controls, nstep=nstep)
    # the full-physics state is [time, qpos, qvel, act, ...]: qpos follows the time entry
    return state[:, -1, 1:1 + model.nq]


_WORKER_MODEL: mujoco.MjModel | None = None


def _init_worker(xml: str, assets: dict[str, bytes]) -> None:
    global _WORKER_MODEL
    _WORKER_MODEL = mujoco.MjModel.from_xml_string(xml, assets)


def _worker_chunk(qpos: np.ndarray) -> np.ndarray:
    return pair_distances(_WORKER_MODEL, qpos)


class PairDistancePool:
    """``pair_distances`` over worker processes, one model each: the per-state C calls hold the GIL,
    so threads do not scale and processes do. ``start`` is apart from ``map`` so that a benchmark
    can time the work without the pool's start-up."""

    def __init__(self, xml: str, assets: dict[str, bytes], workers: int | None = None):
        self.workers = workers or os.cpu_count() or 1
        # spawned: a forked child would inherit the parent's JAX threads and their locks
        self._pool = mp.get_context("spawn").Pool(self.workers, initializer=_init_worker, initargs=(xml, assets))

    def start(self, qpos: np.ndarray) -> None:
        """Runs the states through the pool once, so that ``map`` is timed warm: each process
        builds its model in the initializer, but a spawned one starts cold, and its first full
        chunks ran a third slower."""
        self.map(qpos)

    def map(self, qpos: np.ndarray) -> np.ndarray:
        return np.concatenate(self._pool.map(_worker_chunk, np.array_split(qpos, self.workers * 4)))

    def __enter__(self) -> "PairDistancePool":
        return self

    def __exit__(self, *exc) -> None:
        self._pool.terminate()


class RolloutDepths:
    """Signed distance of every colliding body pair where it is < 0, by C MuJoCo's fastest path for
    the penetration check: ``mujoco.rollout`` runs its threads without the GIL, and a
    signed-distance sensor per body pair (cutoff 0, contacts off) reads each pair's penetration in
    one step (sensors are computed from the state before it is integrated). Pairs are those
    ``mj_collision`` considers: different rigid bodies, both with colliding geoms, not excluded.
    The sensor model is compiled once, apart from the calls."""

    def __init__(self, xml: str, assets: dict[str, bytes]):
        spec = mujoco.MjSpec.from_string(xml, assets)
        model = spec.compile()
        self.nbody = model.nbody
        self.pairs = _colliding_body_pairs(model)
        spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
        for a, b in self.pairs:
            sensor = spec.add_sensor()
            sensor.type = mujoco.mjtSensor.mjSENS_GEOMDIST
            sensor.objtype = sensor.reftype = mujoco.mjtObj.mjOBJ_BODY
            sensor.objname = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, a)
            sensor.refname = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b)
            sensor.cutoff = 0.0
        self.model = spec.compile()
        state_spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
        self._rest = np.zeros(mujoco.mj_stateSize(self.model, state_spec))
        mujoco.mj_getState(self.model, mujoco.MjData(self.model), self._rest, state_spec)

    def __call__(self, qpos: np.ndarray, threads: int | None = None) -> np.ndarray:
        """[S, nbody, nbody] penetration distance (metres, < 0) per body pair; +inf where none."""
        threads = threads or os.cpu_count() or 1
        init = np.repeat(self._rest[None], len(qpos), axis=0)
        init[:, 1:1 + self.model.nq] = qpos  # the full-physics state is [time, qpos, qvel, ...]
        datas = [mujoco.MjData(self.model) for _ in range(threads)]
        with rollout.Rollout(nthread=threads) as r:
            _, sensor_data = r.rollout(self.model, datas, init, nstep=1)
        out = np.full((len(qpos), self.nbody, self.nbody), np.inf)
        depth = sensor_data[:, 0, :]
        for k, (a, b) in enumerate(self.pairs):
            out[:, a, b] = out[:, b, a] = np.where(depth[:, k] < 0, depth[:, k], np.inf)
        return out


def _colliding_body_pairs(model: mujoco.MjModel) -> list[tuple[int, int]]:
    collides = (model.geom_contype | model.geom_conaffinity) > 0
    has = np.zeros(model.nbody, dtype=bool)
    np.logical_or.at(has, model.geom_bodyid[collides], True)
    excluded = set(int(s) for s in model.exclude_signature)
    return [(a, b) for a in range(1, model.nbody) for b in range(a + 1, model.nbody)
            if has[a] and has[b] and model.body_weldid[a] != model.body_weldid[b] and (a << 16) + b not in excluded]
