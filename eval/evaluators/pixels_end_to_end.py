"""From pixels on the same records, one row per stage-1 backend, beside stage 2 on the true parts
(issues 49 and 64).

    python3 -m eval.evaluate pixels_end_to_end --data HELDOUT_PLAIN --slots-model SLOTS --limit 0 \\
        --out runs/pixels_real

Records: the rest views (no joint moved) of the split's plain records (no split or merge variant,
no scene), the first --limit of them (0: all), whatever made them: procedural builds (`jax3dc data
build`) and real objects imported with `jax3dc data import`, which carry no factory parameters.

On the same images, each stage-1 backend is followed by stage 2 as `jax3dc predict IMAGE` runs them
(the shipped structure model, jax3dc/release, or --structure-model; then the exports, the physics
verdict and the report; one loaded model of each stage serves every record):
  factory network  the shipped stage-1 image network (jax3dc/release/stage1, or --stage1-model)
                   writes a factory's parameters, the factory makes the parts; always run
  slots            the slots network (--slots-model DIR) writes the parts as boxes with kinds;
                   run when the folder is given
  true parts       stage 2 alone on each record's own parts (its I, S and prompt, decoded as `eval
                   run` decodes them, by the same loaded model), written to
                   OUT/true_parts/predictions.jsonl (a rerun reuses it); or --true-parts FILE, the
                   structure model's predictions for the same records made elsewhere

Scored per backend (printed, OUT/summary.md, OUT/summary.json):
  - stage 1's parts as boxes at rest (eval.pixels.score_boxes, eval.metrics.part_boxes): RS-dgIoU
    (lower is better; a record whose predict made no parts counts 2), reference parts matched at
    box IoU >= 0.5, extra parts among those predicted, and part-kind accuracy over matched pairs
    whose reference part has a name: for slots the network's own kinds, for the factory network
    its factory's part names read through jax3dc.stage1_slots.kinds (`freezer_door` is a door, a
    name with no word the table knows is `other`);
  - the structure, its parts paired with the reference's by box overlap and renamed onto their ids
    (eval.pixels): reference joints right (matched and passing every gate, out of the reference's
    joints, as the real_objects evaluator counts them), set against the true parts' count on the
    same records, and Table 1;
  - the factory network's own scores on records that carry factory parameters (category, part
    count, matched part-box IoU), and seconds per object (both stages, exports, physics, report).
OUT/<backend>/object_NNN holds each prediction; summary.json also has one row per record and
backend and the joints right per category.
"""

from __future__ import annotations

import argparse
import itertools
import json
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from data_pipeline.record import Record
from data_pipeline.shards import shard_paths
from eval.evaluators.real_objects import breakdown
from eval.generation import generate_predictions
from eval.metrics.cases import Reference, build_cases, load_predictions
from eval.metrics.parameters import summarise as summarise_parameters
from eval.metrics.part_boxes import summarise as summarise_boxes
from eval.metrics.score import Case, evaluate
from eval.metrics.tables import format_tables
from eval.pixels import PixelsResult, pixels_cases, predict_record
from eval.records import read_records, reference_of
from jax3dc.decoding import DecodeOptions
from jax3dc.errors import Jax3dcError
from jax3dc.predict.pipeline import Checkpoints
from jax3dc.predict.stage1 import SLOTS, Stage1Config
from jax3dc.release import default_stage1_model, default_structure_model
from jax3dc.stage1_slots import MARKER

TRUE_PARTS = "true_parts"
TRUE_PARTS_LABEL = "true parts (stage 2 alone)"


@dataclass(frozen=True)
class Backend:
    """One stage-1 row: its folder under OUT (and key in summary.json), its label, the stage 1 it
    configures, and where its part kinds come from."""

    name: str
    label: str
    stage1: Stage1Config
    kinds: str


def backends(stage1_model: str, slots_model: str) -> list[Backend]:
    """The factory network (the shipped one unless ``stage1_model`` names another), then slots when
    ``slots_model`` names a folder."""
    folder = Path(stage1_model) if stage1_model else default_stage1_model()
    if folder is None:
        raise SystemExit("no stage-1 network ships with this install: name one (--stage1-model DIR)")
    if slots_model and not (Path(slots_model) / MARKER).is_file():
        raise SystemExit(f"--slots-model {slots_model}: not a slots-network folder (no {MARKER})")
    rows = [Backend("factory", f"factory network ({folder.name})", Stage1Config(model_dir=folder),
                    "its factory's part names through jax3dc.stage1_slots.kinds")]
    if slots_model:
        rows.append(Backend("slots", f"slots ({Path(slots_model).name})",
                            Stage1Config(backend=SLOTS, slots_model_dir=slots_model), "the network's own kinds"))
    return rows


