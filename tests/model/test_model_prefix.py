"""The log-depth prefix scans the model uses for token positions equal cumsum / cummax exactly."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jax3dc.model.prefix import prefix_max, prefix_sum


@pytest.mark.parametrize("shape,axis", [((8193,), 0), ((3, 1000), 1), ((5, 7), 0)])
def test_prefix_sum_and_max_match_numpy(shape, axis):
    rng = np.random.default_rng(0)
    ints = rng.integers(-50, 50, shape).astype(np.int32)
    flags = rng.random(shape) < 0.3
    np.testing.assert_array_equal(prefix_sum(jnp.asarray(ints), axis), np.cumsum(ints, axis))
    np.testing.assert_array_equal(prefix_sum(jnp.asarray(flags), axis), np.cumsum(flags, axis))
    np.testing.assert_array_equal(prefix_max(jnp.asarray(ints), axis), np.maximum.accumulate(ints, axis))
    jitted = jax.jit(lambda x: prefix_sum(x, axis))(jnp.asarray(flags))
    assert jitted.dtype == jnp.int32
