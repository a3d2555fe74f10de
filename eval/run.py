"""``jax3dc eval run``: generate structures for a test split (or ``--split all``: every record),
score them and write a report folder.

Three sources of predictions: the checkpoint (batched jitted generation, resumable through
predictions.jsonl), ``--predictions FILE`` (score lines made elsewhere), or
``--reference-as-prediction`` (each record's own target: a sanity run that must score 100).

``--task code`` scores the stage-1 code backend instead: the model writes a part program from
image I alone, the interpreter runs it, and eval.metrics.programs compares its parts with those
of the record's own program (programs.jsonl per object, metrics.json, tables.md).
``--task parameters`` scores the stage-1 parameter backend (eval.parameters_run).

Generation is grammar-constrained unless ``--unconstrained``. With ``--candidates K`` > 1 or
``--repair``, a verification stage follows (``eval.run_verify``): the physics verdict picks
among the K candidates and repairs the winner's flagged joints; verified.jsonl says which won,
why, and what was repaired, and its structures are the ones scored.
"""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path

from tqdm import tqdm

from data_pipeline.shards import shard_paths
from eval.metrics.cases import build_cases, load_predictions
from eval.metrics.programs import score_program, summarise
from eval.metrics.tables import format_tables
from eval.records import read_records, reference_of
from jax3dc.cli_args import positive_int
from jax3dc.compilation import DEFAULT_DIR as DEFAULT_CACHE_DIR, use_compile_cache
from jax3dc.decoding import DecodeOptions, add_decoding_arguments, decoding_from_args
from jax3dc.errors import InputFileError, Jax3dcError
from jax3dc.release import default_structure_model
from jax3dc.structure import boxes_to_dict, to_dict
from jax3dc.xla_flags import GENERATION_GPU_FLAGS, apply_gpu_defaults

ALL_SPLITS = "all"  # --split value that reads every shard and keeps every record


def _write_references(refs: list, path: Path) -> None:
    """references.jsonl in the format of ``jax3dc eval metrics --ref`` (to rescore without shards)."""
    with path.open("w", encoding="utf-8") as f:
        for ref in refs:
            line = {"key": ref.key, "structure": to_dict(ref.structure), "boxes": boxes_to_dict(ref.boxes)}
            f.write(json.dumps(line, separators=(",", ":")) + "\n")


def source_folders(folders: list[str]) -> dict[str, Path]:
    """Object id -> its source folder: every sub-folder of the --sources folders."""
    missing = [folder for folder in folders if not Path(folder).is_dir()]
    if missing:
        raise InputFileError(missing[0], "--sources folder not found")
    return {p.name: p for folder in folders for p in Path(folder).iterdir() if p.is_dir()}


