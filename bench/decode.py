"""Decode throughput and peak memory of Qwen3-VL generation (random weights).

Workload of the stage-2 model at inference: one 448x448 image (28x28 patches of 16 -> 196
merged image tokens) inside a 600-token prompt, then 512 generated tokens, at batch 1 and 32.
Stop tokens are disabled so every row generates exactly ``--new-tokens`` tokens.

    python3 bench/decode.py --preset qwen3_vl_4b          # GPU: the figures we report
    python3 bench/decode.py --preset tiny                 # CPU smoke test, seconds

Prints one readable line and one JSON line (``{"bench": "decode", ...}``) per batch size.
Decode tokens/s = batch * new_tokens / wall time of the jitted decode loop (compiled in a warm-up
run of the same shapes, timed on the second run). Peak memory is the device allocator's
``peak_bytes_in_use`` since start-up (so it includes model creation); batch sizes run in
increasing order, so the first figure is that batch size's own peak.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from dataclasses import dataclass

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from bench.options import add_json_lines, add_preset, append_json_lines  # noqa: E402
from bench.profile_summary import summarise  # noqa: E402
from jax3dc.xla_flags import GENERATION_GPU_FLAGS, apply_gpu_defaults  # noqa: E402

apply_gpu_defaults(GENERATION_GPU_FLAGS)  # what `jax3dc predict` and `eval` decode with
import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from flax import nnx  # noqa: E402

from jax3dc.model.config import Qwen3VLConfig  # noqa: E402
from jax3dc.generate import GenerationConfig, decode, prefill, prefill_in_chunks  # noqa: E402
from jax3dc.model.params import param_count  # noqa: E402
from jax3dc.model.qwen3_vl import Qwen3VL  # noqa: E402
from jax3dc.model.random_weights import build_random  # noqa: E402


@dataclass(frozen=True)
class Preset:
    config: Qwen3VLConfig
    prompt_tokens: int
    image_side: int
    new_tokens: int
    batches: tuple[int, ...]
    prefill_rows: int
    targets: dict  # batch -> minimum decode tokens/s; "peak_gb_batch1" -> maximum


PRESETS = {
    "qwen3_vl_4b": Preset(Qwen3VLConfig.qwen3_vl_4b(), prompt_tokens=600, image_side=448, new_tokens=512,
                          batches=(1, 32), prefill_rows=8,
                          targets={1: 250.0, 32: 4000.0, "peak_gb_batch1": 12.0}),
    "tiny": Preset(Qwen3VLConfig.tiny(), prompt_tokens=64, image_side=32, new_tokens=32,
                   batches=(1, 4), prefill_rows=2, targets={}),
}


def build_model(config: Qwen3VLConfig, dtype) -> Qwen3VL:
    """Random weights directly in ``dtype`` on the device, one small fill program per shape."""
    return build_random(lambda: Qwen3VL(config, rngs=nnx.Rngs(0), dtype=dtype, param_dtype=dtype))


def build_prompts(preset: Preset, batch: int, seed: int = 0):
    """``batch`` prompts of ``prompt_tokens`` ids, each with its own image in the middle.

    Pixel values are random numbers in the normalised range [-1, 1] (image preprocessing is not
    what is measured, and this keeps the benchmark free of PIL): an ``image_side`` square image
    is ``image_side / patch_size`` patches a side, already a multiple of the merge size.
    """
    config, vision = preset.config, preset.config.vision
    side = preset.image_side // vision.patch_size
    if preset.image_side % vision.patch_size or side % vision.spatial_merge_size:
        raise ValueError(f"image side {preset.image_side} is not a multiple of patch x merge size")
    pads = side * side // vision.spatial_merge_size**2
    text = preset.prompt_tokens - pads - 2
    if text < 2:
        raise ValueError(f"prompt of {preset.prompt_tokens} tokens cannot hold {pads} image tokens")
    rng = np.random.default_rng(seed)
    pixels = rng.uniform(-1.0, 1.0, (batch * side * side, vision.patch_dim)).astype(np.float32)
    grid = np.tile(np.array([[1, side, side]], np.int32), (batch, 1))
    ids = np.empty((batch, preset.prompt_tokens), np.int32)
    for row in range(batch):
        words = rng.integers(0, config.vision_start_token_id, text)
        ids[row] = np.concatenate([words[: text // 4], [config.vision_start_token_id],
                                   np.full(pads, config.image_token_id), [config.vision_end_token_id],
                                   words[text // 4:]])
    return ids, pixels, grid, pads


def peak_bytes() -> int | None:
    stats = jax.devices()[0].memory_stats()
    return None if not stats else int(stats.get("peak_bytes_in_use", 0))


def run_batch(model, preset: Preset, batch: int, generation: GenerationConfig, prefill_rows: int,
              profile: str | None = None) -> dict:
    ids, pixels, grid, pads = build_prompts(preset, batch)

    def once() -> tuple[float, float, np.ndarray]:
        start = time.perf_counter()
        if prefill_rows < batch:
            state = prefill_in_chunks(model, ids, None, pixels, grid, generation.max_new_tokens, prefill_rows)
        else:
            state = prefill(model, ids, None, pixels, grid, generation.max_new_tokens)
        jax.block_until_ready(state)
        middle = time.perf_counter()
        out = decode(model, state, generation)
        lengths = np.asarray(jax.block_until_ready(out.lengths))
        return middle - start, time.perf_counter() - middle, lengths

    print(f"batch {batch}: compiling and warming up", file=sys.stderr, flush=True)
    once()  # compile prefill and decode for these shapes
    prefill_s, decode_s, lengths = once()
    generated = int(lengths.sum())
    peak = peak_bytes()
    if profile:  # a third, traced run: kernel time per kind and launch counts

        with jax.profiler.trace(profile, create_perfetto_trace=True):
            once()
        summarise(profile, top=25)
    return {
        "bench": "decode",
        "batch": batch,
        "prompt_tokens": int(ids.shape[1]),
        "image_tokens": pads,
        "new_tokens": generation.max_new_tokens,
        "generated_tokens": generated,
        "prefill_s": round(prefill_s, 4),
        "decode_s": round(decode_s, 4),
        "decode_tokens_per_s": round(generated / decode_s, 1),
        "end_to_end_tokens_per_s": round(generated / (prefill_s + decode_s), 1),
        "ms_per_step": round(1000 * decode_s / generation.max_new_tokens, 3),
        "peak_memory_gb": None if peak is None else round(peak / 1e9, 3),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description="Measure Qwen3-VL generation speed (tokens/s) and peak device memory with random weights.")
    add_preset(parser, choices=sorted(PRESETS), help="model size and workload: qwen3_vl_4b (GPU) or tiny (CPU smoke test)")
    parser.add_argument("--batch", type=int, nargs="+", help="batch sizes (default: the preset's, e.g. 1 32)")
    parser.add_argument("--new-tokens", type=int, help="tokens generated per row (default: 512 for 4B)")
    parser.add_argument("--prefill-rows", type=int, help="rows per prefill chunk (bounds prompt-pass memory)")
    parser.add_argument("--dtype", choices=("bfloat16", "float32"), default="bfloat16",
                        help="parameter and compute dtype")
    add_json_lines(parser, "--json-out")
    parser.add_argument("--profile", help="trace one more run of the first batch size into this folder and summarise it")
    parser.add_argument("--compile-cache", help="persistent XLA compilation cache folder (faster reruns)")
    args = parser.parse_args(argv)
    if args.compile_cache:
        jax.config.update("jax_compilation_cache_dir", args.compile_cache)

    preset = PRESETS[args.preset]
    batches = tuple(sorted(args.batch or preset.batches))
    generation = GenerationConfig(max_new_tokens=args.new_tokens or preset.new_tokens, stop_ids=())
    prefill_rows = args.prefill_rows or preset.prefill_rows

    print(f"building {args.preset} with random {args.dtype} weights", file=sys.stderr, flush=True)
    start = time.perf_counter()
    model = build_model(preset.config, jnp.dtype(args.dtype))
    jax.block_until_ready(nnx.state(model))
    header = {"bench": "decode_setup", "preset": args.preset, "device": str(jax.devices()[0]),
              "jax": jax.__version__, "dtype": args.dtype, "params": param_count(model),
              "model_build_s": round(time.perf_counter() - start, 2)}
    lines = [header]
    print(json.dumps(header), flush=True)
    for batch in batches:
        result = {"preset": args.preset, **run_batch(model, preset, batch, generation, prefill_rows,
                                                    args.profile if batch == batches[0] else None)}
        target = preset.targets.get(batch)
        if target is not None:
            result["target_tokens_per_s"] = target
            result["meets_target"] = result["decode_tokens_per_s"] >= target
        if batch == 1 and "peak_gb_batch1" in preset.targets and result["peak_memory_gb"] is not None:
            result["peak_target_gb"] = preset.targets["peak_gb_batch1"]
            result["meets_peak_target"] = result["peak_memory_gb"] < preset.targets["peak_gb_batch1"]
        print(f"batch {batch}: {result['decode_tokens_per_s']} tok/s decode "
              f"({result['ms_per_step']} ms/step), prefill {result['prefill_s']} s, "
              f"peak {result['peak_memory_gb']} GB", flush=True)
        print(json.dumps(result), flush=True)
        lines.append(result)
    append_json_lines(args.json_out, lines)
    return 0


if __name__ == "__main__":
    sys.exit(main())
