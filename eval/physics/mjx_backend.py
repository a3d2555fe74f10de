"""MJX evaluation of the kinematic checks: kinematics + collision only, vmapped over joint states.

One jitted function per model structure (``compile_pair_distances``); objects with the same
structure (same bodies, geoms and pieces) reuse it with new states. Only the stages the checks
need run: no dynamics, no constraint solve.
"""

from __future__ import annotations

from typing import Callable

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
from mujoco import mjx


def _contact(dx):
    impl = getattr(dx, "_impl", None)  # mujoco-mjx ≥ 3.3 keeps the JAX backend's contacts here
    return impl.contact if impl is not None and hasattr(impl, "contact") else dx.contact


def compile_pair_distances(model: mujoco.MjModel) -> Callable[[jax.Array], jax.Array]:
    """A jitted fn: qpos [S, nq] -> [S, nbody, nbody] deepest contact distance (metres, ≤ 0; +inf: none).

    The model must have no geom margin (MJX implements none for mesh pairs)."""
    mx = mjx.put_model(model)
    nbody = model.nbody
    geom_body = jnp.asarray(model.geom_bodyid)

    def one(q):
        dx = mjx.make_data(mx).replace(qpos=q)
        dx = mjx.kinematics(mx, dx)
        dx = mjx.collision(mx, dx)
        con = _contact(dx)
        g1, g2 = con.geom[:, 0], con.geom[:, 1]
        # MJX keeps a slot for every candidate pair; separated pairs read dist = 1 (not their distance),
        # so only touching slots (dist ≤ 0; models here have no margin) are kept
        dist = jnp.where(con.dist <= 0.0, con.dist, jnp.inf)
        b1, b2 = geom_body[g1], geom_body[g2]
        out = jnp.full((nbody, nbody), jnp.inf, dist.dtype)
        out = out.at[b1, b2].min(dist)
        return out.at[b2, b1].min(dist)

    return jax.jit(jax.vmap(one))


def mjx_pair_distances(model: mujoco.MjModel, qpos: np.ndarray) -> np.ndarray:
    fn = compile_pair_distances(model)
    return np.asarray(fn(jnp.asarray(qpos, dtype=jnp.float32)), dtype=np.float64)