def run_eval(args: argparse.Namespace) -> int:
    apply_gpu_defaults(GENERATION_GPU_FLAGS)  # before the backend starts (generation runs here)
    if args.physics_backend == "mjx":  # before the first compile: JAX reads the setting once
        use_compile_cache(args.compile_cache)
    # lazy: `jax3dc --help` imports this module; the decoder costs it 37 ms more, the report (overlays,
    # viewers, the part rebuilder) 43 ms
    from eval.generation import generate_predictions
    from eval.report import write_report
    from jax3dc.sampler import Sampler

    sources = [args.predictions is not None, args.reference_as_prediction, args.checkpoint is not None]
    if sum(sources) > 1:
        raise Jax3dcError("give at most one of --checkpoint, --predictions, --reference-as-prediction")
    if args.ground_joints and not (args.task == "structure" and args.predictions is None and not args.reference_as_prediction):
        raise Jax3dcError("--ground-joints grounds structures as a checkpoint decodes them (--task structure); to ground "
                          "a predictions file, run python3 -m eval.evaluate joint_grounding")
    if not any(sources):  # the shipped default model

        args.checkpoint = str(default_structure_model())
    split = None if args.split == ALL_SPLITS else args.split  # None: every shard, every record
    records = []
    for record in read_records(shard_paths(args.data, split), split):
        records.append(record)
        if args.limit and len(records) >= args.limit:
            break
    if not records:
        raise InputFileError(", ".join(args.data), "no records" if split is None else f"no records of split {split!r}")
    by_key = {r.key: r for r in records}
    if len(by_key) != len(records):
        raise InputFileError(", ".join(args.data), "duplicate record keys")
    refs = [reference_of(r) for r in records]
    out = Path(args.out)
    try:
        out.mkdir(parents=True, exist_ok=True)
        _write_references(refs, out / "references.jsonl")
    except OSError as e:
        raise InputFileError(out, f"cannot write: {e.strerror or e}") from None

    if args.task == "code":
        return _run_code(args, records, out)
    if args.task == "parameters":
        from eval.parameters_run import run_parameters_task  # lazy: the decoder and factories (62 ms)

        return run_parameters_task(args, records, out)
    notes = []
    if args.predictions is not None:
        preds, name = load_predictions(args.predictions), Path(args.predictions).stem
    elif args.reference_as_prediction:
        preds, name = {r.key: r.target for r in records}, "reference"
    else:
        decoding = decoding_from_args(args)
        options = decoding.options
        generator = Sampler.load(args.checkpoint, dtype=decoding.dtype)
        lines, stats = generate_predictions(generator, records, out / "predictions.jsonl", args.batch_size,
                                            decoding.max_new_tokens, args.bucket, options)
        notes.append(("constrained" if options.constrained else "unconstrained") + f" decoding, {options.candidates} "
                     f"candidate(s) per object; " + stats.summary())
        print(notes[-1])
        preds = {key: line["text"] for key, line in lines.items()}
        name = Path(args.checkpoint).name
        if options.candidates > 1 or decoding.repair:
            from eval.run_verify import verify_predictions  # lazy: the verifier and its pool (76 ms)

            preds, verified = verify_predictions(records, lines, out / "verified.jsonl", args.workers, decoding.repair,
                                                 source_folders(args.sources), args.physics_backend)
            notes.append(verified.summary())
            print(notes[-1])
    extra = {"references.jsonl": "references.jsonl"}
    for produced in ("predictions.jsonl", "verified.jsonl"):
        if (out / produced).exists():
            extra[produced] = produced
    evaluation = write_report(out, name, build_cases(refs, preds), by_key, {r.key: r for r in refs},
                              args.overlays, extra, notes, args.viewers, source_folders(args.sources))
    print(format_tables([(name, evaluation.metrics)]))
    counts = evaluation.metrics["counts"]
    print(f"\n{counts['parsed']}/{counts['objects']} predictions parsed")
    if evaluation.metrics["parse_failures"]:
        print("parse failures by rule: " + ", ".join(f"{k} {v}" for k, v in evaluation.metrics["parse_failures"].items()))
    print(f"wrote the report to {out / 'index.md'}")
    return 0


def _run_code(args: argparse.Namespace, records: list, out: Path) -> int:
    """The code task: programs from the checkpoint (or --predictions, or the records' own), scored."""
    from eval.generation import generate_predictions  # lazy: as in run_eval (37 ms)
    from jax3dc.sampler import Sampler  # lazy: as in run_eval

    if args.candidates > 1 or args.repair:
        raise Jax3dcError("--candidates and --repair choose structures; the code task takes neither")
    missing = [r.key for r in records if not r.program]
    if missing:
        raise InputFileError(", ".join(args.data), f"{len(missing)} records have no part program (first: {missing[0]})")
    if args.predictions is not None:
        texts, name = load_predictions(args.predictions), Path(args.predictions).stem
    elif args.reference_as_prediction:
        texts, name = {r.key: r.program for r in records}, "reference"
    else:
        generator = Sampler.load(args.checkpoint, dtype=args.dtype)
        lines, stats = generate_predictions(generator, records, out / "predictions.jsonl", args.batch_size,
                                            args.max_new_tokens, args.bucket,
                                            DecodeOptions(constrained=not args.unconstrained), "code")
        print(("unconstrained" if args.unconstrained else "part-program grammar") + " decoding; " + stats.summary())
        texts, name = {key: line["text"] for key, line in lines.items()}, Path(args.checkpoint).name
    scores = [score_program(r.key, r.program, texts.get(r.key, "")) for r in tqdm(records, desc="running programs", unit="obj")]
    metrics = summarise(scores)
    with (out / "programs.jsonl").open("w", encoding="utf-8") as f:
        for score in scores:
            f.write(json.dumps(score.to_dict(), separators=(",", ":")) + "\n")
    (out / "metrics.json").write_text(json.dumps({"model": name, "task": "code", **metrics}, indent=1), encoding="utf-8")
    table = ("| model | objects | runs | ids | count err | part box IoU | Chamfer (nu) |\n|---|---|---|---|---|---|---|\n"
             f"| {name} | {metrics['objects']} | {_fmt(metrics['runs'])} | {_fmt(metrics['ids'])} | "
             f"{_fmt(metrics['count_err'], 2)} | {_fmt(metrics['box_iou'])} | {_fmt(metrics['chamfer'], 3)} |")
    (out / "tables.md").write_text(table + "\n", encoding="utf-8")
    print(table)
    print(f"wrote {out / 'programs.jsonl'}, {out / 'metrics.json'}")
    return 0


