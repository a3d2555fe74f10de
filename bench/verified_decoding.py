"""Verified decoding against greedy decoding, on the same records and model (issue: verified decoding).

Rows: greedy (unconstrained), constrained (grammar, greedy), best-of-K for K in --ks (one
constrained batched decode of max(K) candidates per object, the first greedy; best-of-K uses the
first K), constrained + repair, best-of-8 + repair — every Table 1 column and success, beside the
no-learning heuristic. Timing: seconds per object of each decode (compiles included, batch
--batch objects), of the physics verdicts (per object, over --workers processes), and decode
tokens/s of unconstrained vs constrained greedy at batch --batch, timed on a second run of the
same batch so compiles are out.

    python3 -m bench.verified_decoding --data DATA --split test --limit 300 --out OUT [--sources DIR]

Resumable: each decode and the verification write JSONL files in OUT and skip what is there.
Writes OUT/tables.md and OUT/summary.json.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import multiprocessing as mp
import numpy as np

from jax3dc.xla_flags import GENERATION_GPU_FLAGS, apply_gpu_defaults

apply_gpu_defaults(GENERATION_GPU_FLAGS)

from data_pipeline.record import Record  # noqa: E402
from data_pipeline.shards import shard_paths  # noqa: E402
from eval.baselines import heuristic  # noqa: E402
from eval.generation import DecodeOptions, Generator, generate_predictions, read_records, reference_of  # noqa: E402
from eval.metrics.cases import build_cases  # noqa: E402
from eval.metrics.score import evaluate  # noqa: E402
from eval.metrics.tables import format_tables  # noqa: E402
from eval.verified.parts import record_parts  # noqa: E402
from eval.verified.repair import repair  # noqa: E402
from eval.verified.select import Candidate, Row, _rank, choose, parse_candidate  # noqa: E402
from eval.verified.stage import candidates_of  # noqa: E402
from jax3dc.structure import boxes_from_dict, to_json  # noqa: E402


def _winner(rows: tuple[Row, ...], k: int) -> int:
    return max(range(min(k, len(rows))), key=lambda i: (_rank(rows[i]), -i))


def _verify(job: tuple[Record, tuple[Candidate, ...], dict[str, Path], tuple[int, ...], int]) -> dict[str, Any]:
    """One object: verdicts of every distinct candidate, the best-of-K winners, and repairs of the
    greedy candidate and of the best-of-``repair_k`` winner where their verdict fails."""
    record, candidates, sources, ks, repair_k = job
    start = time.perf_counter()
    parts, scale, mounted = record_parts(record, sources)
    boxes = boxes_from_dict(record.meta["boxes"])
    choice = choose(candidates, boxes.keys(), parts, scale, mounted, boxes, threads=1)
    out: dict[str, Any] = {"key": record.key, "rows": [[r.parsed, r.ok, r.flagged, r.logprob] for r in choice.rows]}
    for k in ks:
        i = _winner(choice.rows, k)
        out[f"best_of_{k}"] = {"index": i, "text": candidates[i].text}
    for name, i in (("constrained_repair", 0), (f"best_of_{repair_k}_repair", _winner(choice.rows, repair_k))):
        text, repairs = candidates[i].text, []
        if choice.rows[i].parsed and not choice.rows[i].ok:
            fixed = repair(parse_candidate(text, boxes.keys(), boxes), parts, scale, mounted, boxes, threads=1)
            if fixed.repairs:
                text, repairs = to_json(fixed.structure), [f"{r.part}:{r.kind}" for r in fixed.repairs]
        out[name] = {"index": i, "text": text, "repairs": repairs}
    out["seconds"] = time.perf_counter() - start
    return out


def _tokens_per_s(generator: Generator, records: list[Record], batch: int, max_new: int, constrained: bool) -> float:
    prompts = sorted((generator.prompt(r) for r in records[:batch]), key=lambda p: -len(p.input_ids))
    options = DecodeOptions(constrained=constrained)
    generator.generate_batch(prompts, batch, max_new, 64, options)  # compile
    start = time.perf_counter()
    samples = generator.generate_batch(prompts, batch, max_new, 64, options)
    seconds = time.perf_counter() - start
    return sum(s[0].new_tokens for s in samples) / seconds


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--data", nargs="+", required=True)
    p.add_argument("--split", default="test")
    p.add_argument("--limit", type=int, default=300)
    p.add_argument("--out", required=True)
    p.add_argument("--model", help="checkpoint folder (default: the shipped model)")
    p.add_argument("--sources", nargs="*", default=[], help="folders of the source objects of imported records")
    p.add_argument("--ks", type=int, nargs="+", default=[4, 8, 16])
    p.add_argument("--repair-k", type=int, default=8)
    p.add_argument("--batch", type=int, default=32, help="objects per greedy decode batch")
    p.add_argument("--sampled-rows", type=int, default=256, help="rows per best-of-K decode batch (rows / K objects)")
    p.add_argument("--max-new-tokens", type=int, default=1536)
    p.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    p.add_argument("--dtype", default="bfloat16")
    p.add_argument("--skip-throughput", action="store_true")
    a = p.parse_args()
    from jax3dc.release import default_structure_model

    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    split = None if a.split == "all" else a.split
    records = list(read_records(shard_paths(a.data, split), split))[: a.limit or None]
    refs = [reference_of(r) for r in records]
    generator = Generator.load(a.model or default_structure_model(), dtype=a.dtype)
    sources = {q.name: q for folder in a.sources for q in Path(folder).iterdir() if q.is_dir()}
    summary: dict[str, Any] = {"objects": len(records), "ks": a.ks, "batch": a.batch, "workers": a.workers}

    k_max = max(a.ks)
    decodes = {"greedy": DecodeOptions(constrained=False), "constrained": DecodeOptions(),
               "sampled": DecodeOptions(candidates=k_max)}
    lines = {}
    for name, options in decodes.items():
        batch = max(1, a.sampled_rows // options.candidates) if options.candidates > 1 else a.batch
        lines[name], stats = generate_predictions(generator, records, out / f"{name}.jsonl", batch, a.max_new_tokens, 64, options)
        if stats.objects:
            summary[f"decode_{name}"] = {"seconds_per_object": stats.seconds / stats.objects, "tokens": stats.new_tokens,
                                         "batch_objects": batch, "unstopped": stats.unstopped}
        print(f"[{name}] {stats.summary()}", flush=True)
    if not a.skip_throughput:
        summary["tokens_per_s"] = {mode: _tokens_per_s(generator, records, a.batch, a.max_new_tokens, mode == "constrained")
                                   for mode in ("unconstrained", "constrained")}
        print(f"[throughput] {summary['tokens_per_s']}", flush=True)

    verified_path = out / "verified.jsonl"
    done = {}
    if verified_path.exists():  # a torn last line (a killed run) is dropped and redone
        for line in verified_path.read_text().splitlines():
            try:
                item = json.loads(line)
                done[item["key"]] = item
            except (json.JSONDecodeError, KeyError):
                continue
    todo = [r for r in records if r.key not in done]
    start = time.perf_counter()
    jobs = [(r, candidates_of(lines["sampled"][r.key]), sources, tuple(a.ks), a.repair_k) for r in todo]
    with verified_path.open("a") as f, ProcessPoolExecutor(a.workers, mp_context=mp.get_context("spawn")) as pool:
        for n, item in enumerate(pool.map(_verify, jobs, chunksize=1)):
            f.write(json.dumps(item, separators=(",", ":")) + "\n")
            f.flush()
            done[item["key"]] = item
            if (n + 1) % 25 == 0:
                print(f"[verify] {n + 1}/{len(todo)} in {time.perf_counter() - start:.0f} s", flush=True)
    if todo:
        cpu = sum(done[r.key]["seconds"] for r in todo)
        summary["verify"] = {"wall_seconds_per_object": (time.perf_counter() - start) / len(todo),
                             "cpu_seconds_per_object": cpu / len(todo), "workers": a.workers}

    systems = {
        "heuristic": {r.key: to_json(heuristic(ref.boxes, ref.structure.nodes.keys())) for r, ref in zip(records, refs)},
        "greedy": {k: v["text"] for k, v in lines["greedy"].items()},
        "constrained": {k: v["text"] for k, v in lines["constrained"].items()},
    }
    for k in a.ks:
        systems[f"best-of-{k}"] = {r.key: done[r.key][f"best_of_{k}"]["text"] for r in records}
    systems["constrained+repair"] = {r.key: done[r.key]["constrained_repair"]["text"] for r in records}
    systems[f"best-of-{a.repair_k}+repair"] = {r.key: done[r.key][f"best_of_{a.repair_k}_repair"]["text"] for r in records}
    metrics = {name: evaluate(build_cases(refs, preds)).metrics for name, preds in systems.items()}
    table = format_tables(list(metrics.items()))
    repairs = sum(len(done[r.key][f"best_of_{a.repair_k}_repair"]["repairs"]) for r in records)
    winners = np.bincount([done[r.key][f"best_of_{k_max}"]["index"] for r in records], minlength=k_max).tolist()
    summary.update({"metrics": metrics, "repairs_best_of_repair_k": repairs, f"winner_index_best_of_{k_max}": winners})
    (out / "tables.md").write_text(table + "\n")
    (out / "summary.json").write_text(json.dumps(summary, indent=1, default=float))
    print(table)
    print(json.dumps({k: v for k, v in summary.items() if k != "metrics"}, default=float))


if __name__ == "__main__":
    main()
