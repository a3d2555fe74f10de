"""Batched generation: left padding, stop tokens, chunked prefill and the samplers."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from flax import nnx

from jax3dc.model.config import Qwen3VLConfig
from jax3dc.generate import GenerationConfig, left_pad, sample_token, split_rows
from jax3dc.model.qwen3_vl import Qwen3VL
from tests.generation import generate

NEW = 12


@pytest.fixture(autouse=True)
def highest_precision():
    with jax.default_matmul_precision("highest"):
        yield


@pytest.fixture(scope="module")
def tiny():
    config = Qwen3VLConfig.tiny()
    return Qwen3VL(config, rngs=nnx.Rngs(3)), config


def image_prompt(config: Qwen3VLConfig, text_before: int, text_after: int, grid, seed: int) -> list[int]:
    rng = np.random.default_rng(seed)
    pads = int(np.prod(grid)) // config.vision.spatial_merge_size**2
    return (rng.integers(0, config.vision_start_token_id, text_before).tolist()
            + [config.vision_start_token_id] + [config.image_token_id] * pads + [config.vision_end_token_id]
            + rng.integers(0, config.vision_start_token_id, text_after).tolist())


def test_left_pad_aligns_prompt_ends() -> None:
    ids, mask = left_pad([[5, 6, 7], [9]], pad_id=0, multiple=4)
    assert ids.tolist() == [[0, 5, 6, 7], [0, 0, 0, 9]]
    assert mask.tolist() == [[0, 1, 1, 1], [0, 0, 0, 1]]


@pytest.mark.slow
def test_batch_of_different_lengths_equals_per_row(tiny) -> None:
    model, config = tiny
    grid = np.array([[1, 4, 4], [1, 4, 6]])
    rng = np.random.default_rng(0)
    pixels = rng.standard_normal((int(grid.prod(1).sum()), config.vision.patch_dim)).astype(np.float32)
    prompts = [
        image_prompt(config, 2, 3, grid[0], seed=1),
        rng.integers(0, config.vision_start_token_id, 4).tolist(),  # text only, shortest
        image_prompt(config, 6, 1, grid[1], seed=2),
    ]
    gen = GenerationConfig(max_new_tokens=NEW, stop_ids=(), pad_id=0)
    ids, mask = left_pad(prompts, pad_id=0)
    batch = generate(model, ids, mask, pixels, grid, config=gen)
    patches = [pixels[:16], None, pixels[16:]]
    grids = [grid[:1], None, grid[1:]]
    for row, prompt in enumerate(prompts):
        alone = generate(model, np.array([prompt]), None, patches[row], grids[row], config=gen)
        np.testing.assert_array_equal(np.asarray(batch.tokens[row]), np.asarray(alone.tokens[0]))
    # the same batch prefilled one row at a time gives the same tokens
    chunked = generate(model, ids, mask, pixels, grid, config=gen, prefill_rows=1)
    np.testing.assert_array_equal(np.asarray(chunked.tokens), np.asarray(batch.tokens))


def test_greedy_tokens_are_the_argmax_of_a_full_forward(tiny) -> None:
    model, config = tiny
    prompt = np.random.default_rng(4).integers(0, config.vision_start_token_id, (1, 7))
    out = generate(model, prompt, config=GenerationConfig(max_new_tokens=NEW, stop_ids=(), pad_id=0))
    tokens = np.asarray(out.tokens[0])
    logits = np.asarray(model(jnp.asarray(np.concatenate([prompt[0], tokens[:-1]])[None], jnp.int32)))
    np.testing.assert_array_equal(logits[0, prompt.shape[1] - 1:].argmax(-1), tokens)


def test_stop_token_ends_a_row_and_pads_the_rest(tiny) -> None:
    model, config = tiny
    rng = np.random.default_rng(5)
    prompts = [rng.integers(0, config.vision_start_token_id, n).tolist() for n in (6, 3)]
    ids, mask = left_pad(prompts, pad_id=0)
    unstopped = GenerationConfig(max_new_tokens=NEW, stop_ids=(), pad_id=0)
    free = np.asarray(generate(model, ids, mask, config=unstopped).tokens)
    stop = int(free[0, 3])
    first = int(np.flatnonzero(free[0] == stop)[0])
    out = generate(model, ids, mask, config=GenerationConfig(max_new_tokens=NEW, stop_ids=(stop,), pad_id=127))
    tokens, lengths = np.asarray(out.tokens), np.asarray(out.lengths)
    assert lengths[0] == first + 1
    np.testing.assert_array_equal(tokens[0, : first + 1], free[0, : first + 1])
    assert (tokens[0, first + 1:] == 127).all()
    hits = np.flatnonzero(free[1] == stop)
    expected = hits[0] + 1 if len(hits) else NEW
    assert lengths[1] == expected
    np.testing.assert_array_equal(tokens[1, :expected], free[1, :expected])


def test_sampling_is_reproducible_and_differs_from_greedy(tiny) -> None:
    model, config = tiny
    ids = np.random.default_rng(6).integers(0, config.vision_start_token_id, (2, 5))
    hot = GenerationConfig(max_new_tokens=NEW, temperature=5.0, stop_ids=(), pad_id=0)
    a = np.asarray(generate(model, ids, config=hot, key=jax.random.key(1)).tokens)
    b = np.asarray(generate(model, ids, config=hot, key=jax.random.key(1)).tokens)
    c = np.asarray(generate(model, ids, config=hot, key=jax.random.key(2)).tokens)
    np.testing.assert_array_equal(a, b)
    assert (a != c).any()
    tiny_nucleus = generate(model, ids, config=hot.replace(top_p=1e-6), key=jax.random.key(1))
    greedy = generate(model, ids, config=hot.replace(temperature=0.0))
    np.testing.assert_array_equal(np.asarray(tiny_nucleus.tokens), np.asarray(greedy.tokens))


def test_sample_token_follows_softmax_and_nucleus() -> None:
    probs = np.array([0.5, 0.25, 0.15, 0.07, 0.03])
    logits = jnp.asarray(np.log(np.tile(probs, (20000, 1))), jnp.float32)
    drawn = np.asarray(sample_token(logits, jax.random.key(0), temperature=1.0, top_p=1.0))
    freq = np.bincount(drawn, minlength=5) / len(drawn)
    np.testing.assert_allclose(freq, probs, atol=0.015)
    # top_p = 0.8: the smallest set reaching 0.8 is {0, 1, 2} (0.5 + 0.25 < 0.8 <= 0.9)
    nucleus = np.asarray(sample_token(logits, jax.random.key(1), temperature=1.0, top_p=0.8))
    freq = np.bincount(nucleus, minlength=5) / len(nucleus)
    assert freq[3:].sum() == 0
    np.testing.assert_allclose(freq[:3], probs[:3] / probs[:3].sum(), atol=0.015)
    # temperature sharpens: p ** (1/T) renormalised
    cold = np.asarray(sample_token(logits, jax.random.key(2), temperature=0.5, top_p=1.0))
    sharp = probs**2 / (probs**2).sum()
    np.testing.assert_allclose(np.bincount(cold, minlength=5) / len(cold), sharp, atol=0.015)


def test_split_rows_assigns_images_to_rows() -> None:
    grid = np.array([[1, 4, 4], [1, 2, 4], [1, 4, 4]])  # 4, 2 and 4 pad tokens with merge 2
    ids = np.array([[9, 1, 1, 1, 1, 9, 1, 1], [9, 9, 9, 9, 9, 9, 9, 9], [1, 1, 1, 1, 9, 9, 9, 9]])
    assert split_rows(ids, grid, image_token_id=1, merge_size=2) == [(0, 2), (2, 2), (2, 3)]
    with pytest.raises(ValueError):
        split_rows(ids[:1], grid, image_token_id=1, merge_size=2)


def test_generation_config_rejects_nonsense() -> None:
    with pytest.raises(ValueError):
        GenerationConfig(max_new_tokens=0)
    with pytest.raises(ValueError):
        GenerationConfig(top_p=0.0)
    with pytest.raises(ValueError):
        GenerationConfig(temperature=-1.0)


def test_decode_refuses_a_cache_too_small(tiny) -> None:
    from jax3dc.generate import CACHE_MULTIPLE, decode, prefill

    model, config = tiny
    state = prefill(model, np.array([[1, 2, 3]]), max_new_tokens=4)
    slots = state.cache.valid.shape[1]
    assert slots % CACHE_MULTIPLE == 0 and slots >= 3 + 4 - 1  # rounded up, never below the need
    too_many = slots - 3 + 2  # one more slot than the cache holds
    with pytest.raises(ValueError, match=f"prefill with max_new_tokens >= {too_many}"):
        decode(model, state, GenerationConfig(max_new_tokens=too_many, stop_ids=(), pad_id=0))
