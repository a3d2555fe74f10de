"""Random weights for a benchmark model without compiling its whole initialiser.

Building a 4B NNX model inside one jit takes minutes of XLA compile time on a GPU (measured on
an H100, 2026-11-22: > 5 min). Here the model is built abstractly, and each parameter is filled by
a tiny jitted program per distinct (shape, dtype), so set-up costs seconds. Matrices get HF's
initialiser (normal, std 0.02), norm scales one and biases zero, so the result also serves as a
from-scratch starting point.
"""

from __future__ import annotations

from functools import partial
from typing import Callable

import jax
import jax.numpy as jnp
from flax import nnx


@partial(jax.jit, static_argnames=("shape", "dtype", "kind"))
def _fill(key: jax.Array, shape: tuple[int, ...], dtype, kind: str) -> jax.Array:
    if kind == "norm":  # RMSNorm / LayerNorm scales start at one
        return jnp.ones(shape, dtype)
    if kind == "bias":
        return jnp.zeros(shape, dtype)
    return (0.02 * jax.random.normal(key, shape, jnp.float32)).astype(dtype)  # HF's initializer_range


def _kind(path, shape) -> str:
    if len(shape) > 1:
        return "weight"
    return "norm" if any("norm" in str(getattr(k, "key", k)) for k in path) else "bias"


def build_random(make: Callable[[], nnx.Module], seed: int = 0, shardings=None) -> nnx.Module:
    """``make`` constructs the module (it is only traced); returns it with random weights.

    ``shardings``, if given, is a pytree like the state of NamedShardings to place each array on.
    """
    abstract = nnx.eval_shape(make)
    graphdef, state = nnx.split(abstract)
    with_paths, treedef = jax.tree_util.tree_flatten_with_path(state)
    paths = [p for p, _ in with_paths]
    leaves = [leaf for _, leaf in with_paths]
    keys = jax.random.split(jax.random.key(seed), len(leaves))
    targets = jax.tree.leaves(shardings) if shardings is not None else [None] * len(leaves)
    filled = []
    for key, path, leaf, target in zip(keys, paths, leaves, targets):
        shape = tuple(leaf.shape)
        value = _fill(key, shape, jnp.dtype(leaf.dtype), _kind(path, shape))
        filled.append(jax.device_put(value, target) if target is not None else value)
    return nnx.merge(graphdef, jax.tree.unflatten(treedef, filled))
