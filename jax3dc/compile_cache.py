"""JAX's persistent compilation cache, shared by the commands that compile (train, the MJX sweep):
a repeated or resumed run loads its executables from disk instead of compiling them again."""

from __future__ import annotations

import os

DEFAULT_DIR = "~/.cache/jax3dc/xla"


def use_compile_cache(directory: str) -> None:
    """Cache compiled executables in ``directory`` ("" turns it off); the environment's
    JAX_COMPILATION_CACHE_DIR, where set, wins."""
    if directory and "JAX_COMPILATION_CACHE_DIR" not in os.environ:
        import jax

        jax.config.update("jax_compilation_cache_dir", os.path.expanduser(directory))
