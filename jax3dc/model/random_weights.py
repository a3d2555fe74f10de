"""Random weights for a benchmark model without compiling its whole initialiser.

Building a 4B NNX model inside one jit takes minutes of XLA compile time on a GPU (measured on
an H100, 2026-11-22: > 5 min). Here the model is built abstractly, and each parameter is filled by
a tiny jitted program per distinct (shape, dtype), so set-up costs seconds. Throughput does not
depend on the values, only that they are finite and not all zero.
"""

from __future__ import annotations

from functools import partial
from typing import Callable

import jax
import jax.numpy as jnp
from flax import nnx


@partial(jax.jit, static_argnames=("shape", "dtype"))
def _fill(key: jax.Array, shape: tuple[int, ...], dtype) -> jax.Array:
    if len(shape) <= 1:  # norm scales and biases: near one / near zero keeps activations sane
        return (1.0 + 0.01 * jax.random.normal(key, shape, jnp.float32)).astype(dtype)
    return (0.02 * jax.random.normal(key, shape, jnp.float32)).astype(dtype)


def build_random(make: Callable[[], nnx.Module], seed: int = 0, shardings=None) -> nnx.Module:
    """``make`` constructs the module (it is only traced); returns it with random weights.

    ``shardings``, if given, is a pytree like the state of NamedShardings to place each array on.
    """
    abstract = nnx.eval_shape(make)
    graphdef, state = nnx.split(abstract)
    leaves, treedef = jax.tree.flatten(state)
    keys = jax.random.split(jax.random.key(seed), len(leaves))
    targets = jax.tree.leaves(shardings) if shardings is not None else [None] * len(leaves)
    filled = []
    for key, leaf, target in zip(keys, leaves, targets):
        value = _fill(key, tuple(leaf.shape), jnp.dtype(leaf.dtype))
        filled.append(jax.device_put(value, target) if target is not None else value)
    return nnx.merge(graphdef, jax.tree.unflatten(treedef, filled))