def _fmt(value: float | None, digits: int = 1) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def register(subparsers: argparse._SubParsersAction) -> None:
    run = subparsers.add_parser(
        "run",
        help="generate over a test split, score, write a report folder",
        description="Generate a structure for every record of a split (batched, jitted, greedy, under the "
        "structure grammar unless --unconstrained; --candidates K / --repair add the physics-verified choice), parse "
        "and score the generations against the records' targets (SPEC §5), and write a report folder: "
        "metrics.json, per_object.jsonl, tables.md, per_category.md, failure_attribution.png, "
        "overlays/<key>.png (reference joints green, predicted red, drawn with the record's "
        "meta.camera), index.md, and index.html (a thumbnail, the metrics and a 3D viewer per object). Generations go to OUT/predictions.jsonl as they finish; running "
        "the same command again skips keys already there (delete that file to generate afresh, e.g. "
        "with another checkpoint). The end of the run prints tokens/s. Example: jax3dc eval run --checkpoint "
        "runs/ft/final --data data/shards --out reports/test",
    )
    run.add_argument("--data", nargs="+", required=True, metavar="SHARDS",
                     help="ArrayRecord shard files, or folders searched for them")
    run.add_argument("--out", required=True, help="report folder (created; reused to resume)")
    run.add_argument("--checkpoint", help="Hugging Face checkpoint folder (default: the shipped model, jax3dc/release) (config.json, safetensors, tokenizer, "
                     "preprocessor_config.json)")
    run.add_argument("--predictions", help="score this predictions JSONL instead of generating "
                     '({"key", "text"} or {"key", "structure"} lines)')
    run.add_argument("--reference-as-prediction", action="store_true",
                     help="score each record's own target (sanity check: everything must be 100)")
    run.add_argument("--task", default="structure", choices=("structure", "code", "parameters"),
                     help="structure (stage 2: I + S + prompt -> structure, the default) or code (stage 1: I -> part "
                     "program, scored by running it against the record's own program) or parameters (stage 1: I -> a factory's "
                     "category and parameters, run by the factory and scored against the record's own parts, matched "
                     "one-to-one by box overlap)")
    run.add_argument("--split", default="test",
                     help="split to evaluate: shard-name prefix and meta.split (default test); "
                     f"'{ALL_SPLITS}' scores every record of every shard")
    run.add_argument("--limit", type=int, default=0, help="evaluate only the first N records (0 = all)")
    run.add_argument("--batch-size", type=positive_int, default=8, help="rows generated together (default 8)")
    run.add_argument("--bucket", type=positive_int, default=64,
                     help="prompt lengths are padded to a multiple of this, limiting recompiles (default 64)")
    run.add_argument("--overlays", type=int, default=16, help="joint overlays for the first N records (default 16)")
    run.add_argument("--viewers", type=int, default=8,
                     help="interactive 3D viewers (viewers/<key>.html, linked from index.html) of the first N parsed "
                     "predictions, each with its physics verdict (about a second per object) (default 8)")
    add_decoding_arguments(run, "verified.jsonl", "verified.jsonl")
    run.add_argument("--workers", type=positive_int, default=max(1, (os.cpu_count() or 1)),
                     help="processes for the physics verdicts (default: one per core)")
    run.add_argument("--physics-backend", choices=("c", "mjx"), default="c",
                     help="how --candidates/--repair check: c (C MuJoCo in --workers processes) or mjx (the workers' "
                     "candidates' interpenetration sweeps launched together on the accelerator, rollouts in C; "
                     "bench/candidates_mjx.py). Default c")
    run.add_argument("--compile-cache", default=DEFAULT_CACHE_DIR, metavar="DIR",
                     help="with --physics-backend mjx: keep this run's compiled programs (the checks' launches, the "
                     "decoder's) here for the next run (default: %(default)s; '' turns it off; "
                     "JAX_COMPILATION_CACHE_DIR wins)")
    run.add_argument("--sources", nargs="*", default=[], metavar="FOLDER",
                     help="folders holding the source objects of imported records (their part meshes for the "
                     "physics verdict), e.g. the PartNet-Mobility folders given to data import")
    run.set_defaults(func=run_eval)
