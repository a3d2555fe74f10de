"""Training-step throughput: Qwen3-VL preset with random weights, frozen vision tower, one
448x448 image per sequence, synthetic tokens without padding (causal flash attention).

    python3 bench/train_step.py --preset qwen3_vl_4b --seq 4096 --batch 1 [--remat full]

Prints tokens/s, MFU (FLOP count in train/metrics_log.py; vs 989 TFLOP/s and vs 790 measured
matmul peak, the HF peer's denominator) and peak device memory.
"""

import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
os.environ.setdefault("XLA_PYTHON_CLIENT_PREALLOCATE", "false")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--preset", default="qwen3_vl_4b")
    ap.add_argument("--seq", type=int, default=4096)
    ap.add_argument("--batch", type=int, default=1)
    ap.add_argument("--remat", default="none", choices=("none", "full"))
    ap.add_argument("--image", type=int, default=448)
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--master-fp32", action="store_true", help="fp32 master weights (more memory)")
    ap.add_argument("--attention", default=None, help="jax.nn.dot_product_attention implementation, e.g. cudnn")
    a = ap.parse_args()
    import jax

    from train.config import TrainConfig
    from train.loop import Trainer, make_loader
    from train.metrics_log import peak_flops
    from train.parallel import to_host

    cfg = TrainConfig(init=a.preset, seq_len=a.seq, batch_size=a.batch, grad_accum=1, steps=a.steps + 2,
                      warmup_steps=1, image_size=a.image, remat=a.remat, master_fp32=a.master_fp32)
    trainer = Trainer(cfg, attention_impl=a.attention)
    loader = make_loader(cfg, trainer.model.config, "train", padding=False)
    batches = [next(loader) for _ in range(2)]
    for i in range(2):  # compile + warm-up
        to_host(trainer.train_step(batches[i % 2])["loss"])
    t0 = time.perf_counter()
    for i in range(a.steps):
        m = trainer.train_step(batches[i % 2])
    loss = float(to_host(m["loss"]))
    dt = (time.perf_counter() - t0) / a.steps
    flops = trainer.flops_model().step_flops(a.batch, a.seq) / dt
    dev = jax.devices()[0]
    print(f"device: {dev.device_kind} x{jax.device_count()}  preset {a.preset} batch {a.batch} x {a.seq} "
          f"remat {a.remat}")
    print(f"step_s: {dt:.4f}  tokens_per_s: {a.batch * a.seq / dt:.0f}  tflops: {flops / 1e12:.1f}  loss: {loss:.4f}")
    peak = peak_flops(dev.device_kind)
    if peak:
        print(f"mfu_vs_989: {flops / peak / jax.device_count():.3f}  mfu_vs_790: {flops / 790e12 / jax.device_count():.3f}")
    stats = dev.memory_stats() or {}
    if "peak_bytes_in_use" in stats:
        print(f"peak_mem_gib: {stats['peak_bytes_in_use'] / 2**30:.1f}")


if __name__ == "__main__":
    main()
