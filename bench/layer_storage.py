"""Compile time and throughput of one decoder training step by how the layers are stored and
stepped (issue 51: a cold first step ≤ 30 s). The preset's text decoder alone (embedding, its
decoder layers, final norm, tied LM head), fp32 master weights, bf16 compute, AdamW with fp32
moments, `jax.checkpoint` around each layer (the trainer's remat=full), one row of --seq tokens:

  list          a list of per-layer modules, stepped one by one (the trainer's layout today)
  list_scan     the same list stacked at trace time and run as one lax.scan (scan_layers=true)
  stacked_scan  the layers stored stacked (one leading layer axis), run as one lax.scan
  stacked_loop  stored stacked, stepped one by one over static slices

    python3 bench/layer_storage.py --preset qwen3_vl_4b --layout stacked_scan [--unroll 4] --json OUT.jsonl

Prints trace+lower and XLA seconds of the first compile, the step's tokens/s and peak device
memory. One layout per process, so each compile is cold and memory starts empty.
"""

from __future__ import annotations

import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from bench.options import add_json_lines, add_preset, add_seq, append_json_lines, bench_parser  # noqa: E402

LAYOUTS = ("list", "list_scan", "stacked_scan", "stacked_loop")


def main() -> None:
    ap = bench_parser(__doc__)
    add_preset(ap)
    add_seq(ap, 4096)
    ap.add_argument("--layout", choices=LAYOUTS, required=True)
    ap.add_argument("--steps", type=int, default=6)
    ap.add_argument("--layers", type=int, default=0, help="> 0: this many decoder layers instead of the preset's")
    ap.add_argument("--unroll", type=int, default=1,
                    help="the scan layouts: layers per loop iteration (lax.scan unroll); compile grows with it, "
                         "and XLA may fuse and schedule across the layers of one iteration")
    ap.add_argument("--compile-only", action="store_true",
                    help="lower and compile from shapes alone (no weights allocated): compile times on any machine")
    add_json_lines(ap)
    a = ap.parse_args()
    # lazy: --help answers before jax loads
    import dataclasses

    import jax
    import jax.numpy as jnp
    import optax
    from flax import nnx

    from jax3dc.model import config as presets
    from jax3dc.model.text import DecoderLayer

    text = getattr(presets, a.preset)().text
    if a.layers:
        text = dataclasses.replace(text, num_hidden_layers=a.layers)
    n_layers, gpu = text.num_hidden_layers, jax.default_backend() == "gpu"
    kw = dict(dtype=jnp.bfloat16, param_dtype=jnp.float32, attention_impl="cudnn" if gpu else None)

    def one_layer(rngs: nnx.Rngs) -> DecoderLayer:
        return DecoderLayer(text, rngs=rngs, **kw)

    def build() -> tuple[nnx.GraphDef, dict]:
        if a.layout.startswith("stacked"):
            make = nnx.vmap(one_layer, in_axes=0, out_axes=0)
            graphdef, layers = nnx.split(make(nnx.Rngs(0).fork(split=n_layers)))
        else:
            modules = [one_layer(nnx.Rngs(i)) for i in range(n_layers)]
            graphdef, layers = nnx.split(modules[0])[0], [nnx.state(m) for m in modules]
        params = {"embed": 0.02 * jax.random.normal(key, (text.vocab_size, text.hidden_size)), "layers": layers,
                  "norm": jnp.ones((text.hidden_size,))}
        return graphdef, jax.tree.map(lambda x: x.get_value() if isinstance(x, nnx.Variable) else x, params,
                                      is_leaf=lambda x: isinstance(x, nnx.Variable))

    key = jax.random.key(1)
    if a.compile_only:  # shapes only: the graph is static, the weights are never allocated
        graphdef = None

        def shapes() -> dict:
            nonlocal graphdef
            graphdef, params = build()
            return params

        params = jax.eval_shape(shapes)
    else:
        graphdef, params = build()
    seq, hd = a.seq, text.head_dim
    inv = 1.0 / (text.rope_theta ** (jnp.arange(0, hd, 2) / hd))
    ang = jnp.arange(seq)[:, None] * inv[None]
    cos, sin = (jnp.concatenate([f(ang)] * 2, -1)[None] for f in (jnp.cos, jnp.sin))

    def run_layer(h, state):
        return nnx.merge(graphdef, state)(h, cos, sin, None)[0]

    body = jax.checkpoint(run_layer, policy=jax.checkpoint_policies.nothing_saveable, prevent_cse=False)

    def decoder(layer_params, x):
        if a.layout == "list":
            for state in layer_params:
                x = body(x, state)
            return x
        if a.layout == "stacked_loop":
            for i in range(n_layers):
                x = body(x, jax.tree.map(lambda s: s[i], layer_params))
            return x
        stacked = layer_params if a.layout == "stacked_scan" else jax.tree.map(
            lambda *s: jnp.stack([t.astype(jnp.bfloat16) if t.ndim >= 2 else t for t in s]), *layer_params)
        return jax.lax.scan(lambda h, s: (body(h, s), None), x, stacked, unroll=a.unroll)[0]

    def loss_fn(p, ids):
        x = jnp.take(p["embed"], ids, axis=0).astype(jnp.bfloat16)
        x = decoder(p["layers"], x)
        x = x * jax.lax.rsqrt(jnp.mean(jnp.square(x.astype(jnp.float32)), -1, keepdims=True) + 1e-6) * p["norm"]
        logits = (x.astype(jnp.bfloat16) @ p["embed"].astype(jnp.bfloat16).T).astype(jnp.float32)
        return optax.softmax_cross_entropy_with_integer_labels(logits[:, :-1], ids[:, 1:]).mean()

    opt = optax.chain(optax.clip_by_global_norm(1.0), optax.adamw(1e-5, weight_decay=0.01))
    opt_state = jax.eval_shape(opt.init, params) if a.compile_only else opt.init(params)

    def step(p, s, ids):
        loss, g = jax.value_and_grad(loss_fn)(p, ids)
        updates, s = opt.update(g, s, p)
        return optax.apply_updates(p, updates), s, loss

    ids = jax.ShapeDtypeStruct((1, seq), jnp.int32) if a.compile_only else jax.random.randint(
        key, (1, seq), 0, text.vocab_size)
    jitted = jax.jit(step, donate_argnums=(0, 1))
    t0 = time.perf_counter()
    lowered = jitted.lower(params, opt_state, ids)
    t1 = time.perf_counter()
    compiled = lowered.compile()
    t2 = time.perf_counter()
    row = {"bench": "layer_storage", "preset": a.preset, "layers": n_layers, "layout": a.layout, "unroll": a.unroll, "seq": seq,
           "device": jax.devices()[0].device_kind, "trace_lower_s": t1 - t0, "xla_s": t2 - t1}
    name = a.layout if a.unroll == 1 or not a.layout.endswith("scan") else f"{a.layout} u{a.unroll}"
    if a.compile_only:
        print(f"{name:16s} trace+lower {row['trace_lower_s']:.1f} s, XLA {row['xla_s']:.1f} s", flush=True)
        append_json_lines(a.json, [row])
        return
    params, opt_state, loss = compiled(params, opt_state, ids)
    loss.block_until_ready()
    t3 = time.perf_counter()
    for _ in range(a.steps):
        params, opt_state, loss = compiled(params, opt_state, ids)
    loss.block_until_ready()
    step_s = (time.perf_counter() - t3) / a.steps
    stats = jax.devices()[0].memory_stats() or {}
    row |= {"first_step_s": t3 - t2, "step_s": step_s, "tokens_per_s": seq / step_s, "loss": float(loss),
            "peak_mem_gib": stats.get("peak_bytes_in_use", 0) / 2**30}
    print(f"{name:16s} trace+lower {row['trace_lower_s']:.1f} s, XLA {row['xla_s']:.1f} s, "
          f"{row['tokens_per_s']:.0f} tokens/s, peak {row['peak_mem_gib']:.1f} GiB, loss {row['loss']:.3f}", flush=True)
    append_json_lines(a.json, [row])


if __name__ == "__main__":
    main()
