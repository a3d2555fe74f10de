"""Batched autoregressive generation: a jitted prefill, then a jitted ``lax.while_loop`` decode.

Prompts of different lengths are left-padded (:func:`left_pad`) so every row's last prompt token
sits in the same column and all rows decode in lock-step into one KV cache (layout in
qwen3_vl.py). The loop stops when every row has produced a stop token or ``max_new_tokens``
tokens; a finished row keeps stepping (the batch is one array) but its outputs are ``pad_id``,
as in transformers' ``generate``.

Sampling: ``temperature == 0`` is greedy (argmax); otherwise logits are divided by the
temperature, optionally cut to the smallest set of tokens whose probability reaches ``top_p``,
and sampled. The key for step ``i`` is ``fold_in(key, i)``; a sampled row therefore depends on
the batch it is in (greedy rows do not). ``greedy`` rows (a [B] bool) take the argmax even when
the config samples, so one batch can hold a greedy answer beside sampled candidates.

``constraint`` (``jax3dc.constrained``): grammar tables and per-row state on the device; each
step masks the logits to the tokens the grammar allows and advances the rows by the chosen token,
inside the same loop (no host round trip). ``Generated.logprobs`` is the model's own
log-likelihood of each row's tokens (unmasked, temperature 1), for ranking candidates.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from functools import partial
from typing import NamedTuple, Sequence

import jax
import jax.numpy as jnp
import numpy as np
from flax import nnx

from jax3dc.constrained import Constraint, parameters, program, structure
from jax3dc.model.qwen3_vl import KVCache
from jax3dc.processing.tokenizer import QWEN_VL_SPECIAL_IDS


@dataclass(frozen=True)
class GenerationConfig:
    """How to decode; hashable, so it is a static argument of the jitted loop."""

    max_new_tokens: int = 512
    temperature: float = 0.0  # 0 -> greedy
    top_p: float = 1.0  # nucleus size; 1.0 keeps the whole distribution
    stop_ids: tuple[int, ...] = (QWEN_VL_SPECIAL_IDS["<|im_end|>"], QWEN_VL_SPECIAL_IDS["<|endoftext|>"])
    pad_id: int = QWEN_VL_SPECIAL_IDS["<|endoftext|>"]

    def __post_init__(self):
        if self.max_new_tokens < 1:
            raise ValueError(f"max_new_tokens must be >= 1, got {self.max_new_tokens}")
        if self.temperature < 0:
            raise ValueError(f"temperature must be >= 0, got {self.temperature}")
        if not 0.0 < self.top_p <= 1.0:
            raise ValueError(f"top_p must be in (0, 1], got {self.top_p}")

    def replace(self, **changes) -> "GenerationConfig":
        return dataclasses.replace(self, **changes)


class Generated(NamedTuple):
    """``tokens [B, max_new_tokens]`` (``pad_id`` after a row's stop token), ``lengths [B]``:
    tokens produced per row, the stop token included, and ``logprobs [B]``: their summed log-probability."""

    tokens: jax.Array
    lengths: jax.Array
    logprobs: jax.Array


class Prefilled(NamedTuple):
    """What the decode loop starts from: last-token logits, the filled cache, rope offsets."""

    logits: jax.Array  # [B, V]
    cache: KVCache
    rope_deltas: jax.Array  # [B]


def left_pad(prompts: Sequence[Sequence[int]], pad_id: int, multiple: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Stack prompts right-aligned: ``(input_ids [B, L], attention_mask [B, L])`` int32.

    ``L`` is the longest prompt rounded up to ``multiple`` (fewer distinct shapes, fewer compiles).
    """
    if not prompts:
        raise ValueError("no prompts")
    longest = max(len(p) for p in prompts)
    if longest == 0:
        raise ValueError("empty prompt")
    width = -(-longest // multiple) * multiple
    ids = np.full((len(prompts), width), pad_id, dtype=np.int32)
    mask = np.zeros((len(prompts), width), dtype=np.int32)
    for row, prompt in enumerate(prompts):
        if len(prompt):
            ids[row, width - len(prompt):] = np.asarray(prompt, dtype=np.int32)
            mask[row, width - len(prompt):] = 1
    return ids, mask


def sample_token(logits: jax.Array, key: jax.Array, temperature: float, top_p: float,
                 greedy: jax.Array | None = None) -> jax.Array:
    """Next token per row ``[B]`` from ``logits [B, V]`` (temperature and top_p are static;
    ``greedy [B]`` rows take the argmax whatever the temperature)."""
    logits = logits.astype(jnp.float32)
    best = jnp.argmax(logits, axis=-1).astype(jnp.int32)
    if temperature == 0.0:
        return best
    if greedy is not None:
        return jnp.where(greedy, best, sample_token(logits, key, temperature, top_p))
    logits = logits / temperature
    if top_p < 1.0:
        ordered = jnp.sort(logits, axis=-1)[:, ::-1]
        probs = jax.nn.softmax(ordered, axis=-1)
        mass_before = jnp.cumsum(probs, axis=-1) - probs
        kept = jnp.sum(mass_before < top_p, axis=-1)  # >= 1: the top token always survives
        threshold = jnp.take_along_axis(ordered, (kept - 1)[:, None], axis=-1)
        logits = jnp.where(logits >= threshold, logits, -jnp.inf)
    return jax.random.categorical(key, logits, axis=-1).astype(jnp.int32)


@partial(jax.jit, static_argnames=("graphdef", "capacity", "vision_window"))
def _prefill(graphdef, state, input_ids, attention_mask, pixel_values, image_grid_thw, capacity: int,
             vision_window: int | None) -> Prefilled:
    model = nnx.merge(graphdef, state)
    logits, cache, deltas = model.prefill(input_ids, attention_mask, pixel_values, image_grid_thw, max_length=capacity,
                                          vision_window=vision_window)
    return Prefilled(logits, cache, deltas)


class _Out(NamedTuple):
    """What the decode loop writes per row."""

    tokens: jax.Array
    lengths: jax.Array
    logprobs: jax.Array
    done: jax.Array


@partial(jax.jit, static_argnames=("graphdef", "config"), donate_argnames=("cache",))
def _decode(graphdef, state, logits: jax.Array, cache, rope_deltas: jax.Array, key: jax.Array,
            config: GenerationConfig, greedy: jax.Array | None, constraint: Constraint | None) -> tuple[Generated, KVCache]:
    """Returns the final cache too, only so the donated prefill cache can alias it in place."""
    model = nnx.merge(graphdef, state)
    batch = logits.shape[0]
    stop_ids = jnp.asarray(config.stop_ids, jnp.int32)

    grammar = {program.Tables: program, parameters.Tables: parameters}.get(type(constraint and constraint.tables), structure)

    def emit(step, logits, out: _Out, rows):
        logits = logits.astype(jnp.float32)
        if rows is not None:
            mask = grammar.allowed(constraint.tables, rows, config.max_new_tokens - step)
            choose_from = jnp.where(mask, logits, -jnp.inf)
        else:
            choose_from = logits
        token = sample_token(choose_from, jax.random.fold_in(key, step), config.temperature, config.top_p, greedy)
        token = jnp.where(out.done, config.pad_id, token)
        if rows is not None:
            rows = grammar.advance(constraint.tables, rows, token, config.max_new_tokens - step)
        logprob = jnp.take_along_axis(jax.nn.log_softmax(logits, axis=-1), token[:, None], axis=1)[:, 0]
        out = _Out(out.tokens.at[:, step].set(token), out.lengths + (~out.done).astype(jnp.int32),
                   out.logprobs + jnp.where(out.done, 0.0, logprob), out.done | jnp.isin(token, stop_ids))
        return token, out, rows

    out = _Out(jnp.full((batch, config.max_new_tokens), config.pad_id, jnp.int32), jnp.zeros((batch,), jnp.int32),
               jnp.zeros((batch,), jnp.float32), jnp.zeros((batch,), bool))
    rows = None if constraint is None else constraint.rows
    token, out, rows = emit(0, logits, out, rows)

    def cond(carry):
        step, _, _, out, _ = carry
        return (step < config.max_new_tokens) & ~jnp.all(out.done)

    def body(carry):
        step, token, cache, out, rows = carry
        logits, cache = model.decode_step(token, cache, rope_deltas)
        token, out, rows = emit(step, logits, out, rows)
        return step + 1, token, cache, out, rows

    carry = (jnp.asarray(1, jnp.int32), token, cache, out, rows)
    _, _, cache, out, _ = jax.lax.while_loop(cond, body, carry)
    return Generated(out.tokens, out.lengths, out.logprobs), cache


CACHE_MULTIPLE = 128


def cache_capacity(prompt_length: int, max_new_tokens: int) -> int:
    """Slots needed — the prompt plus every generated token but the last (it is never fed back) —
    rounded up to a multiple of CACHE_MULTIPLE. Why round: XLA pads the sequence axis of bf16
    attention matmuls to a multiple of 8, which on an odd-sized cache copied every layer's keys and
    values once per decode step (0.14 ms of 4.1 ms at 4B, batch 1). Unused slots stay masked."""
    needed = prompt_length + max_new_tokens - 1
    return -(-needed // CACHE_MULTIPLE) * CACHE_MULTIPLE


def prefill(model, input_ids, attention_mask=None, pixel_values=None, image_grid_thw=None,
            max_new_tokens: int = 512, vision_window: int | None = None) -> Prefilled:
    """Jitted prompt pass with a cache sized for ``max_new_tokens`` more tokens.

    ``vision_window`` (>= the largest image's patch count) makes each image attend only to itself:
    without it, vision attention over a batch of images is quadratic in all their patches."""
    graphdef, state = nnx.split(model)
    input_ids = jnp.asarray(input_ids, jnp.int32)
    if attention_mask is None:
        attention_mask = jnp.ones_like(input_ids)
    capacity = cache_capacity(input_ids.shape[1], max_new_tokens)
    return _prefill(graphdef, state, input_ids, jnp.asarray(attention_mask, jnp.int32),
                    None if pixel_values is None else jnp.asarray(pixel_values),
                    None if image_grid_thw is None else jnp.asarray(image_grid_thw, jnp.int32), capacity,
                    vision_window)


def decode(model, prefilled: Prefilled, config: GenerationConfig = GenerationConfig(),
           key: jax.Array | None = None, greedy=None, constraint: Constraint | None = None) -> Generated:
    """Jitted decode loop from a prefilled cache (the cache buffers are donated); ``greedy [B]``
    and ``constraint``: see the module docstring."""
    needed = int(prefilled.cache.length) + config.max_new_tokens - 1
    if needed > prefilled.cache.valid.shape[1]:
        raise ValueError(f"cache holds {prefilled.cache.valid.shape[1]} slots, {config.max_new_tokens} new tokens "
                         f"need {needed}: prefill with max_new_tokens >= {config.max_new_tokens}")
    graphdef, state = nnx.split(model)
    key = jax.random.key(0) if key is None else key
    greedy = None if greedy is None else jnp.asarray(greedy, bool)
    generated, _ = _decode(graphdef, state, prefilled.logits, prefilled.cache, prefilled.rope_deltas, key, config,
                           greedy, constraint)
    return generated


def repeat_rows(prefilled: Prefilled, times: int) -> Prefilled:
    """Each row ``times`` times in a row (candidates of one prompt share its prompt pass)."""
    rep = lambda x: jnp.repeat(x, times, axis=0)  # noqa: E731
    cache = prefilled.cache._replace(keys=tuple(rep(k) for k in prefilled.cache.keys),
                                     values=tuple(rep(v) for v in prefilled.cache.values), valid=rep(prefilled.cache.valid))
    return Prefilled(rep(prefilled.logits), cache, rep(prefilled.rope_deltas))


def split_rows(input_ids: np.ndarray, image_grid_thw: np.ndarray | None, image_token_id: int,
               merge_size: int) -> list[tuple[int, int]]:
    """Per row, the [first, end) range of its images in ``image_grid_thw`` (images are in row order)."""
    if image_grid_thw is None:
        return [(0, 0)] * input_ids.shape[0]
    tokens_per_image = np.prod(np.asarray(image_grid_thw).reshape(-1, 3), axis=1) // merge_size**2
    ranges, image = [], 0
    for row in np.asarray(input_ids):
        needed, first = int(np.sum(row == image_token_id)), image
        while needed > 0:
            if image >= len(tokens_per_image):
                raise ValueError("more image tokens in input_ids than images in image_grid_thw")
            needed -= int(tokens_per_image[image])
            image += 1
        if needed < 0:
            raise ValueError("image tokens of a row do not add up to whole images")
        ranges.append((first, image))
    if image != len(tokens_per_image):
        raise ValueError(f"{len(tokens_per_image) - image} image(s) have no image tokens in input_ids")
    return ranges


def prefill_in_chunks(model, input_ids, attention_mask, pixel_values, image_grid_thw, max_new_tokens: int,
                      rows_per_chunk: int) -> Prefilled:
    """Prefill ``rows_per_chunk`` rows at a time and join the caches: bounds the memory of the
    prompt pass (vision attention and [B, heads, L, S] scores) for large batches."""
    input_ids = np.asarray(input_ids)
    attention_mask = np.ones_like(input_ids) if attention_mask is None else np.asarray(attention_mask)
    config = model.config
    ranges = split_rows(input_ids, None if image_grid_thw is None else np.asarray(image_grid_thw),
                        config.image_token_id, config.vision.spatial_merge_size)
    grid = None if image_grid_thw is None else np.asarray(image_grid_thw).reshape(-1, 3)
    patch_starts = None if grid is None else np.concatenate([[0], np.cumsum(np.prod(grid, axis=1))])
    parts = []
    for lo in range(0, input_ids.shape[0], rows_per_chunk):
        hi = min(lo + rows_per_chunk, input_ids.shape[0])
        first, end = ranges[lo][0], ranges[hi - 1][1]
        pixels = chunk_grid = None
        if grid is not None and end > first:
            pixels = np.asarray(pixel_values)[patch_starts[first]:patch_starts[end]]
            chunk_grid = grid[first:end]
        parts.append(prefill(model, input_ids[lo:hi], attention_mask[lo:hi], pixels, chunk_grid, max_new_tokens))
    if len(parts) == 1:
        return parts[0]
    join = lambda *xs: jnp.concatenate(xs, axis=0)  # noqa: E731
    cache = parts[0].cache._replace(
        keys=tuple(join(*layer) for layer in zip(*(p.cache.keys for p in parts))),
        values=tuple(join(*layer) for layer in zip(*(p.cache.values for p in parts))),
        valid=join(*(p.cache.valid for p in parts)))
    return Prefilled(join(*(p.logits for p in parts)), cache, join(*(p.rope_deltas for p in parts)))
