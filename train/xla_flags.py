"""XLA flags the trainer sets for GPUs, unless the user's XLA_FLAGS already names them.

Why: FSDP all-gathers every weight before use and reduce-scatters every gradient. XLA's GPU
default combines collectives only up to a small size, so a 4B step issued ~500 small NCCL calls;
combining up to 256 MiB took 2-GPU FSDP from 1.80x to 1.83x one GPU's throughput (H200,
docs/BENCHMARKS.md). XLA reads XLA_FLAGS when the backend starts, so this must run before the
first jax device query. The flags are ignored by CPU backends.
"""

from __future__ import annotations

import os
from collections.abc import MutableMapping

GPU_FLAGS = {
    "xla_gpu_all_gather_combine_threshold_bytes": str(256 * 2**20),
    "xla_gpu_reduce_scatter_combine_threshold_bytes": str(256 * 2**20),
}


def apply_gpu_defaults(environ: MutableMapping[str, str] = os.environ) -> str:
    """Append each flag of GPU_FLAGS that XLA_FLAGS does not set; returns the new XLA_FLAGS."""
    current = environ.get("XLA_FLAGS", "")
    named = {part.lstrip("-").split("=", 1)[0] for part in current.split()}
    extra = [f"--{name}={value}" for name, value in GPU_FLAGS.items() if name not in named]
    environ["XLA_FLAGS"] = " ".join([current, *extra]).strip()
    return environ["XLA_FLAGS"]
