"""LoRA: low-rank adapters on the decoder's projections, and merging them back for export.

A wrapped projection computes ``x·W + (alpha / rank) · (x·A)·B`` with ``A [*in, rank]`` (normal,
std 1/sqrt(fan-in)) and ``B [rank, *out]`` (zeros, so a fresh adapter leaves the model's output
unchanged). The adapters are ``nnx.LoRAParam`` variables, so a type filter selects them for
training while the base weights stay frozen (held in the compute dtype). They carry the wrapped
kernel's logical axes on their ``in`` / ``out`` sides (rank is never sharded), so the one rules
table places them beside the weights they adapt.

Adding adapters is surgery on a built model rather than a model argument: the base kernel keeps
its path (``...q_proj.kernel``), so the HF weight table, ``freeze=`` patterns and checkpoints of
the base model see no change, and the network code knows nothing about LoRA::

    model = add_lora(model, LoraSpec(rank=16, alpha=32.0), rngs=nnx.Rngs(0))
    ...train the nnx.LoRAParam variables...
    plain = merge_lora(model)   # W + scale * A @ B: the plain architecture again
    save_pretrained(model, ...)  # merges tensor by tensor (merged_params): a plain checkpoint
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import jax
import jax.numpy as jnp
from flax import nnx

from jax3dc.model.layers import Dense
from jax3dc.sharding import param_logical_axes

#: The decoder projections that can take adapters: attention's, then the SwiGLU MLP's.
TARGETS = ("q_proj", "k_proj", "v_proj", "o_proj", "gate_proj", "up_proj", "down_proj")


@dataclass(frozen=True)
class LoraSpec:
    """Rank, scale numerator and which decoder projections get adapters."""

    rank: int
    alpha: float
    targets: tuple[str, ...] = TARGETS

    def __post_init__(self) -> None:
        if self.rank < 1:
            raise ValueError(f"LoRA rank must be >= 1, got {self.rank}")
        unknown = sorted(set(self.targets) - set(TARGETS))
        if unknown or not self.targets:
            raise ValueError(f"LoRA targets {self.targets}: expected a non-empty subset of {', '.join(TARGETS)}")

    @property
    def scale(self) -> float:
        return self.alpha / self.rank


class LoraDense(Dense):
    """A Dense plus a low-rank update. It holds the wrapped Dense's own kernel and bias
    variables (same paths), adding ``lora_a`` and ``lora_b`` beside them."""

    def __init__(self, base: Dense, spec: LoraSpec, *, rngs: nnx.Rngs, param_dtype: jnp.dtype):
        self.n_in, self.dtype, self.kernel, self.bias = base.n_in, base.dtype, base.kernel, base.bias
        self.scale = spec.scale
        shape, axes = self.kernel.get_value().shape, param_logical_axes(self.kernel)
        in_shape, out_shape = shape[:self.n_in], shape[self.n_in:]
        std = 1.0 / math.sqrt(math.prod(in_shape))
        a = std * jax.random.normal(rngs.params(), (*in_shape, spec.rank), jnp.float32)
        self.lora_a = nnx.LoRAParam(a.astype(param_dtype), logical_axes=(*axes[:self.n_in], None))
        self.lora_b = nnx.LoRAParam(jnp.zeros((spec.rank, *out_shape), param_dtype),
                                    logical_axes=(None, *axes[self.n_in:]))

    def __call__(self, x: jax.Array) -> jax.Array:
        low = jnp.tensordot(x.astype(self.dtype), self.lora_a.get_value().astype(self.dtype), axes=self.n_in)
        update = jnp.tensordot(low * self.scale, self.lora_b.get_value().astype(self.dtype), axes=1)
        return super().__call__(x) + update

    def merged_kernel(self) -> jax.Array:
        """``W + scale * A @ B``, summed in float32 and stored in the wider of the kernel's and
        the adapters' dtypes (a bf16 base with fp32 adapters exports fp32 kernels, so small
        updates are not rounded away)."""
        a, b = (v.get_value().astype(jnp.float32) for v in (self.lora_a, self.lora_b))
        delta = jnp.tensordot(a, b, axes=1) * self.scale
        dtype = jnp.promote_types(self.kernel.get_value().dtype, self.lora_a.get_value().dtype)
        return (self.kernel.get_value().astype(jnp.float32) + delta).astype(dtype)


def _sites(model: nnx.Module, targets: tuple[str, ...]) -> Iterator[tuple[nnx.Module, str]]:
    """(parent module, attribute name) of every targeted projection of every decoder layer."""
    for layer in model.language_model.layers:
        for parent in (layer.self_attn, layer.mlp):
            for name in targets:
                if hasattr(parent, name):
                    yield parent, name


def add_lora(model: nnx.Module, spec: LoraSpec, *, rngs: nnx.Rngs, param_dtype: jnp.dtype = jnp.float32) -> nnx.Module:
    """Wraps the decoder projections named by ``spec.targets`` in place; returns ``model``.

    Works on an abstract model too (inside ``nnx.eval_shape``), which is how the trainer gets
    the adapters' shapes and shardings before any array exists."""
    for parent, name in _sites(model, spec.targets):
        setattr(parent, name, LoraDense(getattr(parent, name), spec, rngs=rngs, param_dtype=param_dtype))
    return model


def merged_params(model: nnx.Module) -> Iterator[tuple[str, jax.Array]]:
    """(dotted path, value) of every parameter of the merged model, in ``nnx.state`` order.

    Each merged kernel is computed when it is reached, so an export holds one of them at a time
    beside the model (a 4B decoder's all at once, in float32, would add 14.5 GB to its 9 GB)."""
    adapted = {".".join(map(str, p)) + ".kernel": m for p, m in nnx.iter_graph(model) if isinstance(m, LoraDense)}
    for p, v in nnx.to_flat_state(nnx.state(model, nnx.Param)):
        if isinstance(v, nnx.LoRAParam):
            continue
        name = ".".join(map(str, p))
        yield name, adapted[name].merged_kernel() if name in adapted else v.get_value()


def _plain(lora: LoraDense) -> Dense:
    """A Dense holding the merged kernel (its shell is built abstractly: no random init)."""
    kernel = lora.merged_kernel()
    axes = param_logical_axes(lora.kernel)
    n = lora.n_in
    dense = nnx.eval_shape(lambda: Dense(kernel.shape[:n], kernel.shape[n:], axes[:n], axes[n:],
                                         use_bias=lora.bias is not None, rngs=nnx.Rngs(0),
                                         dtype=lora.dtype, param_dtype=kernel.dtype))
    dense.kernel.set_value(kernel)
    dense.bias = lora.bias
    return dense


def merge_lora(model: nnx.Module) -> nnx.Module:
    """A copy of ``model`` with every adapter folded into its kernel: the plain architecture
    again (no LoRAParam left, no adapter matmuls at inference). ``model`` itself is unchanged."""
    merged = nnx.merge(*nnx.split(model))
    for parent, name in _sites(merged, TARGETS):
        module = getattr(parent, name)
        if isinstance(module, LoraDense):
            setattr(parent, name, _plain(module))
    return merged

