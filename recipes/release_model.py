"""The release recipe: data, tokenizer, training, evaluation and the packaged default model.

Run on a GPU host (one GPU or all GPUs of one host), one command that may be repeated:
    python3 -m recipes.release_model --out runs/release --budget-min 9.3 [--real SHARDS] [--fixtures SHARDS]
Each call does what is left, in order, and stops before --budget-min minutes have passed, so
a host whose commands are cut at 10 minutes still gets there in a few calls (training resumes
from its orbax checkpoint in OUT/train):
  1. data      `jax3dc data build`: factory objects (all categories), scenes, several views with
               one joint moved each, split/merge augmentation; split by object
  2. tokenizer `jax3dc data tokenizer`: a byte-level BPE of the training texts (the model's
               vocabulary, and so its embedding table, stays small enough to ship)
  3. train     `jax3dc train --init release` from scratch, every parameter trained, the
               procedural build mixed with --real (imported real objects, train split only)
  4. evaluate  `eval.evaluators.real_objects`: the procedural test split (plain, split and merge variants,
               scenes), --heldout and --fixtures (real objects kept out of training), each beside
               the no-training baselines and --compare; with --code-weight, `jax3dc eval run
               --task code` on the procedural test split too
  5. package   the weights in bf16, sharded below 16 MiB a file, with the tokenizer, processor
               config and a model card, in OUT/release (what `jax3dc/release/` ships)
`--code-weight W` makes one model serve both stages: a share W of training examples are the code
task (image I alone -> the record's part program) over the same procedural build.
`--init DIR` continues from an earlier release folder instead of random weights (new optimiser);
`--compare DIR` scores an earlier release on the same procedural test records, so a new release
is committed only when it beats the shipped one. The shipped release 1 came from three such runs
(docs/BENCHMARKS.md gives the calls).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import time
from pathlib import Path
from typing import Sequence

from eval.evaluators import real_objects
from recipes.steps import call, last_step, package_weights, set_flags
from train.model_state import PRESETS

COLUMNS = ("parse", "parent_acc", "edge_f1", "presence_f1", "type_acc", "axis_acc", "pos_err", "range_iou",
           "success", "sym_f1", "inst_f1", "fail_type", "fail_axis", "fail_origin", "fail_limit")


def training_mix(data: str, real: str, real_weight: float, code_weight: float,
                 extra: Sequence[tuple[str, float]] = ()) -> tuple[list[str], list[str], list[float]]:
    """The training sources, their tasks and shares of examples: the procedural build, each
    comma-separated folder of ``real`` (several imports of the pool, e.g. two looks of the same
    objects, split ``real_weight`` equally), each ``extra`` folder at its own share (e.g. objects
    composed from real parts) and, with ``code_weight``, the build again as the code task."""
    reals = [d for d in real.split(",") if d]
    datasets = [data, *reals, *(d for d, _ in extra)] + ([data] if code_weight else [])
    tasks = ["structure"] * (1 + len(reals) + len(extra)) + ["code"] * bool(code_weight)
    shares = ([real_weight / len(reals)] * len(reals) if reals else []) + [w for _, w in extra]
    weights = [1 - sum(shares) - code_weight, *shares] + ([code_weight] if code_weight else [])
    if weights[0] <= 0:
        raise SystemExit(f"the shares of the other sources ({sum(shares) + code_weight:g}) leave the build none")
    return datasets, tasks, weights


def mix_entry(text: str) -> tuple[str, float]:
    """``DIR=SHARE`` of ``--mix``."""
    folder, sep, share = text.rpartition("=")
    try:
        value = float(share)
    except ValueError:
        value = -1.0
    if not sep or not folder or not 0 < value < 1:
        raise argparse.ArgumentTypeError(f"expected DIR=SHARE with 0 < SHARE < 1, got {text!r}")
    return folder, value


def _row(metrics: dict) -> dict:
    return {k: metrics.get(k) for k in COLUMNS}


def _evaluate_code(model: Path, data: str, out: Path, limit: int, batch: int, max_new: int) -> dict:
    """eval run --task code: part programs from image I alone, run and compared with the records' own."""
    if not (out / "metrics.json").exists():
        call(["eval", "run", "--task", "code", "--checkpoint", str(model), "--data", data, "--limit", str(limit),
               "--batch-size", str(batch), "--bucket", "256", "--max-new-tokens", str(max_new), "--out", str(out)])
    return json.loads((out / "metrics.json").read_text())


