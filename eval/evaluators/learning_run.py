"""The learning check of issue 6: does a model trained from scratch beat the no-training baselines?

Run (one GPU, one command, about 9 minutes):
    python3 -m eval.evaluate learning_run --out runs/learning
Stages, all through the `jax3dc` commands a user runs:
  1. data      `jax3dc data build`: factory objects, 2 views each, split by object
  2. train     `jax3dc train --init small`: the `small` preset from scratch on the train split
               (everything trained, vision included: there is no pretrained tower to keep),
               stopped by --minutes whatever step it reached
  3. evaluate  `jax3dc eval run`: greedy generation on --eval-records held-out test records
  4. baselines `jax3dc eval baselines` on the same references
Writes OUT/summary.json and OUT/summary.md (the metrics table and the issue's bar: >= 90% of
generations parse, parent accuracy and joint presence F1 above the best no-training baseline)
next to the run's loss.png and config.json.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from collections.abc import Sequence
from pathlib import Path

from jax3dc.cli import main as jax3dc

COLUMNS = ("parse", "parent_acc", "edge_f1", "presence_f1", "type_acc", "axis_acc", "range_iou", "success")


def _call(argv: list[str]) -> None:
    code = jax3dc(argv)
    if code != 0:
        raise SystemExit(f"`jax3dc {' '.join(argv)}` failed with exit code {code}")


def _row(metrics: dict) -> dict:
    return {k: metrics.get(k) for k in COLUMNS}


def main(argv: Sequence[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", default="runs/learning")
    p.add_argument("--init", default="small", help="preset trained from scratch")
    p.add_argument("--objects", type=int, default=2400, help="2 views each; 5%% of objects are test")
    p.add_argument("--image-size", type=int, default=224)
    p.add_argument("--minutes", type=float, default=3.5, help="training time limit")
    p.add_argument("--steps", type=int, default=600, help="schedule length (the time limit may stop earlier)")
    p.add_argument("--seq-len", type=int, default=4096)
    p.add_argument("--batch", type=int, default=32)
    p.add_argument("--lr", type=float, default=1e-3)
    p.add_argument("--workers", type=int, default=max(1, (os.cpu_count() or 2) - 2), help="loader workers")
    p.add_argument("--eval-records", type=int, default=240)
    p.add_argument("--eval-batch", type=int, default=64)
    p.add_argument("--max-new-tokens", type=int, default=2048)
    p.add_argument("--set", action="append", default=[], help="extra `jax3dc train --set` overrides")
    a = p.parse_args(argv)
    out = Path(a.out)
    seconds = {}

    t = time.perf_counter()
    _call(["data", "build", "--out", str(out / "data"), "--objects", str(a.objects), "--views", "2",
           "--size", str(a.image_size), "--workers", str(os.cpu_count() or 1), "--quiet"])
    seconds["data"] = time.perf_counter() - t
    print(f"[learning] data: {seconds['data']:.0f} s", flush=True)

    t = time.perf_counter()
    overrides = [f"data={out / 'data'}", f"image_size={a.image_size}", f"seq_len={a.seq_len}",
                 f"batch_size={a.batch}", "grad_accum=1", f"lr={a.lr}", f"warmup_steps={min(30, a.steps // 10)}", f"steps={a.steps}",
                 f"time_limit_min={a.minutes}", "freeze=", f"loader_workers={a.workers}", "eval_every=100", "eval_batches=2",
                 "save_every=200", "log_every=10", *a.set]
    _call(["train", "--init", a.init, "--output-dir", str(out / "train"), *[x for o in overrides for x in ("--set", o)]])
    seconds["train"] = time.perf_counter() - t
    print(f"[learning] train: {seconds['train']:.0f} s", flush=True)

    t = time.perf_counter()
    _call(["eval", "run", "--checkpoint", str(out / "train" / "hf"), "--data", str(out / "data"), "--split", "test",
           "--limit", str(a.eval_records), "--batch-size", str(a.eval_batch), "--bucket", "256",
           "--max-new-tokens", str(a.max_new_tokens), "--out", str(out / "eval"), "--overlays", "8"])
    seconds["evaluate"] = time.perf_counter() - t
    print(f"[learning] evaluate: {seconds['evaluate']:.0f} s", flush=True)

    t = time.perf_counter()
    _call(["eval", "baselines", "--ref", str(out / "eval" / "references.jsonl"), "--out", str(out / "baselines")])
    seconds["baselines"] = time.perf_counter() - t
    print(f"[learning] baselines: {seconds['baselines']:.0f} s", flush=True)

    model = json.loads((out / "eval" / "metrics.json").read_text())
    table = {"trained": _row(model)}
    for name in ("star", "heuristic"):
        table[name] = _row(json.loads((out / "baselines" / name / "metrics.json").read_text()))
    best = {k: max(table[n][k] or 0 for n in ("star", "heuristic")) for k in ("parent_acc", "presence_f1")}
    bar = {"parse >= 90": (table["trained"]["parse"] or 0) >= 90,
           "parent_acc > best baseline": (table["trained"]["parent_acc"] or 0) > best["parent_acc"],
           "presence_f1 > best baseline": (table["trained"]["presence_f1"] or 0) > best["presence_f1"]}
    steps = [json.loads(line) for line in (out / "train" / "metrics.jsonl").read_text().splitlines()]
    last = [r for r in steps if r.get("kind") == "train"][-1]
    summary = {"objects": a.objects, "eval_records": model["counts"]["objects"], "final_step": last["step"],
               "last_train": last, "seconds": {k: round(v, 1) for k, v in seconds.items()}, "table": table,
               "bar": bar}
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    lines = ["| system | " + " | ".join(COLUMNS) + " |", "|---" * (len(COLUMNS) + 1) + "|"]
    for name, row in table.items():
        lines.append(f"| {name} | " + " | ".join("-" if row[k] is None else f"{row[k]:.1f}" for k in COLUMNS) + " |")
    lines += ["", *(f"- {k}: {'yes' if v else 'NO'}" for k, v in bar.items()),
              f"- trained to step {last['step']} in {seconds['train']:.0f} s; stage seconds {summary['seconds']}"]
    (out / "summary.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
