"""Packed-row attention on a GPU: cuDNN's ragged flash attention against the dense block mask
(the reference: jax3dc/model/packed_attention.py) — equal outputs and gradients on the scored
slots, and the time and memory of each, forward + backward, at the 4B decoder's head shape.

    python3 bench/packed_attention.py [--length 4096] [--examples 6]
"""

from __future__ import annotations

import argparse
import json
import time

import jax
import jax.numpy as jnp
import numpy as np

from jax3dc.model.packed_attention import packed_attention, packed_rows


def segments(length: int, examples: int, rng: np.random.Generator) -> np.ndarray:
    """One row of `examples` contiguous examples of random lengths, then some padding."""
    cuts = np.sort(rng.choice(np.arange(1, int(length * 0.9)), examples - 1, replace=False))
    sizes = np.diff(np.concatenate([[0], cuts, [int(length * 0.9)]]))
    return np.concatenate([np.repeat(np.arange(1, examples + 1), sizes), np.zeros(length - sizes.sum(), int)])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--length", type=int, default=4096)
    ap.add_argument("--examples", type=int, default=6)
    ap.add_argument("--max-examples", type=int, default=12, help="slots per row (the trainer: images per row)")
    ap.add_argument("--heads", type=int, default=32)
    ap.add_argument("--kv-heads", type=int, default=8)
    ap.add_argument("--head-dim", type=int, default=128)
    a = ap.parse_args()
    rng = np.random.default_rng(0)
    seg = jnp.asarray(np.stack([segments(a.length, a.examples, rng) for _ in range(2)]), jnp.int32)
    rows = packed_rows(seg, a.max_examples)
    shape = lambda h: (2, a.length, h, a.head_dim)  # noqa: E731
    q = jnp.asarray(rng.standard_normal(shape(a.heads)), jnp.bfloat16)
    k, v = (jnp.asarray(rng.standard_normal(shape(a.kv_heads)), jnp.bfloat16) for _ in range(2))
    scored = (seg > 0)[:, :, None, None]

    def loss(impl):
        def f(q, k, v):
            out = packed_attention(q, k, v, rows, impl).astype(jnp.float32)
            return jnp.sum(jnp.where(scored, out, 0.0) ** 2), out
        return jax.jit(jax.value_and_grad(f, argnums=(0, 1, 2), has_aux=True))

    res: dict = {"device": jax.devices()[0].device_kind, "length": a.length, "examples": a.examples}
    outs = {}
    for impl in ("xla", "cudnn"):
        fn = loss(impl)
        jax.block_until_ready(fn(q, k, v))
        t0 = time.perf_counter()
        for _ in range(10):
            r = fn(q, k, v)
        jax.block_until_ready(r)
        res[f"{impl}_ms"] = (time.perf_counter() - t0) / 10 * 1e3
        res[f"{impl}_temp_gib"] = fn.lower(q, k, v).compile().memory_analysis().temp_size_in_bytes / 2**30
        outs[impl] = r
    (_, out_x), g_x = outs["xla"]
    (_, out_c), g_c = outs["cudnn"]
    mask = np.asarray(scored)
    res["max_abs_out_diff"] = float(np.max(np.abs(np.where(mask, out_x - out_c, 0))))
    res["max_abs_grad_diff"] = [float(np.max(np.abs(np.where(mask, gx.astype(jnp.float32) - gc.astype(jnp.float32), 0))))
                                for gx, gc in zip(g_x, g_c)]
    res["finite"] = bool(all(np.isfinite(np.asarray(x, np.float32)).all() for x in (out_c, *g_c)))
    res["max_abs_grad"] = [float(np.max(np.abs(gx.astype(jnp.float32)))) for gx in g_x]
    print(json.dumps(res), flush=True)


if __name__ == "__main__":
    main()
