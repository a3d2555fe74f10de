"""Causal attention within the examples of a packed row (segment ids 1..k, 0 = trailing padding).

As a dense block-diagonal mask, a packed 4,096-token row costs what no flash kernel avoids: the
mask becomes a bias of [rows, 1, L, L] that cuDNN reads in the forward and XLA keeps per layer for
the backward, and the 4B step ran out of 80 GB at 4,096 tokens with the loader's packed rows
(docs/BENCHMARKS.md). cuDNN's flash attention takes packed rows natively instead: each
example's length and start offset ("ragged" layout), causal inside each example, nothing
materialised. jax.nn.dot_product_attention does not expose those arguments, so the cuDNN path
calls JAX's cuDNN attention module directly; every other backend uses the dense mask (the
reference the GPU check compares against, bench/packed_attention.py).
"""

from __future__ import annotations

import math

import flax.struct
import jax
import jax.numpy as jnp
from jax._src.cudnn.fused_attention_stablehlo import MaskType, dot_product_attention


@flax.struct.dataclass
class PackedRows:
    """Where each example of each row lies: the mask of packed rows, in both forms."""

    segment_ids: jax.Array  # [B, L] int32: 1..k per example, 0 for padding
    # cuDNN's view, M = max_examples + 1: the k examples, then the trailing padding as one more
    # segment (every slot in some segment, so no slot's output or gradient is left undefined)
    lengths: jax.Array  # [B, M] int32: tokens of each segment, -1 past the row's last
    offsets: jax.Array  # [B, M + 1] int32: first slot of each segment, -1 past the last


def packed_rows(segment_ids: jax.Array, max_examples: int) -> PackedRows:
    """Lengths and offsets of at most `max_examples` contiguous examples per row, numbered
    1..k from the row's start (data_pipeline/packing.py), and of the padding after them."""
    rows, length = segment_ids.shape
    ids = jnp.arange(1, max_examples + 1, dtype=segment_ids.dtype)
    counts = jnp.sum(segment_ids[:, :, None] == ids, axis=1).astype(jnp.int32)  # [B, max_examples]
    padding = length - jnp.sum(counts, axis=1)
    examples = jnp.sum(counts > 0, axis=1)
    counts = jnp.concatenate([counts, jnp.zeros((rows, 1), jnp.int32)], axis=1)
    counts = counts.at[jnp.arange(rows), examples].add(padding)
    starts = jnp.cumsum(counts, axis=1) - counts
    present = counts > 0
    lengths = jnp.where(present, counts, -1)
    offsets = jnp.concatenate([jnp.where(present, starts, -1), jnp.full((rows, 1), -1, jnp.int32)], axis=1)
    return PackedRows(segment_ids, lengths, offsets)


def segment_mask(segment_ids: jax.Array) -> jax.Array:
    """[B, 1, L, L]: causal within each example; padding sees only itself (no empty softmax)."""
    length = segment_ids.shape[1]
    pos = jnp.arange(length)
    causal = pos[None, :] <= pos[:, None]
    same = (segment_ids[:, :, None] == segment_ids[:, None, :]) & (segment_ids[:, None, :] > 0)
    return ((same & causal[None]) | jnp.eye(length, dtype=bool)[None])[:, None]


def packed_attention(q: jax.Array, k: jax.Array, v: jax.Array, rows: PackedRows,
                     implementation: str | None) -> jax.Array:
    """[B, L, heads, head_dim] attention of each token over its own example's earlier tokens.
    Padding slots attend over the padding on the cuDNN path and to themselves on the dense one;
    neither is scored."""
    if implementation != "cudnn":
        return jax.nn.dot_product_attention(q, k, v, mask=segment_mask(rows.segment_ids), implementation=implementation)

    return dot_product_attention(q, k, v, q_seqlen=rows.lengths, kv_seqlen=rows.lengths, q_offsets=rows.offsets,
                                 kv_offsets=rows.offsets, scale=1.0 / math.sqrt(q.shape[-1]),
                                 mask_type=MaskType.PADDING_CAUSAL)
