"""The ``jax3dc eval`` command group: score predictions, score the no-training baselines.

Each module in SUBCOMMAND_MODULES has ``register(subparsers)`` adding more ``jax3dc eval ...``
subcommands (``eval run``: batched generation over a test split, or every record with ``--split all``,
and a report folder).
"""

from __future__ import annotations

import argparse
import importlib
import json
from pathlib import Path
from typing import Any, Iterable

from tqdm import tqdm

from eval.baselines import BOX_BASELINES
from eval.limits import MAX_SCORED_PARTS
from eval.metrics.cases import build_cases, load_predictions, load_references
from eval.metrics.score import evaluate
from eval.metrics.tables import format_tables
from jax3dc.cli_args import command_group, positive_int
from jax3dc.errors import InputFileError
from jax3dc.structure import to_dict

SUBCOMMAND_MODULES: tuple[str, ...] = ("eval.run",)


def _write_jsonl(path: Path, items: Iterable[dict[str, Any]]) -> None:
    with path.open("w", encoding="utf-8") as f:
        for item in items:
            f.write(json.dumps(item, separators=(",", ":")) + "\n")


def write_evaluation(evaluation: Any, out_dir: Path) -> None:
    """metrics.json and per_object.jsonl under ``out_dir``."""
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        (out_dir / "metrics.json").write_text(json.dumps(evaluation.metrics, indent=1) + "\n")
        _write_jsonl(out_dir / "per_object.jsonl", evaluation.rows)
    except OSError as e:
        raise InputFileError(out_dir, f"cannot write results: {e.strerror or e}") from None


def _cases_with_progress(refs: list, preds: dict) -> list:
    cases = []
    for ref in tqdm(refs, desc="parsing", unit="obj", leave=False, disable=len(refs) < 500):
        cases.extend(build_cases([ref], preds))
    return cases


def run_metrics(args: argparse.Namespace) -> int:
    refs = load_references(args.ref, args.max_parts)
    preds = load_predictions(args.pred)
    unknown = len(set(preds) - {r.key for r in refs})
    evaluation = evaluate(_cases_with_progress(refs, preds))
    out = Path(args.out) if args.out else Path(args.pred).with_suffix(".metrics")
    write_evaluation(evaluation, out)
    print(format_tables([(args.name or Path(args.pred).stem, evaluation.metrics)]))
    counts = evaluation.metrics["counts"]
    print(f"\n{counts['parsed']}/{counts['objects']} predictions parsed; {counts['joints_matched']} joints "
          f"matched of {counts['joints_ref']} reference / {counts['joints_pred']} predicted")
    if evaluation.metrics["parse_failures"]:
        print("parse failures by rule: " + ", ".join(f"{k} {v}" for k, v in evaluation.metrics["parse_failures"].items()))
    if unknown:
        print(f"ignored {unknown} predictions whose key is not in {args.ref}")
    print(f"wrote {out / 'metrics.json'} and {out / 'per_object.jsonl'}")
    return 0


def run_baselines(args: argparse.Namespace) -> int:
    refs = load_references(args.ref, args.max_parts)
    out = Path(args.out)
    systems = []
    for name in (*BOX_BASELINES, "reference"):
        if name == "reference":
            preds = {r.key: to_dict(r.structure) for r in refs}
        else:
            make = BOX_BASELINES[name]
            preds = {r.key: to_dict(make(r.boxes, r.structure.nodes.keys())) for r in refs}
        evaluation = evaluate(_cases_with_progress(refs, preds))
        write_evaluation(evaluation, out / name)
        try:
            _write_jsonl(out / name / "predictions.jsonl", ({"key": k, "structure": s} for k, s in preds.items()))
        except OSError as e:
            raise InputFileError(out, f"cannot write predictions: {e.strerror or e}") from None
        systems.append((name, evaluation.metrics))
    tables = format_tables(systems)
    (out / "tables.txt").write_text(tables + "\n")
    print(tables)
    print(f"\nwrote {out}/<baseline>/{{predictions.jsonl,metrics.json,per_object.jsonl}} and {out / 'tables.txt'}")
    return 0


_LINE_FORMATS = (
    'REF lines: {"key": ..., "structure": {...}, "boxes": {...}}; PRED lines: {"key": ..., "text": '
    '"<raw model output>"} or {"key": ..., "structure": {...}}.'
)


def register(subparsers: argparse._SubParsersAction) -> None:
    group = command_group(
        subparsers, "eval",
        help="score predicted structures (paper Tables 1 and 2) and baselines",
        description="Evaluation commands. Run `jax3dc eval SUBCOMMAND --help` for each.",
    )

    metrics = group.add_parser(
        "metrics",
        help="score predictions against references",
        description="Score predicted structures against references with the metrics of SPEC §5 "
        "(parse, tree, joints, failure attribution, relations, and multi-object partitions over "
        "references with more than one root). Both sides are canonicalised first. A missing or "
        "invalid prediction counts as a parse failure. " + _LINE_FORMATS,
    )
    metrics.add_argument("--pred", required=True, help="predictions JSONL")
    metrics.add_argument("--ref", required=True, help="references JSONL (structure + part boxes)")
    metrics.add_argument("--out", help="folder for metrics.json and per_object.jsonl (default: PRED with the suffix .metrics)")
    metrics.add_argument("--name", help="row name in the printed tables (default: PRED's file name)")
    metrics.add_argument("--max-parts", type=positive_int, default=MAX_SCORED_PARTS, metavar="N",
                         help="refuse a reference object of more parts (default: %(default)s)")
    metrics.set_defaults(func=run_metrics)

    baselines = group.add_parser(
        "baselines",
        help="score the baselines that need no training",
        description="Build and score the no-training baselines from each reference's part boxes: "
        "'star' (largest part the root, all others rigid children), 'heuristic' (containment / "
        "adjacency tree, door hinges and drawer slides guessed from box shapes), and 'reference' "
        "(the reference itself, a sanity row that must score 100). " + _LINE_FORMATS,
    )
    baselines.add_argument("--ref", required=True, help="references JSONL (structure + part boxes)")
    baselines.add_argument("--out", required=True, help="folder for each baseline's predictions and metrics")
    baselines.add_argument("--max-parts", type=positive_int, default=MAX_SCORED_PARTS, metavar="N",
                           help="refuse a reference object of more parts (default: %(default)s)")
    baselines.set_defaults(func=run_baselines)

    for name in SUBCOMMAND_MODULES:
        importlib.import_module(name).register(group)