def rest_records(data: Sequence[str], split: str, limit: int) -> list[Record]:
    """The first ``limit`` (0: every) rest views of the split's plain records: no variant, no
    scene, no joint moved, so the reference boxes are the parts at rest. Factory parameters are
    not needed: imported real objects have none."""
    plain = (r for r in read_records(shard_paths(list(data), split), split)
             if not r.meta.get("augmentation") and r.meta.get("category") != "scene"
             and r.meta.get("moved_joint") is None)
    return list(itertools.islice(plain, limit or None))


def joints_right(cases: Sequence[Case], rows: Sequence[dict], records: Sequence[Record]) -> dict[str, Any]:
    """Reference joints right over every record and per category (real_objects.breakdown)."""
    category = {r.key: str(r.meta.get("category")) for r in records}
    return {"joints": breakdown(cases, rows, {key: "all" for key in category})["all"],
            "per_category": breakdown(cases, rows, category)}


def backend_summary(backend: Backend, records: Sequence[Record], references: Sequence[Reference],
                    results: Sequence[PixelsResult]) -> dict[str, Any]:
    """One backend's scores (module docstring) and its rows."""
    cases = pixels_cases(references, results)
    evaluation = evaluate(cases)
    seconds = [r.seconds for r in results]
    parameters = [r.stage1 for r in results if r.stage1 is not None]
    return {"label": backend.label, "kinds_from": backend.kinds,
            "parts": summarise_boxes([r.parts for r in results if r.parts is not None]),
            **joints_right(cases, evaluation.rows, records), "table1": evaluation.metrics,
            "failures": sum(r.failure is not None for r in results),
            "physics_ok": 100.0 * float(np.mean([bool(r.physics_ok) for r in results])),
            "seconds": {"mean_s": float(np.mean(seconds)), "median_s": float(np.median(seconds)),
                        "max_s": float(np.max(seconds)), "first_s": seconds[0]},
            "stage1_parameters": summarise_parameters(parameters) if parameters else None,
            "rows": [{**asdict(r), "stage1": r.stage1.to_dict() if r.stage1 else None} for r in results]}


def true_parts_summary(records: Sequence[Record], references: Sequence[Reference],
                       predictions: dict[str, Any]) -> dict[str, Any]:
    """Stage 2 on the records' own parts: reference joints right and Table 1."""
    cases = build_cases(references, predictions)
    evaluation = evaluate(cases)
    return {"label": TRUE_PARTS_LABEL, **joints_right(cases, evaluation.rows, records), "table1": evaluation.metrics,
            "failures": sum(c.prediction is None for c in cases)}


def true_parts_predictions(args: argparse.Namespace, records: Sequence[Record], structure_model: Path,
                           checkpoints: Checkpoints) -> dict[str, Any]:
    """Key -> the structure model's text on the record's own parts: --true-parts, else decoded
    into OUT/true_parts/predictions.jsonl (resumable), before any backend runs, so that a token
    budget too small for a record's structure stops the run at once, not after every predict."""
    if args.true_parts:
        return load_predictions(args.true_parts)
    folder = Path(args.out) / TRUE_PARTS
    folder.mkdir(parents=True, exist_ok=True)
    try:
        lines, stats = generate_predictions(checkpoints.get(structure_model), records, folder / "predictions.jsonl",
                                            args.batch_size, args.max_new_tokens, 256, DecodeOptions())
    except Jax3dcError as e:
        raise SystemExit(f"true parts: {e}") from None
    print(f"true parts: {stats.summary()}", flush=True)
    return {key: line["text"] for key, line in lines.items()}


def _share(part: int, whole: int) -> str:
    return f"{part} of {whole} ({100 * part / whole:.1f} %)" if whole else "-"


def summary_table(summaries: dict[str, dict[str, Any]]) -> str:
    """Markdown: one row per backend and the true parts' row (module docstring), then what the
    part-kind accuracy of each backend reads."""
    true_right = summaries[TRUE_PARTS]["joints"]["success"]
    lines = ["| stage 1 | RS-dgIoU (lower is better) | reference parts matched | extra parts / predicted | "
             "part kinds right (matched pairs, reference named) | reference joints right | of the true parts' | "
             "predict failed | s / object |",
             "|---" * 9 + "|"]
    for name, s in summaries.items():
        joints = f"{s['joints']['success']} of {s['joints']['ref_joints']}"
        of_true = f"{100 * s['joints']['success'] / true_right:.1f} %" if true_right else "-"
        if name == TRUE_PARTS:
            lines.append(f"| {s['label']} | - | - | - | - | {joints} | {of_true} | {s['failures']} | - |")
            continue
        p = s["parts"]
        cells = [f"{p['rs_dgiou']:.3f}", _share(p["matched"], p["reference_parts"]),
                 _share(p["extra"], p["predicted_parts"]), _share(p["kinds_right"], p["kinds_scored"])]
        lines.append(f"| {s['label']} | {' | '.join(cells)} | {joints} | {of_true} | {s['failures']} | "
                     f"{s['seconds']['mean_s']:.1f} |")
    notes = [f"- part kinds of {s['label']}: {s['kinds_from']}" for name, s in summaries.items() if name != TRUE_PARTS]
    return "\n".join(lines + ["", *notes]) + "\n"


