"""Token cross-entropy through the LM head: chunked along the sequence, split over the mesh.

Why a module of its own: the LM head (vocab x embed, 389 M parameters for Qwen3's vocabulary at
the 4B width) is the largest matrix of the model. Scored chunk by chunk in a loop under plain
sharding propagation, an FSDP-sharded head is all-gathered and its gradient all-reduced once per
chunk, in the forward and again in the backward pass. Here the head enters a ``shard_map`` once
per micro-batch:

* every device scores its own rows (split over the mesh axes of the ``batch`` rule, data x fsdp
  by default) against its slice of the vocabulary (the ``vocab`` rule, tensor by default), both
  read from the active rules table (jax3dc/sharding.py), so the loss follows the run's layout;
* the softmax normaliser and the label's logit are combined over the vocabulary axis with
  collectives of [rows, chunk] floats;
* the head's gradient is summed over the batch axes once, where it leaves the ``shard_map``.

Logits are made ``chunk`` positions at a time and recomputed in the backward pass, so the full
[rows, L, vocab] float32 logits never exist at once.
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
from jax.sharding import PartitionSpec as P

from jax3dc import sharding


def _chunk_scores(h: jax.Array, head: jax.Array, labels: jax.Array, mask: jax.Array,
                  vocab_axis: str | tuple[str, ...] | None) -> tuple[jax.Array, jax.Array]:
    """(masked NLL sum, correct-prediction count) of one chunk against this device's head slice."""
    # bf16 logits, then float32: the backward dots stay in bf16 (a float32 cotangent would turn
    # the two head-sized gradient matmuls into slow tf32 GEMMs)
    logits = jnp.einsum("rce,ve->rcv", h, head).astype(jnp.float32)
    top = jax.lax.stop_gradient(jnp.max(logits, axis=-1))  # only for a stable exp; cancels exactly
    if vocab_axis is not None:
        top = jax.lax.pmax(top, vocab_axis)
    sum_exp = jnp.sum(jnp.exp(logits - top[..., None]), axis=-1)
    local = labels
    if vocab_axis is not None:
        sum_exp = jax.lax.psum(sum_exp, vocab_axis)
        local = labels - jax.lax.axis_index(vocab_axis) * head.shape[0]
    inside = (local >= 0) & (local < head.shape[0])
    picked = jnp.take_along_axis(logits, jnp.clip(local, 0, head.shape[0] - 1)[..., None], axis=-1)[..., 0]
    picked = jnp.where(inside, picked, 0.0)
    if vocab_axis is not None:
        picked = jax.lax.psum(picked, vocab_axis)
    mask = mask.astype(jnp.float32)
    nll = jnp.sum((jnp.log(sum_exp) + top - picked) * mask)
    correct = jnp.sum((picked >= jax.lax.stop_gradient(top)) * mask)  # the label holds the top logit
    return nll, correct


def _local_loss(hidden, head, labels, mask, chunk: int, vocab_axis: str | tuple[str, ...] | None,
                batch_axes: tuple[str, ...]) -> tuple[jax.Array, jax.Array]:
    rows, length, _ = hidden.shape
    n = length // chunk
    split = lambda x: jnp.moveaxis(x.reshape(rows, n, chunk, *x.shape[2:]), 1, 0)
    if batch_axes:  # varying from here: the head's gradient is summed once, here, not per chunk
        head = jax.lax.pcast(head, batch_axes, to="varying")
    one = jax.checkpoint(lambda h, y, m: _chunk_scores(h, head, y, m, vocab_axis))

    _, (nll, correct) = jax.lax.scan(lambda _, xs: (None, one(*xs)), None,
                                     (split(hidden), split(labels), split(mask)))
    nll, correct = jnp.sum(nll), jnp.sum(correct)
    if batch_axes:
        nll, correct = jax.lax.psum(nll, batch_axes), jax.lax.psum(correct, batch_axes)
    return nll, correct


def _dividing_axes(logical: str, what: str, size: int, mesh_shape: dict[str, int]) -> tuple[str, ...]:
    """The mesh axes of ``logical`` in the active rules, or () with a logged warning when they do
    not divide ``size`` (the dimension is then whole on every device)."""
    axes = sharding.mesh_axes(logical, mesh_shape, sharding.active_rules())
    devices = math.prod(mesh_shape[a] for a in axes)
    if size % devices:
        sharding.warn_replicated(what, size, axes, devices)
        return ()
    return axes


def token_loss(hidden: jax.Array, head: jax.Array, labels: jax.Array, mask: jax.Array,
               chunk: int) -> tuple[jax.Array, jax.Array]:
    """(sum of masked token NLL, number of positions whose top logit is the label).

    hidden [rows, L, embed]; head [vocab, embed] (compute dtype); labels, mask [rows, L].
    ``chunk`` must divide L. Under a mesh (``jax.set_mesh``) the work is split as described in
    the module docstring; without one it runs as plain jitted code.
    """
    if hidden.shape[1] % chunk:
        raise ValueError(f"loss chunk {chunk} does not divide the sequence length {hidden.shape[1]}")
    mesh = jax.sharding.get_abstract_mesh()
    if mesh.empty:
        return _local_loss(hidden, head, labels, mask, chunk, None, ())
    shape = dict(mesh.shape)
    batch_axes = _dividing_axes("batch", "loss rows", hidden.shape[0], shape)
    vocab_axes = _dividing_axes("vocab", "LM-head vocabulary", head.shape[0], shape)
    vocab_axis = None if not vocab_axes else vocab_axes[0] if len(vocab_axes) == 1 else vocab_axes
    rows = P(batch_axes or None)
    fn = jax.shard_map(
        lambda h, w, y, m: _local_loss(h, w, y, m, chunk, vocab_axis, batch_axes),
        in_specs=(rows, P(vocab_axis), rows, rows), out_specs=(P(), P()))
    return fn(hidden, head, labels, mask)
