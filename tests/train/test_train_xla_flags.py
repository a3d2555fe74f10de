"""The trainer's GPU XLA defaults: added when absent, a user's own value kept, accepted by XLA."""

import os
import subprocess
import sys

from train.xla_flags import GPU_FLAGS, apply_gpu_defaults


def test_defaults_are_added_and_user_values_win():
    env = {"XLA_FLAGS": "--xla_gpu_all_gather_combine_threshold_bytes=1 --xla_force_host_platform_device_count=2"}
    flags = apply_gpu_defaults(env).split()
    assert "--xla_gpu_all_gather_combine_threshold_bytes=1" in flags
    assert not any(f.startswith("--xla_gpu_all_gather_combine_threshold_bytes=2") for f in flags)
    assert f"--xla_gpu_reduce_scatter_combine_threshold_bytes={GPU_FLAGS['xla_gpu_reduce_scatter_combine_threshold_bytes']}" in flags
    assert "--xla_force_host_platform_device_count=2" in flags
    assert apply_gpu_defaults(env) == env["XLA_FLAGS"]  # idempotent
    assert apply_gpu_defaults({}).count("--") == len(GPU_FLAGS)


def test_xla_accepts_the_flags_on_cpu():
    env = dict(os.environ, XLA_FLAGS=apply_gpu_defaults({}), JAX_PLATFORMS="cpu")
    out = subprocess.run([sys.executable, "-c", "import jax, jax.numpy as jnp; print(int(jnp.arange(4).sum()))"],
                         env=env, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "6"
