"""A training run described by one frozen dataclass, with `key=value` overrides from the CLI.

What a run did can be read back from its config (written as config.json in the output
directory) and its metrics log.
"""

from __future__ import annotations

import dataclasses
import json
import typing
from dataclasses import dataclass, field
from typing import Any, Sequence

from jax3dc import sharding
from jax3dc.compilation import DEFAULT_DIR as DEFAULT_CACHE_DIR
from jax3dc.errors import Jax3dcError
from jax3dc.model.layer_stack import REMAT_POLICIES
from jax3dc.model.lora import LoraSpec
from train.adam_moments import MOMENT_DTYPES


class ConfigError(Jax3dcError):
    """An override names no field of TrainConfig, its value does not parse as the field's type,
    or the settings cannot make a run (validate)."""


#: validate's error when no training data is named (TrainConfig.data is empty).
NO_DATA = ("no training data: pass --set data=DIR[,DIR...] (folders from 'jax3dc data build' / "
           "'jax3dc data import'), or --set data=synthetic for the built-in counting sequences used in speed tests")


@dataclass(frozen=True)
class MeshConfig:
    """Device mesh shape over the axes (data, fsdp, tensor); one entry may be -1 = the rest."""

    data: int = 1
    fsdp: int = -1
    tensor: int = 1


@dataclass(frozen=True)
class TrainConfig:
    """Everything that decides what a training run does. Defaults follow the paper (SPEC §7)."""

    # Model: a preset name (tiny, small, qwen3_vl_4b: random weights) or an HF checkpoint dir.
    init: str = "small"
    output_dir: str = "runs/train"
    # Data (required; empty stops the run with NO_DATA): dataset folders (comma-separated) that
    # the grain loader (data_pipeline/loader.py) reads, mixed by data_weights, or "synthetic":
    # built-in counting sequences for speed and sharding tests, which teach a model nothing.
    data: str = ""
    data_weights: tuple[float, ...] = ()
    val_data: str = ""  # empty: validate on the datasets' val split (held-out sequences for synthetic)
    task: str = "structure"  # structure: I + S + prompt -> JSON; code: I -> part program; parameters: I -> factory parameters
    # One task per data folder (the same folder may be named twice, once per task): one model
    # learns both stages; empty: `task` for every folder.
    data_tasks: tuple[str, ...] = ()
    # How the structure task writes joint pivots (jax3dc/structure/box_frame.py): "absolute" (SPEC §2
    # numbers) or "box" (fractions of the moving part's box); empty: the init checkpoint's, else absolute.
    # The exported model folder records it, so generation reads its pivots back the same way.
    pivot_frame: str = ""
    tokenizer: str = ""  # folder with tokenizer.json; empty: the init checkpoint's, else Qwen3's
    # Score the material text an importer writes for a material its source does not name (off: that
    # text marks the real domain; data_pipeline.importers.material_guess.placeholder_spans).
    score_placeholder_materials: bool = False
    pack: int = 6  # examples packed per row at most (1: one padded example per row); ~1.5k tokens each at 448 px
    loader_workers: int = 0  # grain worker processes decoding and packing
    seq_len: int = 8192
    image_size: int = 448  # square side of I and S in pixels (records of another size are resized)
    batch_size: int = 16  # effective (global) batch in sequences per optimiser step
    grad_accum: int = 16  # micro-batches per step; batch_size / grad_accum rows at a time
    steps: int = 1000
    time_limit_min: float = 0.0  # > 0: stop (save, export) after this many minutes, even before `steps`
    # Optimiser: AdamW, linear warm-up then cosine decay, clipped global gradient norm.
    lr: float = 1e-5
    warmup_steps: int = 30
    end_lr_ratio: float = 0.0  # cosine ends at lr * end_lr_ratio
    weight_decay: float = 0.0
    b1: float = 0.9
    b2: float = 0.999
    eps: float = 1e-8
    clip_norm: float = 1.0
    # Parameters whose '/'-joined path matches any of these regexes get no gradient and no
    # optimiser state.
    freeze: tuple[str, ...] = (r"(^|/)visual/",)
    # LoRA (jax3dc/model/lora.py): lora_rank > 0 trains only low-rank adapters on the decoder
    # projections named in lora_targets, scaled by lora_alpha / lora_rank (adapters matching
    # `freeze` stay frozen too); every base weight is frozen and held in compute_dtype. The HF
    # export merges the adapters into the kernels. 0: full fine-tuning.
    lora_rank: int = 0
    lora_alpha: float = 16.0
    lora_targets: tuple[str, ...] = ("q_proj", "k_proj", "v_proj", "o_proj", "gate_proj", "up_proj", "down_proj")
    # Numerics: compute dtype for matmuls; master_fp32 keeps trainable weights and optimiser
    # state in float32 (else in the compute dtype, half the memory).
    compute_dtype: str = "bfloat16"
    master_fp32: bool = True
    # Adam's two moments: "" keeps them in the trainable weights' dtype; "bfloat16" stores both in
    # bf16 (stochastically rounded, update math in float32) under fp32 master weights: the 4B's
    # moments take 16.1 GB instead of 32.2 (train/adam_moments.py, bench/train_memory.py).
    moments_dtype: str = ""
    # bf16 master weights (master_fp32=false, compute_dtype=bfloat16) rounded stochastically after
    # each update, so updates below half a bf16 step still move them on average
    # (train/stochastic_rounding.py); pair with moments_dtype=bfloat16 for float32 Adam arithmetic.
    stochastic_rounding: bool = False
    # Where FSDP-sharded weights are gathered: "micro" lets each micro-batch gather them (in its
    # forward and again in its rematerialised forward); "step" gathers them once per optimiser
    # step in the compute dtype and reduce-scatters each micro-batch's gradient (fewer
    # collectives with grad_accum > 1, one gathered copy of the weights held; train/step.py).
    weight_gather: str = "micro"
    attention: str = "auto"  # auto: cuDNN fused attention on GPU, XLA elsewhere; or cudnn / xla
    # Decoder-layer rematerialisation policy (jax3dc/model/layer_stack.py): full recomputes each
    # layer in the backward pass, minimal keeps its matmul outputs, qkv its q/k/v projections, none
    # keeps everything.
    remat: str = "full"
    # Run the decoder layers after the DeepStack ones as one lax.scan: 4B compiles in 53 s instead of
    # 64 s, but steps 14 % slower and remat=none no longer fits 80 GB (docs/BENCHMARKS.md, training).
    scan_layers: bool = False
    # JAX's persistent compilation cache: a resumed or repeated run loads its compiled step from
    # here instead of compiling again; "" turns it off.
    compile_cache: str = DEFAULT_CACHE_DIR
    mesh: MeshConfig = field(default_factory=MeshConfig)
    # Rows of the logical -> mesh axes table (jax3dc/sharding.py LOGICAL_RULES) to replace, as
    # "logical=axis[+axis]" ("logical=": replicated), e.g. batch=data+fsdp,vocab=tensor. Parameters,
    # activations, the batch layout and the loss all follow the resulting table.
    sharding_rules: tuple[str, ...] = ()
    seed: int = 0
    # Cadence (in optimiser steps).
    log_every: int = 10
    eval_every: int = 200
    eval_batches: int = 4  # validation batches per evaluation; 0: train without validation
    save_every: int = 200
    keep_last: int = 3
    export_hf: bool = True  # write the final model as an HF directory in output_dir/hf


