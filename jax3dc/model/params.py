"""Hugging Face Qwen3-VL checkpoints <-> our parameters, both ways.

:data:`PARAM_TABLE` names every tensor of ``Qwen3VLForConditionalGeneration``: a HF name
pattern, our parameter path, and how the array changes. ``{i}`` is a layer / block / merger
number. Kinds:

* ``same``   – identical array (norms, biases of 1-D layout, embedding tables);
* ``linear`` – a torch ``nn.Linear`` weight ``[out, in]`` becomes our kernel ``[*in, *out]``
  (transpose, then split heads: e.g. q_proj ``[heads*hd, E]`` -> ``[E, heads, hd]``);
* ``bias``   – reshape a flat bias to our ``[*out]`` (e.g. the vision qkv bias ``[3, heads, hd]``);
* ``conv``   – the patch Conv3d weight ``[D, C, T, P, P]`` (stride = kernel) becomes a matmul
  kernel ``[C*T*P*P, D]`` over transformers' flattened ``pixel_values`` rows.

Loading raises on any checkpoint tensor the table does not map and on any parameter left
unfilled; ``lm_head.weight`` is accepted and ignored when the embeddings are tied.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
from flax import nnx
from jax.experimental import multihost_utils

from jax3dc.errors import InputFileError
from jax3dc.model.config import Qwen3VLConfig
from jax3dc.model.layers import Dense
from jax3dc.model.lora import merged_params
from jax3dc.model.qwen3_vl import Qwen3VL
from jax3dc.model.safetensors_io import iter_tensors, write_safetensors
from jax3dc.sharding import LOGICAL_RULES, Rules, state_shardings

V, T = "model.visual", "model.language_model"
_VIS_BLOCK = [
    ("norm1.weight", "norm1.weight", "same"), ("norm1.bias", "norm1.bias", "same"),
    ("norm2.weight", "norm2.weight", "same"), ("norm2.bias", "norm2.bias", "same"),
    ("attn.qkv.weight", "attn.qkv.kernel", "linear"), ("attn.qkv.bias", "attn.qkv.bias", "bias"),
    ("attn.proj.weight", "attn.proj.kernel", "linear"), ("attn.proj.bias", "attn.proj.bias", "bias"),
    ("mlp.linear_fc1.weight", "mlp.linear_fc1.kernel", "linear"),
    ("mlp.linear_fc1.bias", "mlp.linear_fc1.bias", "bias"),
    ("mlp.linear_fc2.weight", "mlp.linear_fc2.kernel", "linear"),
    ("mlp.linear_fc2.bias", "mlp.linear_fc2.bias", "bias"),
]
_MERGER = [
    ("norm.weight", "norm.weight", "same"), ("norm.bias", "norm.bias", "same"),
    ("linear_fc1.weight", "linear_fc1.kernel", "linear"), ("linear_fc1.bias", "linear_fc1.bias", "bias"),
    ("linear_fc2.weight", "linear_fc2.kernel", "linear"), ("linear_fc2.bias", "linear_fc2.bias", "bias"),
]
_TEXT_LAYER = [
    ("self_attn.q_proj.weight", "self_attn.q_proj.kernel", "linear"),
    ("self_attn.k_proj.weight", "self_attn.k_proj.kernel", "linear"),
    ("self_attn.v_proj.weight", "self_attn.v_proj.kernel", "linear"),
    ("self_attn.o_proj.weight", "self_attn.o_proj.kernel", "linear"),
    ("self_attn.q_proj.bias", "self_attn.q_proj.bias", "bias"),
    ("self_attn.k_proj.bias", "self_attn.k_proj.bias", "bias"),
    ("self_attn.v_proj.bias", "self_attn.v_proj.bias", "bias"),
    ("self_attn.o_proj.bias", "self_attn.o_proj.bias", "bias"),
    ("self_attn.q_norm.weight", "self_attn.q_norm.weight", "same"),
    ("self_attn.k_norm.weight", "self_attn.k_norm.weight", "same"),
    ("mlp.gate_proj.weight", "mlp.gate_proj.kernel", "linear"),
    ("mlp.up_proj.weight", "mlp.up_proj.kernel", "linear"),
    ("mlp.down_proj.weight", "mlp.down_proj.kernel", "linear"),
    ("input_layernorm.weight", "input_layernorm.weight", "same"),
    ("post_attention_layernorm.weight", "post_attention_layernorm.weight", "same"),
]

#: (HF name, our path, kind); ``{i}`` matches a non-negative integer on both sides.
PARAM_TABLE: tuple[tuple[str, str, str], ...] = (
    (f"{V}.patch_embed.proj.weight", "visual.patch_embed.kernel", "conv"),
    (f"{V}.patch_embed.proj.bias", "visual.patch_embed.bias", "bias"),
    (f"{V}.pos_embed.weight", "visual.pos_embed", "same"),
    *((f"{V}.blocks.{{i}}.{h}", f"visual.blocks.{{i}}.{o}", k) for h, o, k in _VIS_BLOCK),
    *((f"{V}.merger.{h}", f"visual.merger.{o}", k) for h, o, k in _MERGER),
    *((f"{V}.deepstack_merger_list.{{i}}.{h}", f"visual.deepstack_merger_list.{{i}}.{o}", k) for h, o, k in _MERGER),
    (f"{T}.embed_tokens.weight", "language_model.embed_tokens", "same"),
    *((f"{T}.layers.{{i}}.{h}", f"language_model.layers.{{i}}.{o}", k) for h, o, k in _TEXT_LAYER),
    (f"{T}.norm.weight", "language_model.norm.weight", "same"),
    ("lm_head.weight", "lm_head.kernel", "linear"),
)


def _pattern(template: str) -> re.Pattern:
    return re.compile("^" + re.escape(template).replace(re.escape("{i}"), r"(?P<i>\d+)") + "$")


@dataclass(frozen=True)
class _Rule:
    hf: re.Pattern
    ours: re.Pattern
    hf_template: str
    ours_template: str
    kind: str


_RULES = tuple(_Rule(_pattern(h), _pattern(o), h, o, k) for h, o, k in PARAM_TABLE)


def hf_to_ours_name(name: str) -> tuple[str, str] | None:
    """(our path, kind) for a HF tensor name, or None if the table has no rule for it."""
    for r in _RULES:
        m = r.hf.match(name)
        if m:
            return r.ours_template.format(**m.groupdict()), r.kind
    return None


def ours_to_hf_name(path: str) -> tuple[str, str]:
    for r in _RULES:
        m = r.ours.match(path)
        if m:
            return r.hf_template.format(**m.groupdict()), r.kind
    raise KeyError(f"no HF name for parameter {path}")


def to_ours(arr: np.ndarray, kind: str, shape: tuple[int, ...]) -> np.ndarray:
    """A HF tensor in our layout (a view where possible; memory maps stay lazy)."""
    if kind == "same":
        out = arr
    elif kind == "bias":
        out = arr.reshape(shape)
    elif kind in ("linear", "conv"):
        out = arr.reshape(arr.shape[0], -1).T.reshape(shape)
    else:
        raise ValueError(kind)
    if out.shape != tuple(shape):
        raise ValueError(f"shape {arr.shape} does not map to {shape}")
    return out


def to_hf(arr: np.ndarray, kind: str, n_in: int, config: Qwen3VLConfig) -> np.ndarray:
    if kind == "same":
        return arr
    if kind == "bias":
        return arr.reshape(-1)
    if kind == "linear":
        return np.ascontiguousarray(arr.reshape(math.prod(arr.shape[:n_in]), -1).T)
    if kind == "conv":
        v = config.vision
        return np.ascontiguousarray(arr.T.reshape(v.hidden_size, v.in_channels, v.temporal_patch_size,
                                                  v.patch_size, v.patch_size))
    raise ValueError(kind)


def _path_str(path: tuple) -> str:
    return ".".join(str(p) for p in path)


def read_config(path: str | Path) -> Qwen3VLConfig:
    f = Path(path) / "config.json"
    try:
        return Qwen3VLConfig.from_hf_dict(json.loads(f.read_text()))
    except FileNotFoundError:
        raise InputFileError(str(f), "missing") from None
    except json.JSONDecodeError as e:
        raise InputFileError(str(f), f"not valid JSON ({e})") from None


def abstract_model(config: Qwen3VLConfig, **model_kwargs) -> Qwen3VL:
    """The model's structure with ShapeDtypeStructs instead of arrays (allocates nothing)."""
    return nnx.eval_shape(lambda: Qwen3VL(config, rngs=nnx.Rngs(0), **model_kwargs))


