"""Training-step throughput: Qwen3-VL preset with random weights, frozen vision tower, one
448x448 image per sequence, synthetic tokens without padding (causal flash attention).

    python3 bench/train_step.py --preset qwen3_vl_4b --seq 4096 --batch 1 [--remat full]

Prints tokens/s, MFU (FLOP count in train/metrics_log.py; vs 989 TFLOP/s and vs 790 measured
matmul peak, the HF peer's denominator) and peak device memory.

LoRA on one smaller GPU (issue 35's target: peak <= 24 GiB at 4,096 tokens): adapters of rank 16
on every decoder projection, fp32 adapters and moments, frozen base in bf16:

    python3 bench/train_step.py --preset qwen3_vl_4b --seq 4096 --batch 1 --remat full --lora-rank 16 --master-fp32

fp32-quality full training on one 80 GB card (issue 51): fp32 master weights, Adam's moments in
bf16 (bench/train_memory.py counts 49.1 GB of weights, gradients and moments before activations;
on an H200, XLA_PYTHON_CLIENT_MEM_FRACTION=0.55 caps the pool at ~77 GB to hold it to an 80 GB card):

    python3 bench/train_step.py --preset qwen3_vl_4b --seq 4096 --batch 1 --remat full --master-fp32 --moments-dtype bfloat16

The other option of issue 51, bf16 master weights and moments both rounded stochastically:

    python3 bench/train_step.py --preset qwen3_vl_4b --seq 4096 --batch 1 --remat full --moments-dtype bfloat16 --stochastic-rounding
"""

import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from bench.options import add_batch, add_image, add_json_lines, add_preset, add_seq, append_json_lines, bench_parser  # noqa: E402
from bench.profile_summary import summarise  # noqa: E402
from jax3dc.compilation import CompileClock  # noqa: E402
from jax3dc.xla_flags import TRAINING_GPU_FLAGS, apply_gpu_defaults  # noqa: E402

os.environ.setdefault("XLA_PYTHON_CLIENT_PREALLOCATE", "false")
REMAT_NAMES = ("none", "full", "minimal", "qkv")  # jax3dc/model/layer_stack.py (not imported: jax loads after the flags)


def main() -> None:
    ap = bench_parser(__doc__)
    add_preset(ap)
    add_seq(ap, 4096)
    add_batch(ap, 1)
    ap.add_argument("--remat", default="none", choices=REMAT_NAMES)
    ap.add_argument("--scan", action=argparse.BooleanOptionalAction, default=False,
                    help="decoder layers as one lax.scan, or unrolled (the trainer's default)")
    add_image(ap)
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--master-fp32", action="store_true", help="fp32 master weights (more memory)")
    ap.add_argument("--moments-dtype", default="", choices=("", "float32", "bfloat16"),
                    help="Adam's moments' dtype (TrainConfig.moments_dtype; empty: the master weights')")
    ap.add_argument("--stochastic-rounding", action="store_true",
                    help="bf16 master weights rounded stochastically after each update (without --master-fp32)")
    ap.add_argument("--lora-rank", type=int, default=0, help="> 0: train LoRA adapters of this rank only")
    ap.add_argument("--attention", default=None, help="jax.nn.dot_product_attention implementation, e.g. cudnn")
    ap.add_argument("--mesh", default="1,-1,1", help="data,fsdp,tensor over all visible devices (-1: the rest)")
    add_json_lines(ap)
    ap.add_argument("--profile", help="after timing, trace 2 steps into this directory and summarise it")
    a = ap.parse_args()
    started = time.perf_counter()

    apply_gpu_defaults(TRAINING_GPU_FLAGS)  # the trainer's collective-combining defaults (train/cli.py sets them too)
    # lazy: --help answers before jax and the trainer load (1.1 s; tests/test_bench_options.py runs it)
    import jax

    from train.config import MeshConfig, TrainConfig
    from train.loop import Trainer, make_loader
    from train.metrics_log import peak_flops
    from train.parallel import to_host

    cfg = TrainConfig(init=a.preset, data="synthetic", seq_len=a.seq, batch_size=a.batch, grad_accum=1, steps=a.steps + 2,
                      warmup_steps=1, image_size=a.image, remat=a.remat, scan_layers=a.scan, master_fp32=a.master_fp32,
                      moments_dtype=a.moments_dtype, stochastic_rounding=a.stochastic_rounding, lora_rank=a.lora_rank,
                      mesh=MeshConfig(*(int(x) for x in a.mesh.split(","))))
    trainer = Trainer(cfg, attention_impl=a.attention)
    loader = make_loader(cfg, trainer.model.config, "train", padding=False)
    batches = [next(loader) for _ in range(2)]

    clock, first = CompileClock(), time.perf_counter()
    for i in range(2):  # compile + warm-up
        to_host(trainer.train_step(batches[i % 2])["loss"])
    compiled = time.perf_counter()
    compile_cost = {"first_steps_s": compiled - first, **clock.elapsed()}
    print("compile: " + "  ".join(f"{k} {v:.1f}" for k, v in compile_cost.items()))
    t0 = time.perf_counter()
    for i in range(a.steps):
        m = trainer.train_step(batches[i % 2])
    loss = float(to_host(m["loss"]))
    dt = (time.perf_counter() - t0) / a.steps
    flops = trainer.flops_model().step_flops(a.batch, a.seq) / dt
    dev = jax.devices()[0]
    print(f"device: {dev.device_kind} x{jax.device_count()}  preset {a.preset} batch {a.batch} x {a.seq} "
          f"remat {a.remat} lora_rank {a.lora_rank} master_fp32 {a.master_fp32} moments_dtype {a.moments_dtype or 'master'} "
          f"stochastic_rounding {a.stochastic_rounding}")
    print(f"step_s: {dt:.4f}  tokens_per_s: {a.batch * a.seq / dt:.0f}  tflops: {flops / 1e12:.1f}  loss: {loss:.4f}")
    peak = peak_flops(dev.device_kind)
    if peak:
        print(f"mfu_vs_989: {flops / peak / jax.device_count():.3f}  mfu_vs_790: {flops / 790e12 / jax.device_count():.3f}")
    peaks = [(d.memory_stats() or {}).get("peak_bytes_in_use", 0) / 2**30 for d in jax.local_devices()]
    print(f"peak_mem_gib per device: max {max(peaks):.1f}")
    if a.profile:
        with jax.profiler.trace(a.profile, create_perfetto_trace=True):
            for i in range(2):
                m = trainer.train_step(batches[i % 2])
            to_host(m["loss"])
        summarise(a.profile, top=20)
    if a.json:
        row = {"device": dev.device_kind, "devices": jax.device_count(), "mesh": dict(trainer.mesh.shape),
               "preset": a.preset, "batch": a.batch, "seq": a.seq, "remat": a.remat, "scan": a.scan, "lora_rank": a.lora_rank,
               "master_fp32": a.master_fp32, "moments_dtype": a.moments_dtype,
               "stochastic_rounding": a.stochastic_rounding, "step_s": dt,
               "tokens_per_s": a.batch * a.seq / dt, "tokens_per_s_per_device": a.batch * a.seq / dt / jax.device_count(),
               "mfu_vs_989": flops / 989e12 / jax.device_count(), "peak_mem_gib": max(peaks),
               "setup_and_compile_s": compiled - started, "compile": compile_cost,
               "xla_flags": os.environ.get("XLA_FLAGS", "")}
        append_json_lines(a.json, [row])


if __name__ == "__main__":
    main()
