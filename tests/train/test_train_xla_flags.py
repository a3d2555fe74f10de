"""jax3dc's GPU XLA defaults: added when absent, a user's own value kept, accepted by XLA."""

import os
import subprocess
import sys

import pytest

from jax3dc.xla_flags import GENERATION_GPU_FLAGS, TRAINING_GPU_FLAGS, apply_gpu_defaults


def test_defaults_are_added_and_user_values_win():
    env = {"XLA_FLAGS": "--xla_gpu_all_gather_combine_threshold_bytes=1 --xla_force_host_platform_device_count=2"}
    flags = apply_gpu_defaults(TRAINING_GPU_FLAGS, env).split()
    assert "--xla_gpu_all_gather_combine_threshold_bytes=1" in flags
    assert sum(f.startswith("--xla_gpu_all_gather_combine_threshold_bytes=") for f in flags) == 1
    want = TRAINING_GPU_FLAGS["xla_gpu_reduce_scatter_combine_threshold_bytes"]
    assert f"--xla_gpu_reduce_scatter_combine_threshold_bytes={want}" in flags
    assert "--xla_force_host_platform_device_count=2" in flags
    assert apply_gpu_defaults(TRAINING_GPU_FLAGS, env) == env["XLA_FLAGS"]  # idempotent
    assert apply_gpu_defaults(GENERATION_GPU_FLAGS, {}).count("--") == len(GENERATION_GPU_FLAGS)


@pytest.mark.parametrize("flags", [TRAINING_GPU_FLAGS, GENERATION_GPU_FLAGS])
def test_xla_accepts_the_flags_on_cpu(flags):
    env = dict(os.environ, XLA_FLAGS=apply_gpu_defaults(flags, {}), JAX_PLATFORMS="cpu")
    code = "import jax, jax.numpy as jnp; print(int(jax.jit(lambda x: x.sum())(jnp.arange(4))))"
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "6"
