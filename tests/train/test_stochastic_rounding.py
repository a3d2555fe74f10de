"""Stochastic rounding to bf16 (train/stochastic_rounding.py): unbiased, exact values kept, and
bf16 weights that move under updates round-to-nearest drops."""

import jax
import jax.numpy as jnp
import numpy as np
import optax
import pytest

from train.config import ConfigError, TrainConfig, validate
from train.stochastic_rounding import apply_updates_rounded, round_to_bfloat16


def test_rounding_lands_on_a_neighbour_and_is_unbiased():
    x = jnp.full((200_000,), 1.0 + 2.0 ** -9 + 2.0 ** -11, jnp.float32)  # 5/16 of the way up
    noise = jax.random.bits(jax.random.key(0), x.shape, jnp.uint32) >> 16
    r = np.asarray(round_to_bfloat16(x, noise), np.float64)
    assert set(np.unique(r)) == {1.0, 1.0 + 2.0 ** -7}
    np.testing.assert_allclose(r.mean(), float(x[0]), rtol=2e-5)
    most = jnp.full((5,), 0xFFFF, jnp.uint32)  # the largest noise leaves exact values alone
    exact = jnp.asarray([0.0, -2.5, 1.0, jnp.inf, -jnp.inf], jnp.float32)
    np.testing.assert_array_equal(np.asarray(round_to_bfloat16(exact, most), np.float32), exact)
    assert np.isnan(np.asarray(round_to_bfloat16(jnp.full((5,), jnp.nan), most), np.float32)).all()


def test_small_updates_move_bf16_weights_on_average():
    """100 updates of 1e-4 on weights at 1.0 (half a bf16 step there is 2^-8 = 0.0039)."""
    params = {"w": jnp.ones((50_000,), jnp.bfloat16), "scale": jnp.ones((3,), jnp.float32)}
    updates = {"w": jnp.full((50_000,), 1e-4, jnp.bfloat16), "scale": jnp.full((3,), 1e-4, jnp.float32)}
    nearest, rounded = params, params
    step = jax.jit(apply_updates_rounded)
    for i in range(100):
        nearest = optax.apply_updates(nearest, updates)
        rounded = step(rounded, updates, jax.random.key(i))
    assert float(jnp.max(jnp.abs(nearest["w"].astype(jnp.float32) - 1))) == 0.0  # every update dropped
    assert rounded["w"].dtype == jnp.bfloat16 and rounded["scale"].dtype == jnp.float32
    np.testing.assert_allclose(float(rounded["w"].astype(jnp.float32).mean()), 1.01, rtol=2e-4)
    np.testing.assert_array_equal(np.asarray(rounded["scale"]), np.asarray(nearest["scale"]))  # float32: as optax


def test_stochastic_rounding_needs_bf16_master():
    good = TrainConfig(data="synthetic", master_fp32=False, stochastic_rounding=True)
    validate(good)
    for bad in (TrainConfig(data="synthetic", stochastic_rounding=True),
                TrainConfig(data="synthetic", master_fp32=False, compute_dtype="float32", stochastic_rounding=True)):
        with pytest.raises(ConfigError, match="stochastic_rounding"):
            validate(bad)
