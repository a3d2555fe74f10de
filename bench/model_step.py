"""Model-level GPU benchmark of the fine-tuning compute, comparable with hf_peer.py's training
step: random bf16 weights, one image of ``--image`` pixels per row, forward + backward of the
mean token NLL w.r.t. the decoder (the vision tower is frozen: forward only), no optimiser
update. Prints tokens/s and TFLOP/s by hf_peer's FLOP formula, e.g. to choose the attention
kernel and remat. (Decoding is measured by bench/decode.py.)

    python3 -m bench.model_step --preset qwen3_vl_4b --batch 4 --length 2048 --impl cudnn --remat
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
from flax import nnx

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from anywhere: the repo root's packages
from bench.options import add_attention_impl, add_batch, add_image, add_preset, add_seq, bench_parser  # noqa: E402
from jax3dc.model.config import Qwen3VLConfig  # noqa: E402
from jax3dc.model.qwen3_vl import Qwen3VL  # noqa: E402
from jax3dc.model.random_weights import build_random  # noqa: E402


def image_batch(cfg: Qwen3VLConfig, rows: int, length: int, image: int, seed: int = 0):
    """input_ids with one image per row at the start, pixel_values and grids (as the processor)."""
    v = cfg.vision
    g = image // v.patch_size
    n_tok = g * g // v.spatial_merge_size**2
    rng = np.random.default_rng(seed)
    ids = rng.integers(0, 150000 if cfg.text.vocab_size > 150000 else cfg.text.vocab_size // 2,
                       (rows, length)).astype(np.int32)
    ids[:, 0] = cfg.vision_start_token_id
    ids[:, 1:1 + n_tok] = cfg.image_token_id
    ids[:, 1 + n_tok] = cfg.vision_end_token_id
    pixels = rng.standard_normal((rows * g * g, v.patch_dim)).astype(np.float32)
    grid = np.tile(np.array([[1, g, g]], np.int32), (rows, 1))
    return jnp.asarray(ids), jnp.asarray(pixels, jnp.bfloat16), jnp.asarray(grid), g * g, n_tok


def timed(fn, *args, repeat: int) -> float:
    jax.block_until_ready(fn(*args))
    t0 = time.perf_counter()
    for _ in range(repeat):
        out = fn(*args)
    jax.block_until_ready(out)
    return (time.perf_counter() - t0) / repeat


def bench_train(model: Qwen3VL, cfg: Qwen3VLConfig, rows: int, length: int, image: int, repeat: int) -> dict:
    ids, pixels, grid, patches, n_tok = image_batch(cfg, rows, length, image)
    graphdef, decoder, rest = nnx.split(model, lambda path, _: path[0] != "visual", ...)

    @jax.jit
    def grads(decoder, rest, ids, pixels, grid):
        def loss(decoder):
            m = nnx.merge(graphdef, decoder, rest)
            hidden = m(ids, pixel_values=pixels, image_grid_thw=grid, return_hidden=True, vision_window=patches)
            logits = m.logits(hidden[:, :-1]).astype(jnp.float32)
            nll = -jnp.take_along_axis(jax.nn.log_softmax(logits), ids[:, 1:, None], axis=-1)
            return nll.mean()
        return jax.value_and_grad(loss)(decoder)

    t0 = time.perf_counter()
    jax.block_until_ready(grads(decoder, rest, ids, pixels, grid))
    compile_s = time.perf_counter() - t0
    dt = timed(grads, decoder, rest, ids, pixels, grid, repeat=repeat)
    t = cfg.text
    layer = (t.hidden_size * t.head_dim * (t.num_attention_heads * 2 + t.num_key_value_heads * 2)
             + 3 * t.hidden_size * t.intermediate_size)
    n_vis = sum(int(np.prod(x.shape)) for x in jax.tree.leaves(nnx.state(model.visual)))
    flops = (6 * (t.num_hidden_layers * layer + t.hidden_size * t.vocab_size)
             + 6 * t.num_hidden_layers * length * t.num_attention_heads * t.head_dim) * rows * length
    flops += 2 * n_vis * patches * rows
    return {"train_rows": rows, "train_length": length, "train_compile_s": round(compile_s, 1),
            "train_step_s": round(dt, 4), "train_tokens_per_s": round(rows * length / dt),
            "train_tflops": round(flops / dt / 1e12, 1)}


def main(argv: list[str] | None = None) -> int:
    ap = bench_parser(__doc__)
    add_preset(ap)
    add_batch(ap, 4)
    add_seq(ap, 2048, flag="--length")
    add_image(ap)
    add_attention_impl(ap, "xla")
    ap.add_argument("--remat", action="store_true", help="recompute each decoder layer in the backward pass")
    ap.add_argument("--repeat", type=int, default=5, help="timed training steps")
    ap.add_argument("--out", help="write the figures as JSON here too")
    args = ap.parse_args(argv)
    cfg = getattr(Qwen3VLConfig, args.preset)()
    res: dict = {"preset": args.preset, "impl": args.impl, "remat": args.remat, "device": str(jax.devices()[0])}
    model = build_random(lambda: Qwen3VL(cfg, rngs=nnx.Rngs(0), dtype=jnp.bfloat16, param_dtype=jnp.bfloat16,
                                         attention_impl=args.impl, remat="full" if args.remat else "none"))
    res.update(bench_train(model, cfg, args.batch, args.length, args.image, args.repeat))
    print(json.dumps(res), flush=True)
    if args.out:
        with open(args.out, "w") as f:
            json.dump(res, f, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
