"""Rotary position embeddings of Qwen3-VL and the multimodal (t, h, w) position ids of the text.

Text: each token has three position ids (temporal, height, width). Text tokens carry the same
number in all three; the merged patches of an image carry ``start + (t, row, col)``, and the text
after an image continues at ``start + max(h, w) / merge``. The rotary frequencies are split
between the three axes *interleaved*: frequency j uses the h id when ``j % 3 == 1`` and
``j < 3 * section[1]``, the w id when ``j % 3 == 2`` and ``j < 3 * section[2]``, else the t id.

Everything here is plain ``jnp`` on arrays, so it runs inside ``jit`` with the image grids as
traced values (no recompilation per image size).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from jax3dc.model.prefix import prefix_max, prefix_sum


def rotate_half(x: jax.Array) -> jax.Array:
    half = x.shape[-1] // 2
    return jnp.concatenate([-x[..., half:], x[..., :half]], axis=-1)


def apply_rotary(x: jax.Array, cos: jax.Array, sin: jax.Array) -> jax.Array:
    """Rotates ``x [..., seq, heads, head_dim]`` by angles given as ``cos/sin [..., seq, head_dim]``
    (in float32, then back to x's dtype, as transformers does)."""
    xf = x.astype(jnp.float32)
    cos, sin = cos[..., None, :], sin[..., None, :]
    return (xf * cos + rotate_half(xf) * sin).astype(x.dtype)


def mrope_axis_of_frequency(head_dim: int, section: tuple[int, int, int]) -> np.ndarray:
    """For each of the ``head_dim // 2`` frequencies, which position axis (0=t, 1=h, 2=w) drives it."""
    j = np.arange(head_dim // 2)
    axis = np.zeros_like(j)
    axis[(j % 3 == 1) & (j < 3 * section[1])] = 1
    axis[(j % 3 == 2) & (j < 3 * section[2])] = 2
    return axis


def text_rope(position_ids: jax.Array, head_dim: int, theta: float,
              section: tuple[int, int, int]) -> tuple[jax.Array, jax.Array]:
    """cos, sin ``[B, L, head_dim]`` (float32) for ``position_ids [3, B, L]``."""
    inv_freq = 1.0 / (theta ** (np.arange(0, head_dim, 2, dtype=np.float32) / head_dim))
    axis = mrope_axis_of_frequency(head_dim, section)
    # pick, per frequency, the position id of its axis: [B, L, head_dim/2]
    pos = jnp.moveaxis(position_ids.astype(jnp.float32), 0, -1)[..., axis]
    freqs = pos * jnp.asarray(inv_freq)
    emb = jnp.concatenate([freqs, freqs], axis=-1)
    return jnp.cos(emb), jnp.sin(emb)


def vision_rope(rows: jax.Array, cols: jax.Array, head_dim: int,
                theta: float) -> tuple[jax.Array, jax.Array]:
    """cos, sin ``[N, head_dim]`` of the 2-D axial rotary embedding of patches at (row, col):
    the first quarter of the frequencies rotate by row, the second by column, then repeated."""
    spatial = head_dim // 2
    inv_freq = 1.0 / (theta ** (np.arange(0, spatial, 2, dtype=np.float32) / spatial))
    fr = rows.astype(jnp.float32)[:, None] * inv_freq
    fc = cols.astype(jnp.float32)[:, None] * inv_freq
    hw = jnp.concatenate([fr, fc], axis=-1)
    emb = jnp.concatenate([hw, hw], axis=-1)
    return jnp.cos(emb), jnp.sin(emb)


def get_rope_index(input_ids: jax.Array, image_grid_thw: jax.Array | None, image_token_id: int,
                   spatial_merge_size: int,
                   attention_mask: jax.Array | None = None) -> tuple[jax.Array, jax.Array]:
    """Multimodal position ids ``[3, B, L]`` and ``rope_deltas [B]`` exactly as transformers'
    ``Qwen3VLModel.get_rope_index`` computes them for text and images (several per row allowed).

    A run of consecutive image tokens is one image; images are taken from ``image_grid_thw``
    in row-major order over the batch (the order of ``pixel_values``). Padding (attention_mask 0)
    takes no position and gets id 0. ``rope_deltas = max position + 1 - number of real tokens``:
    the offset between a token's position id and its index among real tokens, used when decoding.
    """
    b, seq = input_ids.shape
    valid = jnp.ones((b, seq), bool) if attention_mask is None else attention_mask.astype(bool)
    idx = jnp.broadcast_to(jnp.arange(seq), (b, seq))
    if image_grid_thw is None:
        is_img = jnp.zeros((b, seq), bool)
        grid = jnp.ones((1, 3), jnp.int32)
    else:
        is_img = (input_ids == image_token_id) & valid
        grid = jnp.asarray(image_grid_thw, jnp.int32).reshape(-1, 3)
    # an image starts where an image token follows a non-image real token
    prev_img = jnp.concatenate([jnp.zeros((b, 1), bool), is_img[:, :-1]], axis=1)
    starts = is_img & ~prev_img
    image_of_token = prefix_sum(starts.reshape(-1)).reshape(b, seq) - 1
    image_of_token = jnp.clip(image_of_token, 0, grid.shape[0] - 1)
    g = grid[image_of_token]  # [B, L, 3]
    gh, gw = g[..., 1] // spatial_merge_size, g[..., 2] // spatial_merge_size
    advance = jnp.where(is_img, jnp.where(starts, jnp.maximum(gh, gw), 0), valid.astype(jnp.int32))
    before = prefix_sum(advance, axis=1) - advance  # position counter just before each token
    run_start = prefix_max(jnp.where(starts, idx, 0), axis=1)
    k = idx - run_start  # index of the token within its image
    start = jnp.take_along_axis(before, run_start, axis=1)
    plane = jnp.maximum(gh * gw, 1)  # frames of a video advance the temporal id through k // plane
    img_pos = jnp.stack([start + k // plane,
                         start + (k % plane) // jnp.maximum(gw, 1),
                         start + k % jnp.maximum(gw, 1)])
    text_pos = jnp.broadcast_to(before, (3, b, seq))
    pos = jnp.where(is_img[None], img_pos, text_pos)
    pos = jnp.where(valid[None], pos, 0).astype(jnp.int32)
    n_real = valid.sum(axis=1)
    max_pos = jnp.max(jnp.where(valid[None], pos, -1), axis=(0, 2))
    deltas = jnp.where(n_real > 0, max_pos + 1 - n_real, 0).astype(jnp.int32)
    return pos, deltas
