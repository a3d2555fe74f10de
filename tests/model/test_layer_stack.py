"""Scanned decoder layers compute what the unrolled loop computes — logits and the gradient of
every layer's own parameters — under each remat policy, with an image (DeepStack layers stay
unrolled) and with LoRA adapters; generation keeps the loop."""

from __future__ import annotations

import dataclasses
import pathlib
import re

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from flax import nnx

from jax3dc.model import Qwen3VLConfig
from jax3dc.model.layer_stack import REMAT_POLICIES, remat_policy, stackable
from jax3dc.model.lora import LoraSpec, add_lora
from jax3dc.model.qwen3_vl import Qwen3VL

CFG = dataclasses.replace(Qwen3VLConfig.tiny(), text=dataclasses.replace(Qwen3VLConfig.tiny().text,
                                                                         num_hidden_layers=6))
IMAGE = 16  # pixels: a 4 x 4 patch grid, 4 merged image tokens
LENGTH = 12


def batch() -> tuple[jax.Array, jax.Array, jax.Array]:
    v = CFG.vision
    g = IMAGE // v.patch_size
    n_tok = g * g // v.spatial_merge_size**2
    rng = np.random.default_rng(0)
    ids = rng.integers(0, 100, (2, LENGTH)).astype(np.int32)
    ids[:, 0] = CFG.vision_start_token_id
    ids[:, 1:1 + n_tok] = CFG.image_token_id
    ids[:, 1 + n_tok] = CFG.vision_end_token_id
    pixels = rng.standard_normal((2 * g * g, v.patch_dim)).astype(np.float32)
    return jnp.asarray(ids), jnp.asarray(pixels), jnp.asarray(np.tile([[1, g, g]], (2, 1)).astype(np.int32))


def loss_and_grads(model: Qwen3VL, scan: bool, remat: str) -> tuple[jax.Array, jax.Array, dict]:
    model.scan_layers, model.remat = scan, remat
    ids, pixels, grid = batch()
    graphdef, params, rest = nnx.split(model, nnx.Param, ...)

    @jax.jit
    def run(params):
        def loss(params):
            logits = nnx.merge(graphdef, params, rest)(ids, pixel_values=pixels, image_grid_thw=grid)
            return jnp.mean(jax.nn.log_softmax(logits.astype(jnp.float32))[..., 7]), logits
        return jax.value_and_grad(loss, has_aux=True)(params)

    with jax.default_matmul_precision("highest"):
        (value, logits), grads = run(params)
    flat = {"/".join(map(str, p)): np.asarray(v.get_value()) for p, v in nnx.to_flat_state(grads)}
    return value, logits, flat


def scans_in(model: Qwen3VL, scan: bool) -> int:
    model.scan_layers = scan
    ids, pixels, grid = batch()
    jaxpr = jax.make_jaxpr(lambda: model(ids, pixel_values=pixels, image_grid_thw=grid))()
    return str(jaxpr).count("scan[")


@pytest.fixture(scope="module")
def model() -> Qwen3VL:
    return Qwen3VL(CFG, rngs=nnx.Rngs(0))


def test_the_scanned_path_is_taken_only_when_asked(model):
    assert scans_in(model, True) == scans_in(model, False) + 1


@pytest.mark.parametrize("remat", sorted(REMAT_POLICIES))
def test_scanned_layers_equal_the_loop_in_logits_and_every_gradient(model, remat):
    want_value, want_logits, want = loss_and_grads(model, False, "none")
    value, logits, got = loss_and_grads(model, True, remat)
    np.testing.assert_allclose(logits, want_logits, rtol=1e-5, atol=1e-5)
    np.testing.assert_allclose(value, want_value, rtol=1e-6)
    assert got.keys() == want.keys()
    scanned = [k for k in want if re.search(r"layers/[2-5]/", k)]
    assert scanned and all(np.abs(want[k]).max() > 0 for k in scanned)  # the scanned layers do get gradients
    for k in want:
        np.testing.assert_allclose(got[k], want[k], rtol=1e-4, atol=1e-6, err_msg=k)


def test_lora_layers_scan_alike():
    adapted = add_lora(Qwen3VL(CFG, rngs=nnx.Rngs(1)), LoraSpec(rank=2, alpha=4.0), rngs=nnx.Rngs(2))
    for layer in adapted.language_model.layers:  # non-zero B, so the adapters take part in the output
        for p, v in nnx.to_flat_state(nnx.state(layer, nnx.LoRAParam)):
            v.set_value(0.05 * jnp.ones_like(v.get_value()))
    assert stackable(adapted.language_model.layers)
    _, want_logits, want = loss_and_grads(adapted, False, "none")
    _, logits, got = loss_and_grads(adapted, True, "full")
    np.testing.assert_allclose(logits, want_logits, rtol=1e-5, atol=1e-5)
    for k in want:
        np.testing.assert_allclose(got[k], want[k], rtol=1e-4, atol=1e-6, err_msg=k)


def test_generation_keeps_the_loop_when_scanning_is_on(model):
    """prefill threads each layer's cache slice: a scanned model prefills like an unrolled one."""
    ids, pixels, grid = batch()
    model.scan_layers = True
    logits_scan, cache_scan, _ = model.prefill(ids, pixel_values=pixels, image_grid_thw=grid, max_length=16)
    model.scan_layers = False
    logits_loop, cache_loop, _ = model.prefill(ids, pixel_values=pixels, image_grid_thw=grid, max_length=16)
    np.testing.assert_array_equal(logits_scan, logits_loop)
    assert len(cache_scan.keys) == CFG.text.num_hidden_layers


def test_unknown_remat_policy_is_refused_by_name():
    with pytest.raises(ValueError, match="remat policy 'some'"):
        remat_policy("some")
    with pytest.raises(ValueError, match="remat policy"):
        Qwen3VL(Qwen3VLConfig.tiny(), rngs=nnx.Rngs(0), remat="some")


def test_the_step_benchmark_offers_every_policy():
    source = (pathlib.Path(__file__).parents[2] / "bench" / "train_step.py").read_text()
    names = re.search(r"REMAT_NAMES = \(([^)]*)\)", source).group(1)
    assert tuple(n.strip().strip('"') for n in names.split(",")) == tuple(REMAT_POLICIES)
