"""The compile clock counts what jit really compiled: one program per new shape, none on a
repeated call, and the seconds of each phase."""

import jax
import jax.numpy as jnp
import numpy as np

from jax3dc.compilation import CompileClock


def test_the_clock_counts_one_compile_per_new_shape():
    three, five = np.ones(3, np.float32), np.ones(5, np.float32)  # host inputs: no program makes them
    clock = CompileClock()
    f = jax.jit(lambda x: jnp.sin(x) * 2.0 + x.sum())
    f(three).block_until_ready()
    first = clock.elapsed()
    assert first["compiles"] == 1 and first["cache_hits"] == 0
    assert first["trace_s"] > 0 and first["lower_s"] > 0 and first["xla_s"] > 0
    f(three).block_until_ready()  # the same shape: nothing to trace or compile
    assert clock.elapsed() == first
    f(five).block_until_ready()
    later = clock.elapsed()
    assert later["compiles"] == 2 and later["xla_s"] > first["xla_s"]
    assert CompileClock().elapsed()["compiles"] == 0  # a new clock starts from nothing