def param_count(model: Qwen3VL, prefix: str = "") -> int:
    return sum(math.prod(v.get_value().shape) for p, v in nnx.to_flat_state(nnx.state(model, nnx.Param))
               if _path_str(p).startswith(prefix))


def load_pretrained(path: str | Path, dtype=jnp.float32, mesh: jax.sharding.Mesh | None = None,
                    rules: Rules | None = None, *, compute_dtype=None, attention_impl: str | None = None,
                    remat: str = "none", scan_layers: bool = False) -> tuple[Qwen3VL, Qwen3VLConfig]:
    """Builds Qwen3-VL from a HF checkpoint directory with parameters stored in ``dtype``
    (``compute_dtype``, default the same, is what the layers compute in).

    Each tensor goes from its memory map straight to its target sharding on ``mesh`` (from the
    parameters' logical axes and ``rules``; each device reads only its slice); with no mesh,
    to the first device. Raises InputFileError on unmapped, duplicate or missing tensors.
    """
    config = read_config(path)
    abstract = abstract_model(config, dtype=dtype if compute_dtype is None else compute_dtype,
                              param_dtype=dtype, attention_impl=attention_impl, remat=remat,
                              scan_layers=scan_layers)
    graphdef, state = nnx.split(abstract)
    if mesh is not None:
        shard_state = state_shardings(state, mesh, rules or LOGICAL_RULES)
        shardings = {_path_str(p): v.get_value() for p, v in nnx.to_flat_state(shard_state)}
    flat = dict((_path_str(p), v) for p, v in nnx.to_flat_state(state))
    loaded: dict[str, jax.Array] = {}
    device = jax.sharding.SingleDeviceSharding(jax.devices()[0])
    for name, arr in iter_tensors(path):
        mapped = hf_to_ours_name(name)
        if mapped is None:
            raise InputFileError(str(path), f"checkpoint tensor {name} has no mapping in PARAM_TABLE")
        ours, kind = mapped
        if ours == "lm_head.kernel" and config.tie_word_embeddings:
            continue
        if ours not in flat:
            raise InputFileError(str(path), f"checkpoint tensor {name} -> {ours}, which this config has no room for")
        if ours in loaded:
            raise InputFileError(str(path), f"checkpoint tensor {name} appears twice")
        target = flat[ours].get_value()
        try:
            host = to_ours(arr, kind, target.shape)
        except ValueError as e:
            raise InputFileError(str(path), f"tensor {name}: {e}") from None
        sharding = shardings[ours] if mesh is not None else device
        loaded[ours] = jax.make_array_from_callback(
            target.shape, sharding, lambda idx, h=host: np.asarray(h[idx], dtype=target.dtype))
    missing = sorted(set(flat) - set(loaded))
    if missing:
        raise InputFileError(str(path), f"{len(missing)} parameters missing from the checkpoint, e.g. {missing[:3]}")
    new_state = nnx.from_flat_state([(p, v.replace(loaded[_path_str(p)])) for p, v in nnx.to_flat_state(state)])
    return nnx.merge(graphdef, new_state), config


