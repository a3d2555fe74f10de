"""XLA flags jax3dc sets for GPUs at its entry points, unless the user's XLA_FLAGS names them.

XLA reads XLA_FLAGS when the backend starts, so :func:`apply_gpu_defaults` must run before the
first jax device query. CPU backends ignore these flags. Figures are in docs/BENCHMARKS.md.

* Training (``jax3dc train``, bench/train_step.py): FSDP all-gathers every weight before use and
  reduce-scatters every gradient. XLA's GPU default combines collectives only up to a small size,
  so a 4B step issued ~500 small NCCL calls; combining up to 256 MiB took 2-GPU FSDP from 1.80x
  to 1.83x one GPU's throughput (H200).
  Compile time: XLA's autotuning of Triton GEMM tilings took ~10 s of a 4B step's cold compile;
  with cuBLAS for every GEMM it compiled in 38 s instead of 48 s and stepped 1.7 % faster
  (H100); and compiling kernels on every host core took off another ~4 s.
* Generation (``jax3dc predict``, ``jax3dc eval generate``, bench/decode.py): the decode loop is a
  ``lax.while_loop`` of ~15 small kernels per layer; recording the loop body, and the loop itself,
  as CUDA graphs (command buffers of WHILE and CONDITIONAL too) took 4B batch-1 decode from
  249.7 to 257.7 tokens/s on an H100.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, MutableMapping

TRAINING_GPU_FLAGS = {
    "xla_gpu_all_gather_combine_threshold_bytes": str(256 * 2**20),
    "xla_gpu_reduce_scatter_combine_threshold_bytes": str(256 * 2**20),
    "xla_gpu_enable_triton_gemm": "false",
    "xla_gpu_force_compilation_parallelism": str(os.cpu_count() or 1),
}
GENERATION_GPU_FLAGS = {
    "xla_gpu_enable_command_buffer": "FUSION,CUBLAS,CUBLASLT,CUSTOM_CALL,CUDNN,WHILE,CONDITIONAL",
}


def apply_gpu_defaults(flags: Mapping[str, str], environ: MutableMapping[str, str] = os.environ) -> str:
    """Append each of ``flags`` that XLA_FLAGS does not already set; returns the new XLA_FLAGS."""
    current = environ.get("XLA_FLAGS", "")
    named = {part.lstrip("-").split("=", 1)[0] for part in current.split()}
    extra = [f"--{name}={value}" for name, value in flags.items() if name not in named]
    environ["XLA_FLAGS"] = " ".join([current, *extra]).strip()
    return environ["XLA_FLAGS"]
