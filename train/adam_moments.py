"""Adam's scaling with both moments stored in a narrower dtype than the master weights (issue 51).

fp32 master weights with fp32 moments of the 4B config (vision frozen: 16.1 GB of weights,
32.2 GB of moments, 16.1 GB of gradients, bench/train_memory.py) leave too little of one 80 GB
card for activations; bf16 weights do not learn (an lr-1e-5 update is below bf16's resolution).
Keeping the weights in fp32 and only the moments in bf16 halves the moments. optax's
``scale_by_adam`` narrows the first moment only (``mu_dtype``), so this keeps both in the chosen
dtype, reads them back to float32 for the update, and stores them with stochastic rounding
(train/stochastic_rounding.py).

Why stochastic: with b2 = 0.999 the second moment changes by 0.1 % a step, less than half a
bf16 step (0.2-0.4 %), so round-to-nearest drops the change. A toy run of the EMA over 2,000
steps whose gradient scale falls tenfold halfway ended at 0.25 (constant g^2) and 0.59 (noisy)
where float32 reached 0.30: nu stops following the gradients. Stochastic rounding keeps the
stored moment unbiased, so it follows them on average (tests/train/test_adam_moments.py).
The rounding noise is drawn from the step count, so a resumed run draws the same bits, and with
jax's partitionable threefry (the default) the bits do not depend on the mesh either.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import optax

from train.stochastic_rounding import round_to_bfloat16

MOMENT_DTYPES = ("float32", "bfloat16")


def _store(mu: Any, nu: Any, dtype: jnp.dtype, key: jax.Array) -> tuple[Any, Any]:
    """Both moments in `dtype`: unchanged for float32, stochastically rounded for bfloat16. One
    32-bit draw per element serves both (its upper half rounds mu, its lower half nu): drawing the
    bits is most of the update's time on a CPU (338 ms against 69 without rounding, 16.8 M
    parameters); a GPU's figure comes from bench/train_step.py."""
    if dtype == jnp.float32:
        return mu, nu
    mus, treedef = jax.tree.flatten(mu)
    nus = treedef.flatten_up_to(nu)
    keys = jax.random.split(key, max(len(mus), 1))
    pairs = []
    for m, v, k in zip(mus, nus, keys):
        bits = jax.random.bits(k, m.shape, jnp.uint32)
        pairs.append((round_to_bfloat16(m, bits >> 16), round_to_bfloat16(v, bits & jnp.uint32(0xFFFF))))
    return (jax.tree.unflatten(treedef, [m for m, _ in pairs]), jax.tree.unflatten(treedef, [v for _, v in pairs]))


def scale_by_adam_stored_in(moments_dtype: str, b1: float, b2: float, eps: float,
                            seed: int = 0) -> optax.GradientTransformation:
    """optax.scale_by_adam's update with mu and nu kept in `moments_dtype` (float32 arithmetic).

    The state is optax's own ScaleByAdamState, so opt-state shardings and checkpoints treat it
    as they treat optax's."""
    if moments_dtype not in MOMENT_DTYPES:
        raise ValueError(f"moments dtype {moments_dtype!r}: expected one of {', '.join(MOMENT_DTYPES)}")
    dtype = jnp.dtype(moments_dtype)
    base_key = jax.random.key(seed)

    def init(params):
        zeros = lambda p: jnp.zeros(p.shape, dtype)  # noqa: E731
        return optax.ScaleByAdamState(count=jnp.zeros([], jnp.int32), mu=jax.tree.map(zeros, params),
                                      nu=jax.tree.map(zeros, params))

    def update(updates, state, params=None):
        del params
        f32 = lambda x: x.astype(jnp.float32)  # noqa: E731
        mu = jax.tree.map(lambda g, m: b1 * f32(m) + (1 - b1) * f32(g), updates, state.mu)
        nu = jax.tree.map(lambda g, v: b2 * f32(v) + (1 - b2) * jnp.square(f32(g)), updates, state.nu)
        count = optax.safe_increment(state.count)
        mu_scale = 1 / (1 - b1 ** count.astype(jnp.float32))
        nu_scale = 1 / (1 - b2 ** count.astype(jnp.float32))
        scaled = jax.tree.map(lambda g, m, v: (m * mu_scale / (jnp.sqrt(v * nu_scale) + eps)).astype(g.dtype),
                              updates, mu, nu)
        mu, nu = _store(mu, nu, dtype, jax.random.fold_in(base_key, count))
        return scaled, optax.ScaleByAdamState(count=count, mu=mu, nu=nu)

    return optax.GradientTransformation(init, update)