def main(argv: Sequence[str] | None = None) -> dict[str, Any]:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--data", required=True, nargs="+", help="built or imported datasets (their shards) or folders "
                   "of shards")
    p.add_argument("--split", default="test")
    p.add_argument("--limit", type=int, default=50, help="records to predict: the first N rest views (0: all)")
    p.add_argument("--slots-model", default="", metavar="DIR", help="a slots-network folder (recipes/stage1_slots.py): "
                   "its row beside the factory network's")
    p.add_argument("--stage1-model", default="", metavar="DIR", help="a stage-1 image-network folder instead of the "
                   "shipped one (e.g. a former release, for a comparison on the same records)")
    p.add_argument("--structure-model", default="", metavar="DIR", help="a structure-model folder instead of the "
                   "shipped one, for every backend and the true parts")
    p.add_argument("--true-parts", metavar="PREDICTIONS.jsonl", help="the structure model's predictions for the same "
                   "records on their own parts, made elsewhere (`jax3dc eval run`); default: decoded here")
    p.add_argument("--out", default="runs/pixels", help="one predict folder per record and backend, the true parts' "
                   "predictions, summary.json and summary.md")
    p.add_argument("--dtype", default="bfloat16", choices=("bfloat16", "float32"))
    p.add_argument("--max-new-tokens", type=int, default=1536, help="most tokens per structure, from pixels and on "
                   "true parts alike")
    p.add_argument("--batch-size", type=int, default=8, help="records per batch of the true parts' decode")
    args = p.parse_args(argv)

    out = Path(args.out)
    records = rest_records(args.data, args.split, args.limit)
    if not records:
        raise SystemExit(f"no plain rest-view {args.split} records in {', '.join(args.data)}")
    if len({r.key for r in records}) < len(records):
        raise SystemExit(f"{', '.join(args.data)}: two records share a key (one object in two datasets); "
                         "evaluate the datasets apart")
    references = [reference_of(r) for r in records]
    rows = backends(args.stage1_model, args.slots_model)
    structure_model = Path(args.structure_model) if args.structure_model else default_structure_model()
    checkpoints = Checkpoints(args.dtype)
    started = time.perf_counter()
    true_parts = true_parts_summary(records, references, true_parts_predictions(args, records, structure_model,
                                                                                checkpoints))
    summaries: dict[str, dict[str, Any]] = {}
    for backend in rows:
        results = []
        for k, (record, reference) in enumerate(zip(records, references)):
            result = predict_record(record, reference, out / backend.name / f"object_{k:03d}", backend.stage1,
                                    checkpoints, args.max_new_tokens, structure_model)
            results.append(result)
            print(f"[{backend.name} {k + 1}/{len(records)}] {record.key}: {result.seconds:.1f} s, parts matched "
                  f"{result.parts.matched} of {result.parts.reference}, extra {result.parts.extra}, RS-dgIoU "
                  f"{result.parts.dgiou:.3f}" + (f"; failed: {result.failure}" if result.failure else ""), flush=True)
        summaries[backend.name] = backend_summary(backend, records, references, results)
    summaries[TRUE_PARTS] = true_parts

    tables = format_tables([(s["label"], s["table1"]) for s in summaries.values()])
    table = summary_table(summaries)
    heading = f"{len(records)} rest-view {args.split} records of {', '.join(args.data)}"
    summary = {"data": args.data, "records": len(records), "structure_model": str(structure_model),
               "dtype": args.dtype, "wall_s": time.perf_counter() - started, "backends": summaries}
    out.mkdir(parents=True, exist_ok=True)
    (out / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
    (out / "summary.md").write_text(f"# From pixels, per stage-1 backend\n\n{heading}\n\n{table}\n"
                                    f"## Table 1\n\n```\n{tables}\n```\n")
    print(f"\n{heading}\n\n{table}\n{tables}")
    factory = summaries["factory"]["stage1_parameters"]
    if factory:
        print(f"\nfactory network on the {factory['objects']} records with factory parameters: runs "
              f"{factory['runs']:.1f}, category {factory['category']:.1f}, part count exact "
              f"{factory['count_exact']:.1f}, matched part-box IoU {factory['matched_iou']:.1f}")
    print(f"summary: {out / 'summary.json'}, {out / 'summary.md'}")
    return summary


if __name__ == "__main__":
    main()
