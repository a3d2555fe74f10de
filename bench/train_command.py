"""The training command users run, timed: `jax3dc train` on real shards (loader, packing,
checkpointing on) with the HF transformers peer (`hf_peer.py`) run after it in the same call.

    python3 bench/train_command.py --data SHARDS --peer ../shared/bench/hf_peer.py \\
        --out OUT [--preset qwen3_vl_4b] [--seq 4096] [--set master_fp32=false ...]

The figures are the run's own metrics log (train/loop.py): compile_s of the first step, then
the median tokens/s and MFU over the logged intervals after the first (the first interval holds
the loader's warm-up); every interval's figure is kept too, so the cost of a checkpoint save
inside one interval shows beside the steady rate. Tokens/s counts every slot of a packed row, as the peer counts its rows.
MFU here is against 790 TFLOP/s,
the bf16 matmul rate measured on an H100 (the peer's denominator), as well as against the data
sheet's 989.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from bench.options import add_batch, add_json_lines, add_preset, add_seq, append_json_lines, bench_parser  # noqa: E402

PEAK_MEASURED_BF16 = 790e12
PEAK_DATASHEET = 989e12


def run_train(a: argparse.Namespace, out_dir: str) -> tuple[dict, float]:
    """Runs the command; returns its summary from metrics.jsonl and the command's wall seconds."""
    settings = [f"data={a.data}", f"seq_len={a.seq}", f"batch_size={a.batch}", f"grad_accum={a.accum}",
                f"steps={a.steps}", f"log_every={a.log_every}", f"save_every={a.save_every}", "keep_last=1",
                "eval_batches=0", "export_hf=false", f"loader_workers={a.loader_workers}", "warmup_steps=5", *a.set]
    cmd = [sys.executable, "-m", "jax3dc.cli", "train", "--init", a.preset, "--output-dir", out_dir]
    for s in settings:
        cmd += ["--set", s]
    print("$", " ".join(cmd), flush=True)
    started = time.perf_counter()
    subprocess.run(cmd, check=True)
    wall = time.perf_counter() - started
    rows = [json.loads(line) for line in open(os.path.join(out_dir, "metrics.jsonl"))]
    train = [r for r in rows if r.get("kind", "train") == "train"]
    first = next(r for r in train if "compile_s" in r)
    compile_s = first["compile_s"]
    timed = [r for r in train if "tokens_per_s" in r][1:]  # the first interval warms the loader up
    if not timed:
        raise SystemExit(f"{out_dir}/metrics.jsonl: fewer than two logged intervals; raise --steps")
    median = lambda k: float(np.median([r[k] for r in timed]))  # noqa: E731
    summary = {"compile_s": compile_s, **{k: first[k] for k in ("trace_s", "lower_s", "xla_s", "compiles") if k in first},
               "tokens_per_s": median("tokens_per_s"),
               "mfu_vs_989": median("mfu") if "mfu" in timed[0] else None,
               "data_wait_frac": median("data_wait_frac"), "final_loss": train[-1].get("loss"),
               "interval_tokens_per_s": [r["tokens_per_s"] for r in timed],
               "save_blocked_s": [round(r["save_s"], 2) for r in train if "save_s" in r],
               "losses": {r["step"]: r["loss"] for r in train if "loss" in r}}
    if summary["mfu_vs_989"] is not None:
        summary["mfu_vs_790"] = summary["mfu_vs_989"] * PEAK_DATASHEET / PEAK_MEASURED_BF16
    return summary, wall


def run_peer(peer: str, seq: int, out_dir: str) -> dict:
    """The HF peer's training step at batch 1 x `seq` (no generation), in its own process."""
    env = dict(os.environ, B="1", L=str(seq), GEN_B="", OUT=out_dir)
    subprocess.run([sys.executable, peer], check=True, env=env)
    with open(os.path.join(out_dir, "hf_peer.json")) as f:
        return json.load(f)


def add_run_options(ap: argparse.ArgumentParser, preset: str | None = None, log_every: int = 10,
                    save_every: int = 20) -> None:
    """The options `run_train` reads: the run's data, shape, length, cadence and extra settings."""
    ap.add_argument("--data", required=True, help="shards from `jax3dc data build/import`")
    add_preset(ap)
    if preset:
        ap.set_defaults(preset=preset)
    add_seq(ap, 4096)
    add_batch(ap, 4)
    ap.add_argument("--accum", type=int, default=4, help="micro-batches per step")
    ap.add_argument("--steps", type=int, default=40)
    ap.add_argument("--log-every", type=int, default=log_every)
    ap.add_argument("--save-every", type=int, default=save_every)
    ap.add_argument("--loader-workers", type=int, default=8)
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help="more train settings")


def main() -> None:
    ap = bench_parser(__doc__)
    add_run_options(ap)
    ap.add_argument("--peer", help="hf_peer.py: run it after, in the same call")
    ap.add_argument("--out", required=True, help="folder for the run and the figures")
    add_json_lines(ap)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    ours, wall = run_train(a, os.path.join(a.out, "run"))
    row = {"preset": a.preset, "seq": a.seq, "batch": a.batch, "accum": a.accum, "settings": a.set,
           "command_wall_s": wall, **ours}
    print(f"jax3dc train: {ours['tokens_per_s']:.0f} tokens/s, MFU vs 790 {ours.get('mfu_vs_790') or 0:.3f}, "
          f"compile {ours['compile_s']:.1f} s, data wait {ours['data_wait_frac']:.3f}, wall {wall:.0f} s", flush=True)
    if a.peer:
        peer = run_peer(a.peer, a.seq, a.out)
        row["peer"] = {k: peer.get(k) for k in ("gpu", "train_tokens_per_s", "train_mfu_vs_790", "train_peak_mem_gib",
                                                "train_error")}
        if peer.get("train_tokens_per_s"):
            row["ratio"] = ours["tokens_per_s"] / peer["train_tokens_per_s"]
            print(f"HF peer: {peer['train_tokens_per_s']} tokens/s -> ratio {row['ratio']:.2f}", flush=True)
    append_json_lines(a.json, [row])


if __name__ == "__main__":
    main()
