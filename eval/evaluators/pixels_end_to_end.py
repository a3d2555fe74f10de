"""End-to-end Table 1 from pixels on procedural test records (issue 49), beside stage 2 on true parts.

    python3 -m eval.evaluate pixels_end_to_end --data /work/preds/bench/sets/procedural_plain \\
        --true-parts /work/preds/bench/model/predictions.jsonl --out runs/pixels

For each of the first N records of the split: ``predict`` from the record's image alone — the
shipped stage-1 image network (jax3dc/release/stage1) writes a factory's parameters, the factory
makes the parts, the shipped structure model (jax3dc/release) writes the structure, then the
exports, the physics verdict and the report, as `jax3dc predict IMAGE` does — one loaded model of
each stage serving every record. Each prediction is scored by matched parts (eval.pixels). Printed:
Table 1 from pixels; Table 1 of the same records from ``--true-parts`` (the release's structure
predictions on the records' own parts, scored as `eval run --predictions`); the joints that succeed
out of the reference's (Table 1's success is a share of matched joints only); stage 1's own scores
(part count exact, matched part-box IoU, category, runs); and seconds per object. OUT/summary.json
holds the metrics and one row per record.
"""

from __future__ import annotations

import argparse
import itertools
import json
import time
from dataclasses import asdict
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from data_pipeline.shards import shard_paths
from eval.metrics.cases import build_cases, load_predictions
from eval.metrics.parameters import summarise
from eval.metrics.score import Evaluation, evaluate
from eval.metrics.tables import format_tables
from eval.pixels import predict_record, score_pixels
from eval.records import read_records, reference_of
from jax3dc.predict.pipeline import Checkpoints
from jax3dc.predict.stage1 import ReaderSettings, load_reader
from jax3dc.release import default_stage1_model


def successful_joints(evaluation: Evaluation) -> int:
    """Reference joints matched by a joint that passes every gate: Table 1's success is a share of
    the matched joints, so a joint never predicted does not lower it; this count does."""
    return sum(m["gate"] == "success" for row in evaluation.rows for m in row.get("matches", []))


def main(argv: Sequence[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--data", required=True, help="a built dataset (its shards) or a folder of shards")
    p.add_argument("--split", default="test")
    p.add_argument("--limit", type=int, default=50, help="records to predict (the first N plain records)")
    p.add_argument("--true-parts", metavar="PREDICTIONS.jsonl",
                   help="the structure model's predictions for the same records on their own parts")
    p.add_argument("--out", default="runs/pixels", help="one predict folder per record, and summary.json")
    p.add_argument("--dtype", default="bfloat16", choices=("bfloat16", "float32"))
    p.add_argument("--stage1-model", default="", help="a stage-1 folder instead of the shipped one (e.g. a "
                   "former release, for a comparison on the same records)")
    args = p.parse_args(argv)

    out = Path(args.out)
    plain = (r for r in read_records(shard_paths([Path(args.data)], args.split), args.split)
             if not r.meta.get("augmentation") and r.meta.get("category") != "scene" and r.parameters)
    records = list(itertools.islice(plain, args.limit))
    if not records:
        raise SystemExit(f"no plain {args.split} records with parameters in {args.data}")
    checkpoints = Checkpoints(args.dtype)
    reader = load_reader(args.stage1_model or default_stage1_model(), ReaderSettings(checkpoints.get, 1024, True))
    references, results = [], []
    started = time.perf_counter()
    for k, record in enumerate(records):
        reference = reference_of(record)
        result = predict_record(record, reference, out / f"object_{k:03d}", reader, checkpoints)
        references.append(reference)
        results.append(result)
        print(f"[{k + 1}/{len(records)}] {record.key}: {result.seconds:.1f} s, parts matched {result.matched}, "
              f"extra {result.extra}, missing {result.missing}" + (f"; failed: {result.failure}" if result.failure else ""),
              flush=True)
    wall = time.perf_counter() - started

    evaluations = {"from pixels": score_pixels(references, results)}
    if args.true_parts:
        evaluations["true parts"] = evaluate(build_cases(references, load_predictions(args.true_parts)))
    systems = [(name, e.metrics) for name, e in evaluations.items()]
    succeeded = {name: successful_joints(e) for name, e in evaluations.items()}
    stage1 = summarise([r.stage1 for r in results if r.stage1 is not None])
    seconds = [r.seconds for r in results]
    timing = {"objects": len(results), "mean_s": float(np.mean(seconds)), "median_s": float(np.median(seconds)),
              "max_s": float(np.max(seconds)), "first_s": seconds[0], "wall_s": wall}
    summary = {"data": args.data, "records": len(records), "dtype": args.dtype, "tables": dict(systems),
               "successful_joints": succeeded,
               "stage1": stage1, "seconds": timing,
               "physics_ok": float(np.mean([bool(r.physics_ok) for r in results])) * 100,
               "rows": [{**asdict(r), "stage1": r.stage1.to_dict() if r.stage1 else None} for r in results]}
    out.mkdir(parents=True, exist_ok=True)
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    print(f"\n{len(records)} {args.split} records of {args.data}\n")
    print(format_tables(systems))
    joints_ref = evaluations["from pixels"].metrics["counts"]["joints_ref"]
    print("\nsuccessful joints over the reference's " + str(joints_ref) + ": " + ", ".join(
        f"{name} {n} ({100 * n / max(joints_ref, 1):.1f} %)" for name, n in succeeded.items()))
    print(f"stage 1: runs {stage1['runs']:.1f}, category {stage1['category']:.1f}, part count exact "
          f"{stage1['count_exact']:.1f}, matched part-box IoU {stage1['matched_iou']:.1f}, Chamfer {stage1['chamfer']:.4f} nu")
    print(f"predict per object (both stages, exports, physics, report): mean {timing['mean_s']:.1f} s, median "
          f"{timing['median_s']:.1f} s, max {timing['max_s']:.1f} s (first, with compilation: {timing['first_s']:.1f} s); "
          f"physics passes {summary['physics_ok']:.1f} %")
    print(f"summary: {out / 'summary.json'}")


if __name__ == "__main__":
    main()