def _parse_value(text: str, kind: Any, name: str) -> Any:
    origin = typing.get_origin(kind)
    try:
        if kind is bool:
            if text.lower() in ("1", "true", "yes", "on"):
                return True
            if text.lower() in ("0", "false", "no", "off"):
                return False
            raise ValueError(text)
        if kind in (int, float, str):
            return kind(text)
        if origin is tuple:
            items = [t for t in text.split(",") if t] if text else []
            return tuple(_parse_value(t, typing.get_args(kind)[0], name) for t in items)
    except ValueError:
        raise ConfigError(f"--set {name}={text}: not a valid {getattr(kind, '__name__', kind)}") from None
    raise ConfigError(f"--set {name}: field of type {kind} cannot be set from the command line")


def _field_types(cls: type) -> dict[str, Any]:
    hints = typing.get_type_hints(cls)
    return {f.name: hints[f.name] for f in dataclasses.fields(cls)}


def apply_overrides(cfg: Any, overrides: Sequence[str]) -> Any:
    """Return cfg with each 'a.b=value' applied; nested dataclasses are addressed with dots."""
    for item in overrides:
        if "=" not in item:
            raise ConfigError(f"--set {item!r}: expected key=value")
        key, text = item.split("=", 1)
        cfg = _set_path(cfg, key.strip().split("."), text.strip(), key)
    return cfg


def _set_path(obj: Any, path: list[str], text: str, full: str) -> Any:
    types_ = _field_types(type(obj))
    name = path[0]
    if name not in types_:
        raise ConfigError(f"--set {full}: {type(obj).__name__} has no field {name!r} "
                          f"(fields: {', '.join(types_)})")
    if len(path) > 1:
        child = getattr(obj, name)
        if not dataclasses.is_dataclass(child):
            raise ConfigError(f"--set {full}: {name!r} has no sub-fields")
        return dataclasses.replace(obj, **{name: _set_path(child, path[1:], text, full)})
    if dataclasses.is_dataclass(getattr(obj, name)):
        raise ConfigError(f"--set {full}: {name!r} is a group; set one of its fields ({name}.x=...)")
    return dataclasses.replace(obj, **{name: _parse_value(text, types_[name], full)})


