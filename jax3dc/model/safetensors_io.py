"""Checkpoint tensors through the ``safetensors`` library (numpy backend), one tensor at a time.

``ml_dtypes`` is imported first: it registers numpy's ``bfloat16``, which is how the library's
numpy backend reads and writes the bf16 tensors our checkpoints hold. Loading streams tensor by
tensor, so a 4B checkpoint never sits in memory twice.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import ml_dtypes  # noqa: F401  (registers numpy's bfloat16 for the safetensors numpy backend)
import numpy as np
import safetensors.numpy
from safetensors import SafetensorError, safe_open

from jax3dc.errors import InputFileError


def checkpoint_files(directory: str | Path) -> list[Path]:
    """The safetensors files of a Hugging Face checkpoint directory (sharded via its index or one file)."""
    directory = Path(directory)
    index = directory / "model.safetensors.index.json"
    if index.exists():
        try:
            weight_map = json.loads(index.read_text())["weight_map"]
        except (json.JSONDecodeError, KeyError) as e:
            raise InputFileError(str(index), f"bad index file ({e})") from None
        files = [directory / f for f in dict.fromkeys(weight_map.values())]
    else:
        files = sorted(directory.glob("*.safetensors"))
    if not files:
        raise InputFileError(str(directory), "no *.safetensors files")
    for f in files:
        if not f.exists():
            raise InputFileError(str(f), "listed in the index but missing")
    return files


def iter_tensors(directory: str | Path) -> Iterator[tuple[str, np.ndarray]]:
    """(name, array) of every tensor of a checkpoint directory, one at a time."""
    for path in checkpoint_files(directory):
        try:
            with safe_open(str(path), framework="numpy") as f:
                for name in f.keys():
                    yield name, f.get_tensor(name)
        except (SafetensorError, OSError, TypeError) as e:  # TypeError: a dtype numpy cannot hold
            raise InputFileError(str(path), f"not a readable safetensors file ({e})") from None


def write_safetensors(path: str | Path, tensors: dict[str, np.ndarray]) -> None:
    """One safetensors file, with the metadata transformers expects of a PyTorch-format checkpoint."""
    safetensors.numpy.save_file({k: np.ascontiguousarray(v) for k, v in tensors.items()}, str(path),
                                metadata={"format": "pt"})
