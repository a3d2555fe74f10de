"""C MuJoCo evaluation of the checks: the default path on machines without an accelerator.

Kinematic checks need only ``mj_kinematics`` + ``mj_collision`` per state (threads, one MjData
each); dynamic checks use ``mujoco.rollout`` (threaded C rollouts).
"""

from __future__ import annotations

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


def pair_distances_processes(xml: str, assets: dict[str, bytes], qpos: np.ndarray,
                             workers: int | None = None) -> np.ndarray:
    """``pair_distances`` over worker processes, one model each: the per-state C calls hold the GIL,
    so threads do not scale and processes are the fastest C path on a many-core machine."""
    import multiprocessing as mp

    workers = workers or os.cpu_count() or 1
    chunks = np.array_split(qpos, workers * 4)
    with mp.get_context("fork").Pool(workers, initializer=_init_worker, initargs=(xml, assets)) as pool:
        return np.concatenate(pool.map(_worker_chunk, chunks))