def kernel_input_dims(model: Qwen3VL) -> dict[str, int]:
    """For each Dense kernel path, how many leading dims are inputs (needed to flatten it back)."""
    return {_path_str(p) + ".kernel": mod.n_in for p, mod in nnx.iter_graph(model)
            if isinstance(mod, Dense)}


def _to_host(x: jax.Array) -> np.ndarray:
    if x.is_fully_addressable:
        return np.asarray(jax.device_get(x))

    return np.asarray(multihost_utils.process_allgather(x, tiled=True))


def save_pretrained(model: Qwen3VL, config: Qwen3VLConfig, path: str | Path, dtype=None,
                    max_shard_bytes: int = 5 * 2**30) -> None:
    """Writes config.json and safetensors (sharded with an index above ``max_shard_bytes``)
    that transformers' ``Qwen3VLForConditionalGeneration.from_pretrained`` loads.

    LoRA adapters (jax3dc/model/lora.py) are merged into their kernels, so the folder holds a
    plain model. One tensor at a time is merged and gathered to the host. With several processes
    every process must call this (the gathers are collective); only process 0 writes.
    """
    path = Path(path)
    writer = jax.process_index() == 0
    if writer:
        path.mkdir(parents=True, exist_ok=True)
    n_in = kernel_input_dims(model)
    written: list[tuple[Path, list[str]]] = []  # shard files, written as soon as they fill
    shard: dict[str, np.ndarray] = {}
    total = 0
    out_dtype = None

    def flush():
        f = path / f"model-part{len(written):05d}.tmp"
        if writer:
            write_safetensors(f, shard)
        written.append((f, list(shard)))

    for ours, value in merged_params(model):
        hf_name, kind = ours_to_hf_name(ours)
        arr = _to_host(value)
        if dtype is not None:
            arr = arr.astype(dtype)
        out_dtype = arr.dtype
        arr = to_hf(arr, kind, n_in.get(ours, 1), config)
        if shard and sum(a.nbytes for a in shard.values()) + arr.nbytes > max_shard_bytes:
            flush()
            shard = {}
        shard[hf_name] = arr
        total += arr.nbytes
    flush()
    if not writer:
        return
    if len(written) == 1:
        written[0][0].replace(path / "model.safetensors")
    else:
        weight_map = {}
        for k, (f, names) in enumerate(written, 1):
            fname = f"model-{k:05d}-of-{len(written):05d}.safetensors"
            f.replace(path / fname)
            weight_map.update({n: fname for n in names})
        (path / "model.safetensors.index.json").write_text(json.dumps(
            {"metadata": {"total_size": total}, "weight_map": weight_map}, indent=1))
    dtype_name = {np.dtype(np.float32): "float32", np.dtype(np.float16): "float16"}.get(
        np.dtype(out_dtype), "bfloat16")
    (path / "config.json").write_text(json.dumps(config.to_hf_dict(dtype_name), indent=2))
