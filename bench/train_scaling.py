"""Training-step throughput of Qwen3-VL across mesh layouts on one host (issue 10's scaling run).

One full fine-tuning step — forward, backward w.r.t. the decoder (vision tower and mergers frozen:
forward only, no optimiser state), AdamW update — with random bf16 weights, one 448x448 image per
row, ``--seq`` tokens per row and ``--per-device-batch`` rows per device. Each layout is a
``data x fsdp x tensor`` mesh over the first d*f*t devices; parameters are placed by the logical
rules table of ``jax3dc.sharding``, the batch over (data, fsdp). Prints per layout: step time,
tokens/s (total and per device), MFU by hf_peer.py's FLOP count against 989 TFLOP/s (H100/H200
dense bf16 peak) and against 790 (the matmul rate measured on these GPUs), peak memory per device,
compile time, and the scaling efficiency of tokens/s per device against the 1-device layout.

    python3 bench/train_scaling.py --preset qwen3_vl_4b --layouts 1x1x1 1x8x1 1x4x2
    python3 bench/train_scaling.py --preset tiny --seq 128 --image 32 --layouts 1x1x1 1x4x2   # CPU
"""

from __future__ import annotations

import json
import sys
import time
from functools import partial
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import optax
from flax import nnx
from jax.sharding import NamedSharding, PartitionSpec as P

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from anywhere: the repo root's packages
from bench.model_step import image_batch  # noqa: E402
from bench.options import (add_attention_impl, add_image, add_json_lines, add_preset, add_seq,  # noqa: E402
                           append_json_lines, bench_parser)
from jax3dc.model.config import Qwen3VLConfig  # noqa: E402
from jax3dc.model.qwen3_vl import Qwen3VL  # noqa: E402
from jax3dc.model.random_weights import build_random  # noqa: E402
from jax3dc.sharding import make_mesh, model_shardings  # noqa: E402
from train.metrics_log import PEAK_FLOPS, FlopsModel  # noqa: E402

PEAK_MEASURED_BF16 = 790e12  # the bf16 matmul rate measured on these GPUs (hf_peer.py's denominator)


def run_layout(cfg: Qwen3VLConfig, layout: tuple[int, int, int], args) -> dict:
    d, f, t = layout
    n = d * f * t
    mesh = make_mesh(d, f, t, devices=jax.devices()[:n])
    make = lambda: Qwen3VL(cfg, rngs=nnx.Rngs(0), dtype=jnp.bfloat16, param_dtype=jnp.bfloat16,  # noqa: E731
                           attention_impl=args.impl, remat="full" if args.remat else "none")
    model = build_random(make, shardings=model_shardings(nnx.eval_shape(make), mesh))
    graphdef, decoder, rest = nnx.split(model, lambda path, _: path[0] != "visual", ...)
    n_vis = sum(int(np.prod(x.shape)) for x in jax.tree.leaves(nnx.state(model.visual)))
    rows = args.per_device_batch * d * f  # tensor-parallel devices share rows
    ids, pixels, grid, patches, _ = image_batch(cfg, rows, args.seq, args.image)
    batch_sharding = NamedSharding(mesh, P(("data", "fsdp")))
    ids, pixels, grid = (jax.device_put(x, batch_sharding) for x in (ids, pixels, grid))
    opt = optax.adamw(1e-5, mu_dtype=jnp.float32)
    opt_state = jax.jit(opt.init)(decoder)

    @partial(jax.jit, donate_argnums=(0, 1))
    def step(decoder, opt_state, rest, ids, pixels, grid):
        def loss(decoder):
            m = nnx.merge(graphdef, decoder, rest)
            hidden = m(ids, pixel_values=pixels, image_grid_thw=grid, return_hidden=True,
                       vision_window=patches)
            logits = m.logits(hidden[:, :-1]).astype(jnp.float32)
            nll = -jnp.take_along_axis(jax.nn.log_softmax(logits), ids[:, 1:, None], axis=-1)
            return nll.mean()
        value, grads = jax.value_and_grad(loss)(decoder)
        updates, opt_state = opt.update(grads, opt_state, decoder)
        return optax.apply_updates(decoder, updates), opt_state, value

    with jax.set_mesh(mesh):
        t0 = time.perf_counter()
        decoder, opt_state, value = step(decoder, opt_state, rest, ids, pixels, grid)
        jax.block_until_ready(value)
        compile_s = time.perf_counter() - t0
        t0 = time.perf_counter()
        for _ in range(args.steps):
            decoder, opt_state, value = step(decoder, opt_state, rest, ids, pixels, grid)
        jax.block_until_ready(value)
        dt = (time.perf_counter() - t0) / args.steps
    flops = FlopsModel.from_model_config(cfg, n_vis, patches).step_flops(rows, args.seq)
    peaks = [dev.memory_stats().get("peak_bytes_in_use") for dev in mesh.devices.flat
             if dev.memory_stats()] if mesh.devices.flat[0].platform == "gpu" else []
    tokens = rows * args.seq
    return {"layout": f"{d}x{f}x{t}", "devices": n, "rows": rows, "seq": args.seq,
            "remat": args.remat, "impl": args.impl, "loss": float(value), "compile_s": round(compile_s, 1),
            "step_s": round(dt, 4), "tokens_per_s": round(tokens / dt),
            "tokens_per_s_per_device": round(tokens / dt / n),
            "mfu_vs_989": round(flops / dt / n / PEAK_FLOPS["H100"], 3),
            "mfu_vs_790": round(flops / dt / n / PEAK_MEASURED_BF16, 3),
            "peak_gib_per_device": round(max(peaks) / 2**30, 1) if peaks else None}


def main(argv: list[str] | None = None) -> int:
    ap = bench_parser(__doc__)
    add_preset(ap)
    add_seq(ap, 8192)
    ap.add_argument("--per-device-batch", type=int, default=2, help="rows per data/fsdp device")
    add_image(ap)
    ap.add_argument("--layouts", nargs="+", default=["1x1x1", "1x8x1", "1x4x2"],
                    help="meshes as DATAxFSDPxTENSOR")
    add_attention_impl(ap, "cudnn")
    ap.add_argument("--no-remat", dest="remat", action="store_false", help="keep activations")
    ap.add_argument("--steps", type=int, default=3, help="timed steps per layout")
    add_json_lines(ap, "--out")
    args = ap.parse_args(argv)
    cfg = getattr(Qwen3VLConfig, args.preset)()
    results = []
    for spec in args.layouts:
        layout = tuple(int(x) for x in spec.split("x"))
        try:
            res = run_layout(cfg, layout, args)
        except Exception as e:  # one failed layout (e.g. out of memory) must not hide the others
            res = {"layout": spec, "error": repr(e)[:400]}
        if results and "tokens_per_s_per_device" in res and "tokens_per_s_per_device" in results[0]:
            res["scaling_efficiency"] = round(res["tokens_per_s_per_device"]
                                              / results[0]["tokens_per_s_per_device"], 3)
        results.append(res)
        print(json.dumps(res), flush=True)
        append_json_lines(args.out, [res])
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
