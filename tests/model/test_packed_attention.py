"""Packed rows: the example lengths and offsets handed to cuDNN's ragged attention equal what the
segment ids say (numpy reference), and the dense-mask path keeps each example apart exactly as
if it were alone in its own row."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jax3dc.model.packed_attention import packed_attention, packed_rows

ROWS = np.array([[1, 1, 1, 2, 2, 3, 0, 0],
                 [1, 1, 1, 1, 1, 1, 1, 1],
                 [1, 2, 2, 2, 0, 0, 0, 0]], np.int32)


def reference(segment_ids: np.ndarray, max_examples: int) -> tuple[np.ndarray, np.ndarray]:
    """The examples' runs, then the padding's run, then -1."""
    lengths = -np.ones((len(segment_ids), max_examples + 1), np.int32)
    offsets = -np.ones((len(segment_ids), max_examples + 2), np.int32)
    for b, row in enumerate(segment_ids):
        runs = [np.flatnonzero(row == m + 1) for m in range(max_examples)] + [np.flatnonzero(row == 0)]
        runs = [r for r in runs if r.size]
        for m, where in enumerate(runs):
            lengths[b, m], offsets[b, m] = where.size, where[0]
    return lengths, offsets


@pytest.mark.parametrize("max_examples", [3, 5])
def test_lengths_and_offsets_follow_the_segment_ids(max_examples):
    rows = packed_rows(jnp.asarray(ROWS), max_examples)
    lengths, offsets = reference(ROWS, max_examples)
    np.testing.assert_array_equal(rows.lengths, lengths)
    np.testing.assert_array_equal(rows.offsets, offsets)
    assert rows.offsets.shape == (3, max_examples + 2) and (rows.offsets[:, -1] == -1).all()


def test_each_example_attends_as_if_alone():
    rng = np.random.default_rng(0)
    q, k, v = (jnp.asarray(rng.standard_normal((3, 8, 4, 16)), jnp.float32) for _ in range(3))
    kv = k[:, :, :2], v[:, :, :2]  # grouped-query: 4 query heads over 2 key/value heads
    out = packed_attention(q, *kv, packed_rows(jnp.asarray(ROWS), 4), implementation=None)
    for b, row in enumerate(ROWS):
        for seg in set(row.tolist()) - {0}:
            idx = np.flatnonzero(row == seg)
            alone = jax.nn.dot_product_attention(q[b:b + 1, idx], kv[0][b:b + 1, idx], kv[1][b:b + 1, idx],
                                                 is_causal=True)
            np.testing.assert_allclose(out[b, idx], alone[0], rtol=1e-5, atol=1e-6)
