"""The stage-1 recipe: a model that reads image I and writes a factory's category and parameters
(jax3dc.parameters), which the factory runs into parts with clean ids (issue 49).

Run on a GPU host, one command that may be repeated (each call does what is left and stops before
--budget-min minutes, training resumes from its orbax checkpoint in OUT/train):
    python3 -m recipes.stage1_model --out runs/stage1 --budget-min 9.3
  1. data      `jax3dc data build` without augmentation (split/merge variants are no factory's
               parts, so they carry no parameters), varied appearance, --views views per object
  2. tokenizer `jax3dc data tokenizer` over the build (its texts include the parameter texts),
               or --tokenizer DIR
  3. train     `jax3dc train --init PRESET` from scratch on the parameters task (I alone -> the
               parameter text); with --structure-weight W one model serves both stages: a share W
               of examples are the structure task over the same build
  4. package   bf16 weights sharded below 16 MiB a file, tokenizer, processor config, in OUT/stage1
               (what would ship beside jax3dc/release), and their size against the 24 MiB budget
  5. evaluate  `jax3dc eval run --task parameters` on the procedural test split (texts that run,
               part count exact, parts matched one-to-one by box overlap, Chamfer); with
               --structure-weight, `jax3dc eval run` of the structure task too
OUT/summary.json holds the numbers; the last lines print them.

CPU smoke run (seconds per step, numbers meaningless):
    python3 -m recipes.stage1_model --out /tmp/stage1 --objects 12 --views 1 --image-size 64 --init tiny \
        --vocab 600 --steps 3 --batch 2 --seq-len 1024 --eval-records 2 --eval-batch 2 --reserve-min 0
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import time
from collections.abc import Sequence
from pathlib import Path

from eval.parameters_run import table
from jax3dc.constrained.parameters import longest_text
from jax3dc.factories.registry import SCHEMAS
from recipes.steps import call, last_step, package_weights, set_flags

SHIPPED_BUDGET_BYTES = 24 * 2**20  # SPEC §7: all shipped weights together


def _weight_bytes(folder: Path) -> int:
    return sum(f.stat().st_size for f in folder.glob("*.safetensors"))


def _eval_parameters(model: Path, data: Path, out: Path, limit: int, batch: int, max_new: int) -> dict:
    if not (out / "metrics.json").exists():
        call(["eval", "run", "--task", "parameters", "--checkpoint", str(model), "--data", str(data), "--split", "test",
               "--limit", str(limit), "--batch-size", str(batch), "--bucket", "256", "--max-new-tokens", str(max_new),
               "--out", str(out)])
    return json.loads((out / "metrics.json").read_text())


def _eval_structure(model: Path, data: Path, out: Path, limit: int, batch: int) -> dict:
    if not (out / "metrics.json").exists():
        call(["eval", "run", "--checkpoint", str(model), "--data", str(data), "--split", "test", "--limit", str(limit),
               "--batch-size", str(batch), "--bucket", "256", "--max-new-tokens", "1536", "--out", str(out),
               "--overlays", "0", "--viewers", "0"])
    return json.loads((out / "metrics.json").read_text())


def main(argv: Sequence[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", default="runs/stage1")
    p.add_argument("--budget-min", type=float, default=9.3, help="stop this call before this many minutes")
    p.add_argument("--init", default="mini", help="model preset (random weights)")
    p.add_argument("--tokenizer", default="", help="a folder with tokenizer.json to use instead of learning one")
    p.add_argument("--objects", type=int, default=8500)
    p.add_argument("--views", type=int, default=1, help="views per object (views after the first move one joint)")
    p.add_argument("--appearance", default="varied")
    p.add_argument("--image-size", type=int, default=224)
    p.add_argument("--vocab", type=int, default=2048)
    p.add_argument("--structure-weight", type=float, default=0.0,
                   help="share of training examples that are the structure task (one model for both stages); 0: stage 1 only")
    p.add_argument("--steps", type=int, default=1500)
    p.add_argument("--batch", type=int, default=32)
    p.add_argument("--seq-len", type=int, default=4096)
    p.add_argument("--lr", type=float, default=1e-3)
    p.add_argument("--eval-records", type=int, default=300)
    p.add_argument("--eval-batch", type=int, default=100)
    p.add_argument("--reserve-min", type=float, default=2.0, help="minutes kept for packaging and evaluation")
    p.add_argument("--set", action="append", default=[], help="extra `jax3dc train --set` overrides")
    a = p.parse_args(argv)
    if not 0.0 <= a.structure_weight < 1.0:
        raise SystemExit(f"--structure-weight must be in [0, 1), got {a.structure_weight}")
    start = time.perf_counter()

    def left() -> float:
        return a.budget_min - (time.perf_counter() - start) / 60

    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    data, tok, train_dir, package = out / "data", Path(a.tokenizer) if a.tokenizer else out / "tokenizer", out / "train", out / "stage1"
    workers = os.cpu_count() or 1

    manifest = data / "manifest.json"
    if not (manifest.exists() and json.loads(manifest.read_text()).get("complete")):
        t = time.perf_counter()
        call(["data", "build", "--out", str(data), "--objects", str(a.objects), "--scenes", "0", "--views", str(a.views),
               "--size", str(a.image_size), "--workers", str(workers), "--quiet",
               *(["--appearance", a.appearance] if a.appearance else [])])
        print(f"[stage1] data: {time.perf_counter() - t:.0f} s", flush=True)
    if not (tok / "tokenizer.json").exists():
        call(["data", "tokenizer", "--data", str(data), "--vocab-size", str(a.vocab), "--out", str(tok), "--quiet"])

    if not (last_step(train_dir) >= a.steps and (train_dir / "hf" / "config.json").exists()):
        minutes = left() - a.reserve_min
        if minutes < 0.5:
            print("[stage1] no time left for training in this call; run it again", flush=True)
            return
        both = [f"data={data},{data}", "data_tasks=parameters,structure",
                f"data_weights={1 - a.structure_weight:g},{a.structure_weight:g}"] if a.structure_weight else [f"data={data}"]
        overrides = [*both, f"val_data={data}", "task=parameters", f"image_size={a.image_size}",
                     f"seq_len={a.seq_len}", f"batch_size={a.batch}", "grad_accum=1", f"lr={a.lr}",
                     f"warmup_steps={max(1, min(200, a.steps // 20))}", f"steps={a.steps}",
                     f"time_limit_min={minutes:.2f}", "freeze=", f"loader_workers={max(0, workers - 2)}",
                     f"eval_every={min(500, a.steps)}", "eval_batches=2", f"save_every={min(500, a.steps)}",
                     f"log_every={min(50, a.steps)}", "keep_last=1", f"tokenizer={tok}", *a.set]
        call(["train", "--init", a.init, "--output-dir", str(train_dir), *set_flags(overrides)])
        if last_step(train_dir) < a.steps:
            print(f"[stage1] trained to step {last_step(train_dir)} of {a.steps}; run again to go on", flush=True)
            return

    if not (package / "config.json").exists():
        package_weights(train_dir, package)
    weights = _weight_bytes(package)
    print(f"[stage1] packaged weights: {weights / 2**20:.2f} MiB (all shipped weights together: at most "
          f"{SHIPPED_BUDGET_BYTES / 2**20:.0f} MiB)", flush=True)
    max_new = longest_text(SCHEMAS) + 8  # bytes bound tokens: the grammar never needs more
    results = {"parameters": _eval_parameters(package, data, out / "eval_parameters", a.eval_records, a.eval_batch,
                                              max_new)}
    if a.structure_weight:
        results["structure"] = _eval_structure(package, data, out / "eval_structure", a.eval_records, a.eval_batch)
    rows = [json.loads(line) for line in (train_dir / "metrics.jsonl").read_text().splitlines() if line.strip()]
    train_rows = [r for r in rows if r.get("kind") == "train"]
    summary = {"args": vars(a), "final_step": last_step(train_dir), "weights_bytes": weights,
               "last_train": train_rows[-1] if train_rows else None, "results": results}
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    shutil.copy2(out / "summary.json", package / "stage1_summary.json")

    print("\n## parameters task (procedural test)\n" + table("stage1", results["parameters"]), flush=True)
    if "structure" in results:
        s = results["structure"]
        print(f"\n## structure task: parse {s.get('parse')}, success {s.get('success')}", flush=True)


if __name__ == "__main__":
    main()
