"""``jax3dc eval run --task parameters``: the stage-1 parameter backend, scored.

The model writes a factory's category and parameters from image I alone (under the parameter
grammar unless ``--unconstrained``), the factory runs them into parts, and
eval.metrics.parameters compares those parts with the record's own: parts matched one-to-one by
box overlap (whatever their ids), part-count accuracy, Chamfer distance, the texts that run, and
the per-id scores stage 2 sees. Writes parameters.jsonl (per object), metrics.json and tables.md.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from tqdm import tqdm

from eval.metrics.cases import load_predictions
from eval.metrics.parameters import score_parameters, summarise
from jax3dc.errors import InputFileError, Jax3dcError
from jax3dc.factories.registry import SCHEMAS, run_parameters
from eval.generation import generate_predictions
from jax3dc.sampler import DecodeOptions, Sampler

COLUMNS = (("runs", "runs", 1), ("category", "category", 1), ("count_exact", "count exact", 1),
           ("matched_iou", "matched part-box IoU", 1), ("ids", "ids", 1), ("box_iou", "part-box IoU by id", 1),
           ("chamfer", "Chamfer (nu)", 3))


def table(name: str, metrics: dict) -> str:
    head = "| model | objects | " + " | ".join(title for _, title, _ in COLUMNS) + " |"
    rule = "|---" * (len(COLUMNS) + 2) + "|"
    cells = ["-" if metrics[k] is None else f"{metrics[k]:.{d}f}" for k, _, d in COLUMNS]
    return "\n".join([head, rule, f"| {name} | {metrics['objects']} | " + " | ".join(cells) + " |"])


def run_parameters_task(args: argparse.Namespace, records: list, out: Path) -> int:
    """Texts from the checkpoint (or --predictions, or the records' own), run and scored."""
    if args.candidates > 1 or args.repair:
        raise Jax3dcError("--candidates and --repair choose structures; the parameters task takes neither")
    missing = [r.key for r in records if not r.parameters]
    if missing:
        raise InputFileError(", ".join(args.data), f"{len(missing)} records have no factory parameters "
                             f"(first: {missing[0]}; split/merge variants, scenes and imports have none)")
    if args.predictions is not None:
        texts, name = load_predictions(args.predictions), Path(args.predictions).stem
    elif args.reference_as_prediction:
        texts, name = {r.key: r.parameters for r in records}, "reference"
    else:
        generator = Sampler.load(args.checkpoint, dtype=args.dtype)
        lines, stats = generate_predictions(generator, records, out / "predictions.jsonl", args.batch_size,
                                            args.max_new_tokens, args.bucket,
                                            DecodeOptions(constrained=not args.unconstrained, schemas=SCHEMAS),
                                            "parameters")
        print(("unconstrained" if args.unconstrained else "parameter grammar") + " decoding; " + stats.summary())
        texts, name = {key: line["text"] for key, line in lines.items()}, Path(args.checkpoint).name
    scores = [score_parameters(r.key, r.parameters, texts.get(r.key, ""), SCHEMAS, run_parameters)
              for r in tqdm(records, desc="running parameters", unit="obj")]
    metrics = summarise(scores)
    with (out / "parameters.jsonl").open("w", encoding="utf-8") as f:
        for score in scores:
            f.write(json.dumps(score.to_dict(), separators=(",", ":")) + "\n")
    (out / "metrics.json").write_text(json.dumps({"model": name, "task": "parameters", **metrics}, indent=1),
                                      encoding="utf-8")
    text = table(name, metrics)
    (out / "tables.md").write_text(text + "\n", encoding="utf-8")
    print(text)
    print(f"wrote {out / 'parameters.jsonl'}, {out / 'metrics.json'}")
    return 0
