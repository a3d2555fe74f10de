"""Accuracy against model size and training time: the measurement behind the release size.

    python3 -m eval.evaluate size_sweep --data BUILD --out runs/size_sweep [--points mini:1200,release:400,...]

Each point ``PRESET:STEPS`` trains that preset from random weights on BUILD's train split (the
release tokenizer, the release recipe's batch and learning rate, a full cosine schedule over
STEPS), then scores `jax3dc eval run` (constrained greedy decoding) on the first
--eval-records test records. Points already in OUT/points.jsonl are skipped, so a host whose
commands are cut at 10 minutes gets through the list in several calls. Every call redraws
OUT/size_sweep.png: success against parameters and against training wall time.
"""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Sequence
from pathlib import Path

from safetensors import safe_open

from jax3dc.cli import main as jax3dc

RELEASE_TOKENIZER = Path(__file__).resolve().parents[2] / "jax3dc" / "release"


def _call(argv: list[str]) -> None:
    print(f"[sweep] jax3dc {' '.join(argv)}", flush=True)
    if jax3dc(argv) != 0:
        raise SystemExit(f"`jax3dc {' '.join(argv)}` failed")


def _params(hf: Path) -> int:
    total = 0
    for f in sorted(hf.glob("*.safetensors")):
        with safe_open(str(f), "numpy") as st:
            for name in st.keys():
                shape = st.get_slice(name).get_shape()
                n = 1
                for d in shape:
                    n *= d
                total += n
    return total


def run_point(preset: str, steps: int, data: str, out: Path, eval_records: int, lr: float) -> dict:
    train_dir, report = out / f"{preset}_{steps}", out / f"{preset}_{steps}_eval"
    resumed = (train_dir / "checkpoints").exists()  # a cut call: its wall time would be the rest only
    start = time.perf_counter()
    sets = [f"data={data}", "image_size=224", "seq_len=4096", "batch_size=32", "grad_accum=1", f"lr={lr}",
            f"warmup_steps={min(200, steps // 10)}", f"steps={steps}", "freeze=", "loader_workers=12",
            f"eval_every={steps}", "eval_batches=2", f"save_every={steps}", f"log_every={max(1, steps // 20)}",
            "keep_last=1", f"tokenizer={RELEASE_TOKENIZER}"]
    _call(["train", "--init", preset, "--output-dir", str(train_dir), *[x for s in sets for x in ("--set", s)]])
    wall = time.perf_counter() - start
    _call(["eval", "run", "--checkpoint", str(train_dir / "hf"), "--data", data, "--limit", str(eval_records),
           "--batch-size", "100", "--bucket", "256", "--max-new-tokens", "1536", "--out", str(report), "--overlays", "0"])
    metrics = json.loads((report / "metrics.json").read_text())
    val = [json.loads(x) for x in (train_dir / "metrics.jsonl").read_text().splitlines() if '"val"' in x]
    return {"preset": preset, "steps": steps, "params": _params(train_dir / "hf"),
            "train_wall_s": None if resumed else round(wall, 1),
            "val_loss": val[-1]["loss"] if val else None,
            **{k: metrics.get(k) for k in ("parse", "parent_acc", "type_acc", "axis_acc", "pos_err", "range_iou", "success")}}


def plot(points: list[dict], path: Path) -> None:
    import matplotlib  # lazy: matplotlib (0.20 s with pyplot) for the plot only

    matplotlib.use("Agg")
    # lazy: after the Agg backend is chosen
    import matplotlib.pyplot as plt
    from matplotlib import ticker

    fig, (by_size, by_time) = plt.subplots(1, 2, figsize=(9, 3.6))
    for preset in dict.fromkeys(p["preset"] for p in points):
        mine = sorted((p for p in points if p["preset"] == preset), key=lambda p: p["steps"])
        timed = [p for p in mine if p["train_wall_s"] is not None]  # None: not measured (see OUT/points.jsonl notes)
        by_time.plot([p["train_wall_s"] / 60 for p in timed], [p["success"] or 0 for p in timed], "o-", label=preset)
        for p in mine:
            by_size.scatter(p["params"] / 1e6, p["success"] or 0, label=f"{preset}, {p['steps']} steps")
    by_size.set(xscale="log", xlabel="parameters (M)", ylabel="articulation success (%)", title="by model size")
    by_size.xaxis.set_major_formatter(ticker.FormatStrFormatter("%g"))
    by_size.xaxis.set_minor_formatter(ticker.NullFormatter())
    by_size.set_xticks(sorted({round(p["params"] / 1e6, 1) for p in points}))
    by_time.set(xlabel="training wall time (min, one GPU)", ylabel="articulation success (%)", title="by training time")
    by_size.legend(fontsize=7)
    by_time.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main(argv: Sequence[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--data", required=True, help="a `jax3dc data build` folder (train and test splits)")
    p.add_argument("--out", default="runs/size_sweep")
    p.add_argument("--points", default="release:400,mini:1200,small:400,release:1200", help="PRESET:STEPS,...")
    p.add_argument("--eval-records", type=int, default=100)
    p.add_argument("--lr", type=float, default=1e-3)
    p.add_argument("--budget-min", type=float, default=9.3, help="start no new point after this many minutes")
    p.add_argument("--point-min", type=float, default=4.0, help="minutes a point is assumed to need at most")
    a = p.parse_args(argv)
    start = time.perf_counter()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    log = out / "points.jsonl"
    done = [json.loads(x) for x in log.read_text().splitlines()] if log.exists() else []
    for spec in a.points.split(","):
        preset, steps = spec.split(":")
        if any(d["preset"] == preset and d["steps"] == int(steps) for d in done):
            continue
        if (time.perf_counter() - start) / 60 + a.point_min > a.budget_min:
            print("[sweep] no time for the next point in this call; run it again", flush=True)
            break
        point = run_point(preset, int(steps), a.data, out, a.eval_records, a.lr)
        done.append(point)
        with log.open("a") as f:
            f.write(json.dumps(point) + "\n")
        print(f"[sweep] {json.dumps(point)}", flush=True)
    if done:
        plot(done, out / "size_sweep.png")


if __name__ == "__main__":
    main()
