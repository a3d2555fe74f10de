"""Qwen3-VL (image + text -> next-token logits) in Flax NNX, numerically matching transformers.

Forward pass (training / scoring)::

    model = Qwen3VL(config, rngs=nnx.Rngs(0), dtype=jnp.bfloat16, param_dtype=jnp.float32)
    logits = model(input_ids, attention_mask=None, pixel_values=None, image_grid_thw=None)  # [B, L, V]

* ``input_ids [B, L]`` int; image placeholders are ``config.image_token_id``, one per merged
  patch (``t*h*w / merge²`` per image), images in the same order as in ``pixel_values``.
* ``attention_mask [B, L]`` (1 real, 0 padding; left or right padding). ``None`` = no padding
  (then the causal mask is implicit, which lets cuDNN flash attention run on GPU).
* ``pixel_values [N, C*T*P*P]`` and ``image_grid_thw [n_images, 3]``: transformers' processor
  output (see vision.py; N may be padded to a fixed budget).
* ``position_ids [3, B, L]`` optional; computed like transformers' ``get_rope_index`` if absent.
* ``vision_window`` (static int >= the patches of the largest image; images only): each image
  attends in its own window instead of over all packed patches (see vision.py). Leave it
  ``None`` only for few images: full packed attention costs ``N²`` for N patches in the batch.
* Right-padded batches (training) may pass ``attention_mask=None``: real tokens never attend to
  the padding after them, so their logits are unchanged, and attention stays purely causal.
* Packed training rows (several examples per row, see data_pipeline/packing.py): ``segment_ids
  [B, L]`` (1.. per example, 0 padding) restrict attention to each example, and
  ``images_per_row`` (static) says that row b owns images ``b*k .. b*k+k-1`` of the grid list,
  so a row that leaves image slots unused does not shift the next row's features. Give
  ``position_ids`` with them (each example's own, restarting at 0).
* ``return_hidden=True`` returns the final-norm hidden states ``[B, L, E]`` instead of logits
  (use ``model.logits(hidden)`` on chunks to bound memory for the 151936-word vocabulary).

Generation with a KV cache (jit-friendly: fixed shapes, no Python control flow on values)::

    logits, cache, rope_deltas = model.prefill(input_ids, attention_mask, pixel_values,
                                               image_grid_thw, max_length=S)
    # logits [B, V]: for each row's LAST REAL token (left or right padding both fine)
    logits, cache = model.decode_step(tokens, cache, rope_deltas)   # tokens [B] -> logits [B, V]

``KVCache`` (a NamedTuple pytree):

* ``keys``, ``values``: tuple over decoder layers of ``[B, S, kv_heads, head_dim]`` arrays in the
  model's compute dtype. ``S = max_length`` is the capacity: prompt length + new tokens.
* ``valid [B, S]`` bool: slots holding a real token (prompt padding and unwritten slots False).
* ``length`` int32 scalar: the next slot to write, the same for every row (prefill writes slots
  ``0 .. L-1`` including padding; each decode step writes slot ``length`` then adds 1).

The rotary position of a decoded token is ``valid.sum(-1) + rope_deltas`` (the number of real
tokens before it, shifted by ``rope_deltas [B]`` from ``prefill`` = transformers' ``rope_deltas``:
max multimodal position + 1 - number of real prompt tokens). ``decode_step`` must not be called
once ``length == S`` (the write would be clamped onto the last slot).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from flax import nnx

from jax3dc.model.config import Qwen3VLConfig
from jax3dc.model.layer_stack import remat_policy, scan_layers, stackable
from jax3dc.model.layers import Dense
from jax3dc.model.packed_attention import packed_rows
from jax3dc.model.rope import get_rope_index, text_rope
from jax3dc.model.text import DecoderLayer, TextModel
from jax3dc.model.vision import VisionModel
from jax3dc.model.prefix import prefix_sum
from jax3dc.sharding import constrain


class KVCache(NamedTuple):
    keys: tuple[jax.Array, ...]
    values: tuple[jax.Array, ...]
    valid: jax.Array
    length: jax.Array


def place_image_tokens(x: jax.Array, image_mask: jax.Array, features: jax.Array, add: bool,
                       row_start: jax.Array | None = None) -> jax.Array:
    """Puts feature row k at the k-th image token of the batch (row-major), like transformers'
    ``masked_scatter``; with ``add`` the features are added instead (DeepStack). With
    ``row_start [B]`` the k-th image token of row b takes feature ``row_start[b] + k`` instead,
    so rows with image slots they leave unused (packed training rows) stay aligned."""
    b, seq = image_mask.shape
    if row_start is None:
        order = prefix_sum(image_mask.reshape(-1)) - 1
    else:
        order = (row_start[:, None] + prefix_sum(image_mask, axis=1) - 1).reshape(-1)
    order = jnp.clip(order, 0, features.shape[0] - 1)
    placed = features.astype(x.dtype)[order].reshape(b, seq, -1)
    if add:
        return x + jnp.where(image_mask[..., None], placed, 0)
    return jnp.where(image_mask[..., None], placed, x)


def image_row_starts(image_grid_thw: jax.Array, images_per_row: int, merge: int) -> jax.Array:
    """Index of each row's first image feature when every row owns ``images_per_row`` images."""
    tokens = jnp.prod(jnp.asarray(image_grid_thw).reshape(-1, 3), axis=-1) // merge**2
    return (jnp.cumsum(tokens) - tokens)[::images_per_row]


