"""The Qwen3-VL vision tower: patches of several images in, LLM-width tokens and DeepStack features out.

Input is transformers' packed layout: ``pixel_values [N, C*T*P*P]`` holds the patches of all
images one after another, each image's patches in spatial-merge-block order (every
``merge x merge`` block of neighbouring patches is consecutive), and ``grid_thw [n_images, 3]``
gives each image's grid of patches. ``N`` may exceed the patches the grids account for: the
rest is padding (its outputs are garbage and never used), so a fixed patch budget compiles once.

Each frame of each image attends only to itself (block-diagonal attention). The grid is used as
a traced array: a new image size does not recompile.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np
from flax import nnx

from jax3dc.model.config import VisionConfig
from jax3dc.model.layers import Dense, LayerNorm, activation
from jax3dc.model.rope import apply_rotary, vision_rope
from jax3dc.sharding import constrain


@dataclass(frozen=True)
class PatchLayout:
    """Per-patch facts derived from the grids (all ``[N]`` or ``[N, 4]``, traceable)."""

    segment: jax.Array  # attention segment (one per frame of each image; padding: its own)
    index_in_frame: jax.Array  # position of the patch in its frame's packed order
    row: jax.Array  # patch row within its image
    col: jax.Array  # patch column within its image
    interp_index: jax.Array  # [N, 4] taps into the learned position table
    interp_weight: jax.Array  # [N, 4] bilinear weights


def patch_layout(grid_thw: jax.Array, num_patches: int, merge: int, side: int) -> PatchLayout:
    """Where each packed patch sits: its image frame, (row, col), and the bilinear taps that
    resample the ``side x side`` learned position table to its image's grid (align_corners)."""
    grid = jnp.asarray(grid_thw, jnp.int32).reshape(-1, 3)
    t, h, w = grid[:, 0], grid[:, 1], grid[:, 2]
    counts = t * h * w
    ends = jnp.cumsum(counts)
    i = jnp.arange(num_patches, dtype=jnp.int32)
    image = jnp.searchsorted(ends, i, side="right").astype(jnp.int32)
    is_pad = image >= grid.shape[0]
    img = jnp.minimum(image, grid.shape[0] - 1)
    start = (ends - counts)[img]
    hw = h[img] * w[img]
    frame = (i - start) // hw
    within = (i - start) % hw
    frame_offset = (jnp.cumsum(t) - t)[img]
    total_frames = jnp.sum(t)
    segment = jnp.where(is_pad, total_frames, frame_offset + frame)
    blocks_w = w[img] // merge
    in_col = within % merge
    in_row = (within // merge) % merge
    block_col = (within // (merge * merge)) % blocks_w
    block_row = within // (merge * merge * blocks_w)
    row = block_row * merge + in_row
    col = block_col * merge + in_col

    def taps(index, size):
        src = index.astype(jnp.float32) * (side - 1) / jnp.maximum(size - 1, 1).astype(jnp.float32)
        lo = jnp.floor(src)
        off = jnp.arange(2, dtype=jnp.float32)
        tap = jnp.clip(lo[:, None].astype(jnp.int32) + off.astype(jnp.int32), 0, side - 1)
        weight = jnp.clip(1.0 - jnp.abs(src[:, None] - lo[:, None] - off), 0.0, None)
        return tap, weight

    h_tap, h_w = taps(row, h[img])
    w_tap, w_w = taps(col, w[img])
    index = (h_tap[:, :, None] * side + w_tap[:, None, :]).reshape(-1, 4)
    weight = (h_w[:, :, None] * w_w[:, None, :]).reshape(-1, 4)
    return PatchLayout(segment, within, row, col, index, weight)


@dataclass(frozen=True)
class AttentionPlan:
    """Which patches attend to which. Without ``slot``: one block-diagonal ``mask [1, 1, N, N]``.
    With ``slot``: each frame's patches are scattered into their own row of ``window`` slots
    (patch -> ``slot``; out of range = padding, dropped) and attend there under
    ``mask [frames, 1, window, window]``: cost ``frames * window²`` instead of ``N²``."""

    mask: jax.Array
    slot: jax.Array | None = None


def attention_plan(layout: PatchLayout, n_frames: int, window: int | None) -> AttentionPlan:
    seg = layout.segment
    if window is None:
        return AttentionPlan((seg[:, None] == seg[None, :])[None, None])
    inside = (seg < n_frames) & (layout.index_in_frame < window)
    slot = jnp.where(inside, seg * window + layout.index_in_frame, n_frames * window)
    filled = jnp.zeros(n_frames * window, bool).at[slot].set(True, mode="drop").reshape(n_frames, window)
    mask = filled[:, None, :] | jnp.eye(window, dtype=bool)[None]  # empty slots see themselves only
    return AttentionPlan(mask[:, None], slot)


class VisionAttention(nnx.Module):
    def __init__(self, cfg: VisionConfig, *, rngs: nnx.Rngs, dtype, param_dtype, attention_impl):
        d, n, hd = cfg.hidden_size, cfg.num_heads, cfg.head_dim
        kw = dict(rngs=rngs, dtype=dtype, param_dtype=param_dtype)
        self.qkv = Dense((d,), (3, n, hd), ("vision_embed",), ("qkv", "vision_heads", "head_dim"), use_bias=True, **kw)
        self.proj = Dense((n, hd), (d,), ("vision_heads", "head_dim"), ("vision_embed",), use_bias=True, **kw)
        self.attention_impl = attention_impl

    def __call__(self, x: jax.Array, cos: jax.Array, sin: jax.Array, plan: AttentionPlan) -> jax.Array:
        qkv = self.qkv(x)  # [N, 3, heads, hd]
        q, k, v = qkv[:, 0], qkv[:, 1], qkv[:, 2]
        q, k = apply_rotary(q, cos, sin), apply_rotary(k, cos, sin)
        if plan.slot is None:
            out = jax.nn.dot_product_attention(q[None], k[None], v[None], mask=plan.mask,
                                               implementation=self.attention_impl)[0]
        else:
            frames, window = plan.mask.shape[0], plan.mask.shape[-1]

            def rows(a):
                flat = jnp.zeros((frames * window, *a.shape[1:]), a.dtype).at[plan.slot].set(a, mode="drop")
                return flat.reshape(frames, window, *a.shape[1:])

            out = jax.nn.dot_product_attention(rows(q), rows(k), rows(v), mask=plan.mask,
                                               implementation=self.attention_impl)
            out = out.reshape(frames * window, *out.shape[2:])[jnp.minimum(plan.slot, frames * window - 1)]
        return self.proj(out)


class VisionMLP(nnx.Module):
    def __init__(self, cfg: VisionConfig, *, rngs: nnx.Rngs, dtype, param_dtype):
        kw = dict(rngs=rngs, dtype=dtype, param_dtype=param_dtype, use_bias=True)
        self.linear_fc1 = Dense((cfg.hidden_size,), (cfg.intermediate_size,), ("vision_embed",), ("vision_mlp",), **kw)
        self.linear_fc2 = Dense((cfg.intermediate_size,), (cfg.hidden_size,), ("vision_mlp",), ("vision_embed",), **kw)
        self.act = activation(cfg.hidden_act)

    def __call__(self, x: jax.Array) -> jax.Array:
        return self.linear_fc2(self.act(self.linear_fc1(x)))


class VisionBlock(nnx.Module):
    def __init__(self, cfg: VisionConfig, *, rngs: nnx.Rngs, dtype, param_dtype, attention_impl):
        kw = dict(dtype=dtype, param_dtype=param_dtype)
        self.norm1 = LayerNorm(cfg.hidden_size, "vision_embed", **kw)
        self.norm2 = LayerNorm(cfg.hidden_size, "vision_embed", **kw)
        self.attn = VisionAttention(cfg, rngs=rngs, attention_impl=attention_impl, **kw)
        self.mlp = VisionMLP(cfg, rngs=rngs, **kw)

    def __call__(self, x, cos, sin, plan: AttentionPlan):
        x = x + self.attn(self.norm1(x), cos, sin, plan)
        return x + self.mlp(self.norm2(x))


class PatchMerger(nnx.Module):
    """Concatenates each merge block's patches and maps them to the LLM width. The DeepStack
    mergers normalise after concatenation (``postshuffle``), the final merger before."""

    def __init__(self, cfg: VisionConfig, postshuffle_norm: bool, *, rngs: nnx.Rngs, dtype, param_dtype):
        self.merged = cfg.hidden_size * cfg.spatial_merge_size**2
        self.postshuffle_norm = postshuffle_norm
        kw = dict(dtype=dtype, param_dtype=param_dtype)
        self.norm = LayerNorm(self.merged if postshuffle_norm else cfg.hidden_size, "vision_embed", **kw)
        self.linear_fc1 = Dense((self.merged,), (self.merged,), ("vision_embed",), ("vision_merged",),
                                use_bias=True, rngs=rngs, **kw)
        self.linear_fc2 = Dense((self.merged,), (cfg.out_hidden_size,), ("vision_merged",), ("embed",),
                                use_bias=True, rngs=rngs, **kw)

    def __call__(self, x: jax.Array) -> jax.Array:
        if self.postshuffle_norm:
            x = self.norm(x.reshape(-1, self.merged))
        else:
            x = self.norm(x).reshape(-1, self.merged)
        return self.linear_fc2(jax.nn.gelu(self.linear_fc1(x), approximate=False))


class VisionModel(nnx.Module):
    """``__call__(pixel_values, grid_thw, window=None) -> (tokens [N/merge², out], [deepstack …])``.

    ``window`` (static int, images only: every grid has t = 1) must be at least the patches of
    the largest image (784 for 448 x 448 at patch 16); then each image attends in its own row
    of ``window`` slots, costing ``n_images * window²`` instead of ``N²`` for the packed batch.
    Patches beyond ``window`` would be dropped: the bound is checked when the grid is concrete.
    """

    def __init__(self, cfg: VisionConfig, *, rngs: nnx.Rngs, dtype=jnp.float32, param_dtype=jnp.float32,
                 attention_impl: str | None = None):
        self.cfg = cfg
        self.dtype = dtype
        kw = dict(dtype=dtype, param_dtype=param_dtype)
        self.patch_embed = Dense((cfg.patch_dim,), (cfg.hidden_size,), ("vision_patch",), ("vision_embed",),
                                 use_bias=True, rngs=rngs, **kw)
        self.pos_embed = nnx.Param(
            (0.02 * jax.random.normal(rngs.params(), (cfg.num_position_embeddings, cfg.hidden_size))).astype(param_dtype),
            logical_axes=("vision_positions", "vision_embed"))
        self.blocks = nnx.List([VisionBlock(cfg, rngs=rngs, attention_impl=attention_impl, **kw)
                                for _ in range(cfg.depth)])
        self.merger = PatchMerger(cfg, postshuffle_norm=False, rngs=rngs, **kw)
        self.deepstack_merger_list = nnx.List([PatchMerger(cfg, postshuffle_norm=True, rngs=rngs, **kw)
                                               for _ in cfg.deepstack_visual_indexes])

    @staticmethod
    def _check_window(grid_thw, window: int) -> None:
        """Under jit the grid is abstract and this check cannot run; eagerly it does."""
        try:
            g = np.asarray(grid_thw).reshape(-1, 3)
        except jax.errors.TracerArrayConversionError:
            return
        if (g[:, 0] != 1).any() or (g[:, 1] * g[:, 2]).max() > window:
            raise ValueError(f"vision window {window} needs single-frame images of at most {window} "
                             f"patches, got grids {g.tolist()}")

    def __call__(self, pixel_values: jax.Array, grid_thw: jax.Array,
                 window: int | None = None) -> tuple[jax.Array, list[jax.Array]]:
        cfg = self.cfg
        n = pixel_values.shape[0]
        if pixel_values.shape[-1] != cfg.patch_dim or n % cfg.spatial_merge_size**2:
            raise ValueError(f"pixel_values must be [N, {cfg.patch_dim}] with N a multiple of "
                             f"{cfg.spatial_merge_size**2}, got {pixel_values.shape}")
        if window is not None:
            self._check_window(grid_thw, window)
        layout = patch_layout(grid_thw, n, cfg.spatial_merge_size, cfg.num_grid_per_side)
        x = self.patch_embed(pixel_values)
        table = self.pos_embed.get_value().astype(jnp.float32)
        pos = jnp.sum(table[layout.interp_index] * layout.interp_weight[..., None], axis=1)
        x = constrain(x + pos.astype(x.dtype), ("patches", "act_embed"))
        cos, sin = vision_rope(layout.row, layout.col, cfg.head_dim, cfg.rope_theta)
        plan = attention_plan(layout, jnp.shape(grid_thw)[0], window)
        deepstack = []
        for i, block in enumerate(self.blocks):
            x = block(x, cos, sin, plan)
            if i in cfg.deepstack_visual_indexes:
                merger = self.deepstack_merger_list[cfg.deepstack_visual_indexes.index(i)]
                deepstack.append(merger(x))
        return self.merger(x), deepstack
