"""Building blocks shared by the vision tower and the decoder: dense maps and norms whose
parameters carry logical axis names (see jax3dc/sharding.py).

Parameters are stored in ``param_dtype`` and cast to the compute ``dtype`` at use, so fp32 master
weights with bf16 compute is one switch. Norm statistics are always float32.
"""

from __future__ import annotations

from collections.abc import Sequence

import jax
import jax.numpy as jnp
from flax import nnx

INIT_STD = 0.02


def make_param(rngs: nnx.Rngs | None, shape: Sequence[int], axes: Sequence[str | None],
               param_dtype: jnp.dtype, fill: float | None = None) -> nnx.Param:
    """A parameter with logical axes; normal(0, 0.02) unless ``fill`` gives a constant."""
    if len(axes) != len(shape):
        raise ValueError(f"{len(axes)} logical axes for shape {tuple(shape)}")
    if fill is not None:
        value = jnp.full(shape, fill, param_dtype)
    else:
        value = (INIT_STD * jax.random.normal(rngs.params(), tuple(shape), jnp.float32)).astype(param_dtype)
    return nnx.Param(value, logical_axes=tuple(axes))


class Dense(nnx.Module):
    """Contracts the last ``len(in_shape)`` dims of x with a kernel ``[*in_shape, *out_shape]``.

    Multi-dimensional kernels (e.g. ``[embed, heads, head_dim]``) keep heads as their own axis so
    that tensor parallelism shards them without reshapes.
    """

    def __init__(self, in_shape: Sequence[int], out_shape: Sequence[int], in_axes: Sequence[str | None],
                 out_axes: Sequence[str | None], *, use_bias: bool, rngs: nnx.Rngs,
                 dtype: jnp.dtype = jnp.float32, param_dtype: jnp.dtype = jnp.float32):
        self.n_in = len(in_shape)
        self.dtype = dtype
        self.kernel = make_param(rngs, (*in_shape, *out_shape), (*in_axes, *out_axes), param_dtype)
        self.bias = make_param(rngs, out_shape, out_axes, param_dtype, fill=0.0) if use_bias else None

    def __call__(self, x: jax.Array) -> jax.Array:
        y = jnp.tensordot(x.astype(self.dtype), self.kernel.get_value().astype(self.dtype), axes=self.n_in)
        if self.bias is not None:
            y = y + self.bias.get_value().astype(self.dtype)
        return y


class RMSNorm(nnx.Module):
    """Qwen's RMSNorm: normalise in float32, cast back, then scale (transformers' order)."""

    def __init__(self, dim: int, eps: float, axis_name: str, *, dtype: jnp.dtype = jnp.float32,
                 param_dtype: jnp.dtype = jnp.float32):
        self.eps = eps
        self.dtype = dtype
        self.weight = make_param(None, (dim,), (axis_name,), param_dtype, fill=1.0)

    def __call__(self, x: jax.Array) -> jax.Array:
        xf = x.astype(jnp.float32)
        xf = xf * jax.lax.rsqrt(jnp.mean(xf * xf, axis=-1, keepdims=True) + self.eps)
        return self.weight.get_value().astype(self.dtype) * xf.astype(self.dtype)


class LayerNorm(nnx.Module):
    """LayerNorm with scale and bias (the vision tower's), statistics in float32."""

    def __init__(self, dim: int, axis_name: str, eps: float = 1e-6, *, dtype: jnp.dtype = jnp.float32,
                 param_dtype: jnp.dtype = jnp.float32):
        self.eps = eps
        self.dtype = dtype
        self.weight = make_param(None, (dim,), (axis_name,), param_dtype, fill=1.0)
        self.bias = make_param(None, (dim,), (axis_name,), param_dtype, fill=0.0)

    def __call__(self, x: jax.Array) -> jax.Array:
        xf = x.astype(jnp.float32)
        mean = jnp.mean(xf, axis=-1, keepdims=True)
        var = jnp.mean(jnp.square(xf - mean), axis=-1, keepdims=True)
        y = (xf - mean) * jax.lax.rsqrt(var + self.eps)
        y = y * self.weight.get_value().astype(jnp.float32) + self.bias.get_value().astype(jnp.float32)
        return y.astype(self.dtype)


def activation(name: str):
    """The activation functions Qwen3-VL's configs name (transformers' ACT2FN keys)."""
    table = {
        "silu": jax.nn.silu,
        "gelu": lambda x: jax.nn.gelu(x, approximate=False),
        "gelu_pytorch_tanh": lambda x: jax.nn.gelu(x, approximate=True),
        "gelu_new": lambda x: jax.nn.gelu(x, approximate=True),
    }
    if name not in table:
        raise ValueError(f"unsupported activation {name!r}; known: {sorted(table)}")
    return table[name]
