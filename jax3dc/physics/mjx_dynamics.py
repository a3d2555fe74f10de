"""MJX rollouts for the dynamic checks (limit reachability, gravity), batched over start states.

The same contract as ``cpu_backend.final_qpos``: from rest velocities at each start ``qpos``, hold
each row's ``ctrl`` for ``nstep`` steps and return the final positions. Each row is one
``mjx.step`` loop under ``jax.vmap``. The MJX model is an argument of the compiled function, so
models that agree in what MJX keeps static (sizes, contact pairs, mesh data) share one compile.
Float32, as MJX runs on accelerators (C MuJoCo: float64).

The solver runs a fixed few Newton iterations: under ``vmap`` every row iterates until the slowest
converges, and float32 never meets C's 1e-8 tolerance, so MuJoCo's 100 (x 50 line-search)
iterations would all run at every step. 4 (x 8) take a quarter of the time and end within 1.5 mm,
0.0025 (quaternion) and 0.0074 rad of them on a laptop, a cabinet and a toilet held at random
targets on the floor, where MJX and C themselves part by up to 0.04 m and 0.12 rad (a toppling
object's fall is chaotic). ``tests/physics/test_physics_mjx_dynamics.py`` checks that the
verdicts agree.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
from mujoco import mjx

SOLVER_ITERATIONS = 4  # Newton iterations per MJX step (C MuJoCo: up to 100, until converged)
LINESEARCH_ITERATIONS = 8  # line-search iterations per Newton iteration (C MuJoCo: up to 50)


@functools.partial(jax.jit, static_argnames="nstep")
def _rollouts(mx: mjx.Model, qpos: jax.Array, ctrl: jax.Array, nstep: int) -> jax.Array:
    def one(q: jax.Array, c: jax.Array) -> jax.Array:
        data = mjx.make_data(mx).replace(qpos=q, ctrl=c)
        data = jax.lax.fori_loop(0, nstep, lambda _, d: mjx.step(mx, d), data)
        return data.qpos

    return jax.vmap(one)(qpos, ctrl)


def mjx_final_qpos(model: mujoco.MjModel, qpos: np.ndarray, ctrl: np.ndarray, nstep: int) -> np.ndarray:
    """[S, nq] positions after ``nstep`` MJX steps from rest velocities at ``qpos`` under constant ``ctrl``."""
    try:
        mx = mjx.put_model(model)
    except NotImplementedError as error:
        raise ValueError(f"the simulation model uses a feature MJX lacks: {error}") from error
    mx = mx.replace(opt=mx.opt.replace(iterations=SOLVER_ITERATIONS, ls_iterations=LINESEARCH_ITERATIONS))
    out = _rollouts(mx, jnp.asarray(qpos, jnp.float32), jnp.asarray(ctrl, jnp.float32), nstep=nstep)
    return np.asarray(out, dtype=np.float64)
