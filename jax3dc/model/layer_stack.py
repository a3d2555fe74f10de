"""Running a run of identical decoder layers as one scanned layer, with a named remat policy.

Unrolled, a 36-layer decoder is 36 copies of the same program for XLA to compile (36–55 s for
the 4B config); `jax.lax.scan` over the layers compiles one. The parameters keep their
per-layer layout (the HF weight table, checkpoints, LoRA and sharding rules are unchanged):
each layer's state is stacked at trace time, in the compute dtype the layers already run in,
so XLA fuses the stack with the cast the step does anyway, and the gradient flows back through
the stack to each layer's own parameters.

Remat policies (MaxText's vocabulary, mapped to `jax.checkpoint_policies`) name what the
backward pass may keep instead of recomputing:
  none     no rematerialisation: every activation kept (fastest, most memory)
  full     nothing kept: the layer is recomputed in the backward pass (least memory)
  minimal  matmul outputs without batch dimensions kept (projections; not attention scores)
  qkv      only the attention's q, k, v projections kept (tagged with `checkpoint_name`)
"""

from __future__ import annotations

from typing import Any, Callable, Sequence

import jax
import jax.numpy as jnp
from flax import nnx

REMAT_POLICIES: dict[str, Callable[..., bool] | None] = {
    "none": None,
    "full": jax.checkpoint_policies.nothing_saveable,
    "minimal": jax.checkpoint_policies.dots_with_no_batch_dims_saveable,
    "qkv": jax.checkpoint_policies.save_only_these_names("query_proj", "key_proj", "value_proj"),
}


def remat_policy(name: str) -> Callable[..., bool] | None:
    """The `jax.checkpoint` policy for `name`; None means no rematerialisation."""
    if name not in REMAT_POLICIES:
        raise ValueError(f"remat policy {name!r}: expected one of {', '.join(REMAT_POLICIES)}")
    return REMAT_POLICIES[name]


def stackable(layers: Sequence[nnx.Module]) -> bool:
    """Whether the layers share one structure (same graph definition), so one scanned body
    serves all of them (LoRA on some layers only would break this)."""
    graphdefs = [nnx.graphdef(layer) for layer in layers]
    return all(g == graphdefs[0] for g in graphdefs[1:])


def scan_layers(layers: Sequence[nnx.Module], x: jax.Array, call: Callable[[nnx.Module, jax.Array], jax.Array],
                remat: str = "none") -> jax.Array:
    """x after `call(layer, x)` for each layer in order, as one `lax.scan` over stacked states."""
    graphdef = nnx.graphdef(layers[0])
    states = [nnx.state(layer) for layer in layers]
    stacked: Any = jax.tree.map(lambda *leaves: jnp.stack(leaves), *states)

    def body(h: jax.Array, state: Any) -> tuple[jax.Array, None]:
        return call(nnx.merge(graphdef, state), h), None

    policy = remat_policy(remat)
    if remat != "none":
        body = jax.checkpoint(body, policy=policy, prevent_cse=False)
    out, _ = jax.lax.scan(body, x, stacked)
    return out