def _check_image_tokens(input_ids, image_grid_thw, cfg: Qwen3VLConfig) -> None:
    """Placeholders must match the images' merged patches (checked when the inputs are concrete;
    under jit a mismatch cannot be detected and features would be misplaced)."""
    try:
        ids, grid = np.asarray(input_ids), np.asarray(image_grid_thw).reshape(-1, 3)
    except jax.errors.TracerArrayConversionError:
        return
    want = int(grid.prod(-1).sum()) // cfg.vision.spatial_merge_size**2
    have = int((ids == cfg.image_token_id).sum())
    if have != want:
        raise ValueError(f"{have} image tokens in input_ids but the image grids give {want} merged patches")


def _attention_mask(key_valid: jax.Array, q_pos: jax.Array, k_pos: jax.Array) -> jax.Array:
    """[B, 1, T, S]: causal over slots and real keys only; a query always sees its own slot so
    padding rows never have an empty softmax."""
    causal = k_pos[None, :] <= q_pos[:, None]
    mask = causal[None] & key_valid[:, None, :]
    return (mask | (k_pos[None, :] == q_pos[:, None])[None])[:, None]


class Qwen3VL(nnx.Module):
    """Vision tower + DeepStack + Qwen3 decoder + LM head (tied to the embedding or not)."""

    def __init__(self, config: Qwen3VLConfig, *, rngs: nnx.Rngs, dtype=jnp.float32,
                 param_dtype=jnp.float32, attention_impl: str | None = None, remat: str = "none",
                 scan_layers: bool = False):
        remat_policy(remat)  # an unknown policy name fails here, not at the first traced step
        self.config = config
        self.dtype = dtype
        self.remat = remat
        # scan the decoder layers after the DeepStack ones when no KV cache is involved (training
        # and scoring); generation keeps the loop, which threads each layer's cache slice
        self.scan_layers = scan_layers
        self.visual = VisionModel(config.vision, rngs=rngs, dtype=dtype, param_dtype=param_dtype,
                                  attention_impl=attention_impl)
        self.language_model = TextModel(config.text, rngs=rngs, dtype=dtype, param_dtype=param_dtype,
                                        attention_impl=attention_impl)
        t = config.text
        self.lm_head = None if config.tie_word_embeddings else Dense(
            (t.hidden_size,), (t.vocab_size,), ("embed",), ("vocab",), use_bias=False, rngs=rngs,
            dtype=dtype, param_dtype=param_dtype)

    # ------------------------------------------------------------------ pieces
    def output_head(self) -> jax.Array:
        """The LM head as a [vocab, embed] matrix in the compute dtype (the embedding when tied),
        for losses that apply it themselves (train/loss.py)."""
        if self.lm_head is not None:
            return self.lm_head.kernel.get_value().astype(self.dtype).T
        return self.language_model.embed_tokens.get_value().astype(self.dtype)

    def logits(self, hidden: jax.Array) -> jax.Array:
        if self.lm_head is not None:
            out = self.lm_head(hidden)
        else:
            emb = self.language_model.embed_tokens.get_value().astype(self.dtype)
            out = jnp.einsum("...e,ve->...v", hidden.astype(self.dtype), emb)
        return constrain(out, ("batch",) + ("length",) * (out.ndim - 2) + ("act_vocab",))

    def _inputs(self, input_ids, attention_mask, pixel_values, image_grid_thw, position_ids, vision_window,
                images_per_row=None):
        """Embeddings with image features placed, DeepStack features, image mask, rope ids, and
        where each row's image features start (None: row-major over the batch)."""
        cfg = self.config
        x = self.language_model.embed(input_ids)
        image_mask = input_ids == cfg.image_token_id
        deepstack: list[jax.Array] = []
        row_start = None
        if pixel_values is not None:
            if image_grid_thw is None:
                raise ValueError("pixel_values given without image_grid_thw")
            if images_per_row is None:
                _check_image_tokens(input_ids, image_grid_thw, cfg)
            else:
                if position_ids is None:
                    raise ValueError("images_per_row (packed rows) needs the rows' position_ids")
                row_start = image_row_starts(image_grid_thw, images_per_row, cfg.vision.spatial_merge_size)
            tokens, deepstack = self.visual(pixel_values, image_grid_thw, vision_window)
            x = place_image_tokens(x, image_mask, tokens, add=False, row_start=row_start)
        deltas = None
        if position_ids is None:
            position_ids, deltas = get_rope_index(input_ids, image_grid_thw, cfg.image_token_id,
                                                  cfg.vision.spatial_merge_size, attention_mask)
        return x, deepstack, image_mask, position_ids, deltas, row_start

    def _layers(self, x, cos, sin, mask, deepstack, image_mask, caches=None, write_index=None, from_cache=True,
                row_start=None):
        layers = self.language_model.layers
        # the layers that take DeepStack features run one by one; the rest may run as one scan
        unrolled = len(layers)
        if self.scan_layers and caches is None and len(layers) - len(deepstack) > 1 \
                and stackable(layers[len(deepstack):]):
            unrolled = len(deepstack)
        policy = remat_policy(self.remat)
        new_caches = []
        for i in range(unrolled):
            layer, cache = layers[i], None if caches is None else caches[i]
            if self.remat != "none":
                x, cache = nnx.remat(DecoderLayer.__call__, static_argnums=(7,), policy=policy)(
                    layer, x, cos, sin, mask, cache, write_index, from_cache)
            else:
                x, cache = layer(x, cos, sin, mask, cache, write_index, from_cache)
            new_caches.append(cache)
            if i < len(deepstack):
                x = place_image_tokens(x, image_mask, deepstack[i], add=True, row_start=row_start)
        if unrolled < len(layers):
            x = scan_layers(layers[unrolled:], x, lambda layer, h: layer(h, cos, sin, mask)[0], self.remat)
        return self.language_model.norm(x), new_caches

    # ------------------------------------------------------------------ forward
    def __call__(self, input_ids: jax.Array, attention_mask: jax.Array | None = None,
                 pixel_values: jax.Array | None = None, image_grid_thw: jax.Array | None = None,
                 position_ids: jax.Array | None = None, return_hidden: bool = False,
                 vision_window: int | None = None, segment_ids: jax.Array | None = None,
                 images_per_row: int | None = None) -> jax.Array:
        x, deepstack, image_mask, position_ids, _, row_start = self._inputs(
            input_ids, attention_mask, pixel_values, image_grid_thw, position_ids, vision_window, images_per_row)
        t = self.config.text
        cos, sin = text_rope(position_ids, t.head_dim, t.rope_theta, t.mrope_section)
        mask = None
        if segment_ids is not None:  # packed rows: at most one example per image slot
            mask = packed_rows(segment_ids, images_per_row or input_ids.shape[1])
        elif attention_mask is not None:
            pos = jnp.arange(input_ids.shape[1])
            mask = _attention_mask(attention_mask.astype(bool), pos, pos)
        hidden, _ = self._layers(x, cos, sin, mask, deepstack, image_mask, row_start=row_start)
        return hidden if return_hidden else self.logits(hidden)

    # ------------------------------------------------------------------ KV-cache generation
    def init_cache(self, batch: int, max_length: int) -> KVCache:
        t = self.config.text
        shape = (batch, max_length, t.num_key_value_heads, t.head_dim)
        zeros = tuple(jnp.zeros(shape, self.dtype) for _ in range(t.num_hidden_layers))
        return KVCache(zeros, tuple(jnp.zeros(shape, self.dtype) for _ in range(t.num_hidden_layers)),
                       jnp.zeros((batch, max_length), bool), jnp.zeros((), jnp.int32))

    def prefill(self, input_ids: jax.Array, attention_mask: jax.Array | None = None,
                pixel_values: jax.Array | None = None, image_grid_thw: jax.Array | None = None,
                max_length: int | None = None,
                vision_window: int | None = None) -> tuple[jax.Array, KVCache, jax.Array]:
        """Runs the prompt, fills a new cache of capacity ``max_length`` (static) and returns the
        logits of each row's last real token ``[B, V]``, the cache and ``rope_deltas [B]``."""
        b, seq = input_ids.shape
        max_length = seq if max_length is None else max_length
        if max_length < seq:
            raise ValueError(f"max_length {max_length} < prompt length {seq}")
        valid = jnp.ones((b, seq), bool) if attention_mask is None else attention_mask.astype(bool)
        x, deepstack, image_mask, position_ids, deltas, _ = self._inputs(
            input_ids, valid, pixel_values, image_grid_thw, None, vision_window)
        t = self.config.text
        cos, sin = text_rope(position_ids, t.head_dim, t.rope_theta, t.mrope_section)
        cache = self.init_cache(b, max_length)
        mask = _attention_mask(valid, jnp.arange(seq), jnp.arange(seq))
        hidden, layer_caches = self._layers(x, cos, sin, mask, deepstack, image_mask,
                                            list(zip(cache.keys, cache.values)), jnp.zeros((), jnp.int32),
                                            from_cache=False)
        key_valid = jnp.zeros((b, max_length), bool).at[:, :seq].set(valid)
        last = jnp.max(jnp.where(valid, jnp.arange(seq), 0), axis=1)
        last_hidden = jnp.take_along_axis(hidden, last[:, None, None], axis=1)[:, 0]
        cache = KVCache(tuple(k for k, _ in layer_caches), tuple(v for _, v in layer_caches),
                        key_valid, jnp.asarray(seq, jnp.int32))
        return self.logits(last_hidden), cache, deltas

    def decode_step(self, tokens: jax.Array, cache: KVCache,
                    rope_deltas: jax.Array) -> tuple[jax.Array, KVCache]:
        """One new token per row ``[B]`` -> its next-token logits ``[B, V]`` and the updated cache."""
        b, s = cache.valid.shape
        position = cache.valid.sum(axis=1).astype(jnp.int32) + rope_deltas.astype(jnp.int32)
        position_ids = jnp.broadcast_to(position[None, :, None], (3, b, 1))
        t = self.config.text
        cos, sin = text_rope(position_ids, t.head_dim, t.rope_theta, t.mrope_section)
        valid = jax.lax.dynamic_update_slice_in_dim(cache.valid, jnp.ones((b, 1), bool), cache.length, axis=1)
        mask = valid[:, None, None, :]
        x = self.language_model.embed(tokens[:, None])
        hidden, layer_caches = self._layers(x, cos, sin, mask, [], None,
                                            list(zip(cache.keys, cache.values)), cache.length)
        new = KVCache(tuple(k for k, _ in layer_caches), tuple(v for _, v in layer_caches),
                      valid, cache.length + 1)
        return self.logits(hidden[:, 0]), new