def describe_fields(cls: type = TrainConfig, prefix: str = "") -> list[str]:
    """One 'name (type, default)' line per settable field, for --help."""
    lines = []
    default = cls()
    for name, kind in _field_types(cls).items():
        value = getattr(default, name)
        if dataclasses.is_dataclass(value):
            lines += describe_fields(type(value), prefix + name + ".")
        else:
            shown = ",".join(value) if isinstance(value, tuple) else value
            kind_name = getattr(kind, "__name__", str(kind).replace("typing.", ""))
            lines.append(f"  {prefix}{name} ({kind_name}) = {shown}")
    return lines


def to_json(cfg: TrainConfig) -> str:
    return json.dumps(dataclasses.asdict(cfg), indent=1, sort_keys=True)


def require_data(cfg: TrainConfig) -> None:
    """ConfigError(NO_DATA) unless cfg.data names something to train on."""
    if not any(s.strip() for s in cfg.data.split(",")):
        raise ConfigError(NO_DATA)


def sharding_rules(cfg: TrainConfig) -> sharding.Rules:
    """The run's logical -> mesh axes table: LOGICAL_RULES with cfg.sharding_rules applied."""
    try:
        return sharding.with_overrides(sharding.LOGICAL_RULES, cfg.sharding_rules)
    except ValueError as e:
        raise ConfigError(f"sharding_rules: {e}") from None


def lora_spec(cfg: TrainConfig) -> LoraSpec:
    """The run's LoraSpec (lora_rank must be > 0); ConfigError for an unknown target."""
    try:
        return LoraSpec(cfg.lora_rank, cfg.lora_alpha, cfg.lora_targets)
    except ValueError as e:
        raise ConfigError(str(e)) from None


def validate(cfg: TrainConfig) -> None:
    """Reject settings that cannot work before any device work starts (and before the run
    writes anything)."""
    require_data(cfg)
    sharding_rules(cfg)
    if cfg.batch_size % cfg.grad_accum:
        raise ConfigError(f"batch_size {cfg.batch_size} is not a multiple of grad_accum {cfg.grad_accum}")
    for task in (cfg.task, *cfg.data_tasks):
        if task not in ("structure", "code", "parameters"):
            raise ConfigError(f"task {task!r}: expected structure, code or parameters")
    folders = [s for s in cfg.data.split(",") if s]
    if cfg.data_tasks and len(cfg.data_tasks) != len(folders):
        raise ConfigError(f"data_tasks names {len(cfg.data_tasks)} tasks for {len(folders)} data folders")
    if cfg.pack < 1 or cfg.loader_workers < 0:
        raise ConfigError(f"pack must be >= 1 and loader_workers >= 0 (got {cfg.pack}, {cfg.loader_workers})")
    if cfg.attention not in ("auto", "cudnn", "xla"):
        raise ConfigError(f"attention {cfg.attention!r}: expected auto, cudnn or xla")
    if cfg.weight_gather not in ("micro", "step"):
        raise ConfigError(f"weight_gather {cfg.weight_gather!r}: expected micro or step")
    if cfg.remat not in REMAT_POLICIES:
        raise ConfigError(f"remat {cfg.remat!r}: expected one of {', '.join(REMAT_POLICIES)}")
    if cfg.lora_rank < 0:
        raise ConfigError(f"lora_rank must be >= 0 (0: no LoRA), got {cfg.lora_rank}")
    if cfg.lora_rank:
        lora_spec(cfg)
    if cfg.moments_dtype not in ("", *MOMENT_DTYPES):
        raise ConfigError(f"moments_dtype {cfg.moments_dtype!r}: expected empty (the weights' dtype) or one of "
                          f"{', '.join(MOMENT_DTYPES)}")
    if cfg.stochastic_rounding and (cfg.master_fp32 or cfg.compute_dtype != "bfloat16"):
        raise ConfigError("stochastic_rounding rounds bf16 master weights: it needs master_fp32=false and "
                          f"compute_dtype=bfloat16 (got master_fp32={cfg.master_fp32}, compute_dtype={cfg.compute_dtype})")
    if cfg.compute_dtype not in ("bfloat16", "float32", "float16"):
        raise ConfigError(f"compute_dtype {cfg.compute_dtype!r}: expected bfloat16, float32 or float16")
    for name in ("steps", "seq_len", "log_every", "eval_every", "save_every", "keep_last"):
        if getattr(cfg, name) <= 0:
            raise ConfigError(f"{name} must be positive, got {getattr(cfg, name)}")
    if cfg.eval_batches < 0:
        raise ConfigError(f"eval_batches must be >= 0, got {cfg.eval_batches}")
    if cfg.warmup_steps < 0 or cfg.warmup_steps >= cfg.steps:
        raise ConfigError(f"warmup_steps {cfg.warmup_steps} must be in [0, steps={cfg.steps})")
