"""Stochastic rounding from float32 to bfloat16: round up with probability equal to the fraction
dropped, so the stored value is right on average. A quantity that moves by less than half a bf16
step per update (Adam's second moment at b2 = 0.999, a weight under an lr-1e-5 update) then
still moves; round-to-nearest drops every such change.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp


def round_to_bfloat16(x: jax.Array, noise: jax.Array) -> jax.Array:
    """float32 -> bfloat16, rounding the magnitude up with probability equal to the dropped fraction.

    A bfloat16 is the upper 16 bits of a float32: adding `noise` (uniform in [0, 2^16), uint32)
    to the 16 bits below them and truncating rounds up exactly that often (inf and nan stay)."""
    bits = jax.lax.bitcast_convert_type(x.astype(jnp.float32), jnp.uint32)
    truncated = (bits + noise) & jnp.uint32(0xFFFF0000)
    return jax.lax.bitcast_convert_type(truncated, jnp.float32).astype(jnp.bfloat16)


def apply_updates_rounded(params: Any, updates: Any, key: jax.Array) -> Any:
    """optax.apply_updates for bf16 weights: each sum is taken in float32 and rounded stochastically
    to bf16 (leaves of other dtypes are added as optax does)."""
    leaves, treedef = jax.tree.flatten(params)
    steps = treedef.flatten_up_to(updates)
    keys = jax.random.split(key, max(len(leaves), 1))
    out = []
    for p, u, k in zip(leaves, steps, keys):
        total = p.astype(jnp.float32) + u.astype(jnp.float32)
        if p.dtype == jnp.bfloat16:
            out.append(round_to_bfloat16(total, jax.random.bits(k, p.shape, jnp.uint32) >> 16))
        else:
            out.append(total.astype(p.dtype))
    return jax.tree.unflatten(treedef, out)