def main(argv: Sequence[str] | None = None) -> None:
    """Run the recipe's steps left to do with the flags of ``argv`` (the command line's by default)."""
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", default="runs/release")
    p.add_argument("--budget-min", type=float, default=9.3, help="stop this call before this many minutes")
    p.add_argument("--init", default="release", help="preset (random weights; eval.evaluators.size_sweep compares them), or an "
                   "earlier release folder to continue from")
    p.add_argument("--tokenizer", default="", help="a folder with tokenizer.json to use instead of learning one")
    p.add_argument("--objects", type=int, default=4000)
    p.add_argument("--scenes", type=int, default=120)
    p.add_argument("--views", type=int, default=2)
    p.add_argument("--augment", action=argparse.BooleanOptionalAction, default=True,
                   help="split/merge variants of each object (default on)")
    p.add_argument("--appearance", default="varied", help="`data build --appearance` (empty: the build's default)")
    p.add_argument("--fuse-handles", action="store_true", help="`data build --fuse-handles`: every object also with its "
                   "handles fused into the parts they sit on")
    p.add_argument("--image-size", type=int, default=224)
    p.add_argument("--vocab", type=int, default=2048)
    p.add_argument("--real", default="", help="shards of imported real training objects (train split); several "
                   "folders, comma-separated (e.g. two looks of the same objects), share --real-weight equally")
    p.add_argument("--real-weight", type=float, default=0.1, help="share of training examples from --real")
    p.add_argument("--mix", type=mix_entry, action="append", default=[], metavar="DIR=SHARE",
                   help="more training shards at their own share of examples (e.g. objects composed from real "
                   "parts); repeatable")
    p.add_argument("--heldout", default="", help="shards of the real pool's held-out fifth (scripts/real_split.py), never "
                   "trained on, scored by eval.evaluators.real_objects")
    p.add_argument("--pivot-frame", default="box", choices=("box", "absolute"),
                   help="how the model writes joint pivots (jax3dc/structure/box_frame.py); ignored with --init DIR, "
                   "which keeps that model's")
    p.add_argument("--code-weight", type=float, default=0.0,
                   help="share of training examples that are the code task (I -> part program); 0: structure only")
    p.add_argument("--code-eval-records", type=int, default=100, help="procedural test records for the code task")
    p.add_argument("--compare", default="", help="an earlier release folder scored on the same records")
    p.add_argument("--fixtures", default="", help="shards of real objects never trained on, scored per object")
    p.add_argument("--heldout-varied", default="", help="--heldout's objects in the varied look (eval.evaluators.real_objects)")
    p.add_argument("--fixtures-varied", default="", help="--fixtures' objects in the varied look")
    p.add_argument("--steps", type=int, default=6000)
    p.add_argument("--batch", type=int, default=32)
    p.add_argument("--seq-len", type=int, default=4096)
    p.add_argument("--lr", type=float, default=1e-3)
    p.add_argument("--eval-records", type=int, default=400)
    p.add_argument("--eval-batch", type=int, default=100)
    p.add_argument("--max-new-tokens", type=int, default=2048)
    p.add_argument("--reserve-min", type=float, default=2.5, help="minutes kept for evaluation and packaging")
    p.add_argument("--set", action="append", default=[], help="extra `jax3dc train --set` overrides")
    a = p.parse_args(argv)
    start = time.perf_counter()

    def left() -> float:
        return a.budget_min - (time.perf_counter() - start) / 60

    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    data, tok, train_dir = out / "data", out / "tokenizer", out / "train"
    workers = str(os.cpu_count() or 1)

    manifest = data / "manifest.json"
    if not (manifest.exists() and json.loads(manifest.read_text()).get("complete")):
        t = time.perf_counter()
        build = ["data", "build", "--out", str(data), "--objects", str(a.objects), "--scenes", str(a.scenes),
                 "--views", str(a.views), *(["--augment"] if a.augment else []), *(["--fuse-handles"] if a.fuse_handles else []),
                 "--size", str(a.image_size), "--workers", workers, "--quiet"]
        call(build + (["--appearance", a.appearance] if a.appearance else []))
        print(f"[release] data: {time.perf_counter() - t:.0f} s", flush=True)

    init_dir = None if a.init in PRESETS else Path(a.init)
    if a.tokenizer:
        tok = Path(a.tokenizer)
    if init_dir is None and not (tok / "tokenizer.json").exists():
        sources = [x for d in [str(data), *filter(None, a.real.split(","))] for x in ("--data", d)]
        call(["data", "tokenizer", *sources, "--vocab-size", str(a.vocab), "--out", str(tok), "--quiet"])

    done = last_step(train_dir) >= a.steps and (train_dir / "hf" / "config.json").exists()
    if not done:
        minutes = left() - a.reserve_min
        if minutes < 1:
            print("[release] no time left for training in this call; run it again", flush=True)
            return
        datasets, tasks, weights = training_mix(str(data), a.real, a.real_weight, a.code_weight, a.mix)
        overrides = [f"data={','.join(datasets)}", f"val_data={data}", f"image_size={a.image_size}", f"seq_len={a.seq_len}",
                     f"batch_size={a.batch}", "grad_accum=1", f"lr={a.lr}", f"warmup_steps={min(200, a.steps // 20)}",
                     f"steps={a.steps}", f"time_limit_min={minutes:.2f}", "freeze=", f"loader_workers={int(workers) - 2}",
                     "eval_every=500", "eval_batches=2", "save_every=500", "log_every=50", "keep_last=1",
                     f"tokenizer={tok if a.tokenizer or init_dir is None else init_dir}",
                     *([f"pivot_frame={a.pivot_frame}"] if init_dir is None else []), *a.set]
        if len(datasets) > 1:
            overrides.append("data_weights=" + ",".join(f"{w:g}" for w in weights))
            overrides.append("data_tasks=" + ",".join(tasks))
        call(["train", "--init", str(init_dir or a.init), "--output-dir", str(train_dir), *set_flags(overrides)])
        if last_step(train_dir) < a.steps:
            print(f"[release] trained to step {last_step(train_dir)} of {a.steps}; run again to go on", flush=True)
            return

    release = out / "release"
    if not (release / "config.json").exists():
        package_weights(train_dir, release)
    bench = real_objects.main(["--model", str(release), *(["--compare", a.compare] if a.compare else []),
                               *(["--heldout", a.heldout] if a.heldout else []),
                               *(["--fixtures", a.fixtures] if a.fixtures else []),
                               *(["--heldout-varied", a.heldout_varied] if a.heldout_varied else []),
                               *(["--fixtures-varied", a.fixtures_varied] if a.fixtures_varied else []),
                               "--procedural", str(data),
                               "--out", str(out / "bench"), "--plain", str(a.eval_records),
                               "--batch", str(a.eval_batch), "--max-new-tokens", str(a.max_new_tokens)])
    code = None
    if a.code_weight:
        code = _evaluate_code(release, str(data), out / "eval_code", a.code_eval_records, a.eval_batch, 2048)
    steps = [json.loads(line) for line in (train_dir / "metrics.jsonl").read_text().splitlines() if line.strip()]
    train_rows = [r for r in steps if r.get("kind") == "train"]
    summary = {"args": vars(a), "final_step": last_step(train_dir), "last_train": train_rows[-1] if train_rows else None,
               "results": {name: {system: {**_row(r["metrics"]), "hinge_edge_acc": r.get("hinge_edge_acc"),
                                           "counts": r["metrics"]["counts"]} for system, r in systems.items()}
                           for name, systems in bench.items()}, "code": code}
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    shutil.copy2(out / "summary.json", release / "release_summary.json")
    if code:
        print("\n## code task (procedural test)\n" + json.dumps(code, indent=1), flush=True)


if __name__ == "__main__":
    main()
