"""The parameters of a small NNX network as one float16 safetensors file, named by their state
paths: what the stage-1 networks (``jax3dc.stage1_net``, ``jax3dc.stage1_slots``) ship. Loading
is strict (a missing, extra or misshapen tensor names itself), since a folder that loads half its
weights would predict nonsense without a word."""

from __future__ import annotations

from pathlib import Path
from typing import TypeVar

import numpy as np
import safetensors.numpy
from flax import nnx
from safetensors import SafetensorError

from jax3dc.errors import InputFileError

M = TypeVar("M", bound=nnx.Module)


def _tensor_name(path: tuple) -> str:
    return ".".join(str(p) for p in path)


def save_params(model: nnx.Module, path: Path) -> None:
    """Writes ``model``'s parameters to ``path`` in float16 (half the bytes; the networks run in float32)."""
    tensors = {_tensor_name(p): np.asarray(v[...], np.float16) for p, v in nnx.to_flat_state(nnx.state(model, nnx.Param))}
    safetensors.numpy.save_file(tensors, str(path))


def load_params(model: M, path: Path) -> M:
    """``model`` (built, or abstract from ``nnx.eval_shape``) with its parameters read from ``path``
    in float32; the file must hold exactly the model's tensors, each of its shape."""
    if not path.is_file():
        raise InputFileError(str(path), "missing: the network's weights")
    try:
        tensors = safetensors.numpy.load_file(str(path))
    except (SafetensorError, OSError, ValueError) as e:
        raise InputFileError(str(path), f"not a readable safetensors file ({e})") from None
    flat = nnx.to_flat_state(nnx.state(model, nnx.Param))
    extra = sorted(set(tensors) - {_tensor_name(p) for p, _ in flat})
    if extra:
        raise InputFileError(str(path), f"unexpected tensor {extra[0]!r} ({len(extra)} in all)")
    for p, variable in flat:
        name = _tensor_name(p)
        if name not in tensors:
            raise InputFileError(str(path), f"missing tensor {name!r}")
        if tensors[name].shape != variable.shape:
            raise InputFileError(str(path), f"tensor {name!r} has shape {tensors[name].shape}, "
                                            f"the config needs {variable.shape}")
        variable.set_value(np.asarray(tensors[name], np.float32))
    nnx.update(model, nnx.from_flat_state(flat))
    return model
