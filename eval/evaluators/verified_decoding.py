"""Verified decoding against greedy decoding, on the same records and model (issue: verified decoding).

Rows: greedy (unconstrained), constrained (grammar, greedy), best-of-K for K in --ks (one
constrained batched decode of max(K) candidates per object, the first greedy; best-of-K uses the
first K), constrained + repair, best-of-8 + repair — every Table 1 column and success, beside the
no-learning heuristic. Repairs try --repair-kinds (pivot moves by default). Timing: seconds per object of each decode (compiles included, batch
--batch objects), of the physics verdicts (per object, over --workers processes), and decode
tokens/s of unconstrained vs constrained greedy at batch --batch, timed on a second run of the
same batch so compiles are out.

    python3 -m eval.evaluate verified_decoding --data DATA --split test --limit 300 --out OUT [--sources DIR]

Resumable: each decode and the verification write JSONL files in OUT and skip what is there.
Writes OUT/tables-KINDS.md and OUT/summary-KINDS.json.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from concurrent.futures import ProcessPoolExecutor
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import multiprocessing as mp
import numpy as np

from jax3dc.xla_flags import GENERATION_GPU_FLAGS, apply_gpu_defaults

apply_gpu_defaults(GENERATION_GPU_FLAGS)

from data_pipeline.record import Record  # noqa: E402
from data_pipeline.shards import shard_paths  # noqa: E402
from eval.baselines import heuristic  # noqa: E402
from eval.records import read_records, reference_of  # noqa: E402
from eval.generation import generate_predictions  # noqa: E402
from jax3dc.sampler import DecodeOptions, Sampler  # noqa: E402
from eval.metrics.cases import build_cases  # noqa: E402
from eval.metrics.score import evaluate  # noqa: E402
from eval.metrics.tables import format_tables  # noqa: E402
from data_pipeline.record_parts import record_parts  # noqa: E402
from jax3dc.verify.repair import ALL_KINDS, FLIPPED, PIVOT, SWAPPED, repair  # noqa: E402
from jax3dc.verify.select import Candidate, Row, choose, rank, parse_candidate  # noqa: E402
from eval.run_verify import candidates_of  # noqa: E402
from jax3dc.release import default_structure_model  # noqa: E402
from jax3dc.structure import boxes_from_dict, to_json  # noqa: E402
from jax3dc.verify.verdicts import Physics, VerdictCache  # noqa: E402


KIND_NAMES = {"flip": FLIPPED, "pivot": PIVOT, "swap": SWAPPED}


def _winner(rows: tuple[Row, ...], k: int) -> int:
    return max(range(min(k, len(rows))), key=lambda i: (rank(rows[i]), -i))


def _check(parts: dict, scale: float, mounted: bool) -> VerdictCache:
    """One object's verdicts with one rollout thread: the objects run in parallel worker processes."""
    return VerdictCache(Physics(parts, scale, mounted, threads=1))


def _choose(job: tuple[Record, tuple[Candidate, ...], dict[str, Path], tuple[int, ...]]) -> dict[str, Any]:
    """One object: the verdict of every distinct candidate and the best-of-K winners."""
    record, candidates, sources, ks = job
    start = time.perf_counter()
    parts, scale, mounted = record_parts(record, sources)
    boxes = boxes_from_dict(record.meta["boxes"])
    choice = choose(candidates, boxes, _check(parts, scale, mounted))
    out: dict[str, Any] = {"key": record.key, "rows": [[r.parsed, r.ok, r.flagged, r.logprob] for r in choice.rows]}
    for k in ks:
        i = _winner(choice.rows, k)
        out[f"best_of_{k}"] = {"index": i, "text": candidates[i].text}
    out["seconds"] = time.perf_counter() - start
    return out


def _repair(job: tuple[Record, dict[str, Any], tuple[Candidate, ...], dict[str, Path], int, frozenset[str]]) -> dict[str, Any]:
    """Repairs of the greedy candidate and of the best-of-``repair_k`` winner where their verdict fails."""
    record, chosen, candidates, sources, repair_k, kinds = job
    start = time.perf_counter()
    rows = chosen["rows"]
    out: dict[str, Any] = {"key": record.key}
    for name, i in (("constrained_repair", 0), ("best_of_k_repair", chosen[f"best_of_{repair_k}"]["index"])):
        text, repairs = candidates[i].text, []
        parsed, ok = rows[i][0], rows[i][1]
        if parsed and not ok:
            parts, scale, mounted = record_parts(record, sources)
            boxes = boxes_from_dict(record.meta["boxes"])
            fixed = repair(parse_candidate(text, boxes.keys(), boxes), boxes, _check(parts, scale, mounted), kinds)
            if fixed.repairs:
                text, repairs = to_json(fixed.structure), [f"{r.part}:{r.kind}" for r in fixed.repairs]
        out[name] = {"index": i, "text": text, "repairs": repairs}
    out["seconds"] = time.perf_counter() - start
    return out


def _resumed(path: Path, records: list[Record], make, jobs_of, workers: int, label: str) -> tuple[dict[str, dict], float | None]:
    """Lines of ``path`` by key, computing (in ``workers`` processes) those of records not there yet;
    also the CPU seconds per newly computed object."""
    done: dict[str, dict] = {}
    if path.exists():  # a torn last line (a killed run) is dropped and redone
        for line in path.read_text().splitlines():
            try:
                item = json.loads(line)
                done[item["key"]] = item
            except (json.JSONDecodeError, KeyError):
                continue
    todo = [r for r in records if r.key not in done]
    if not todo:
        return done, None
    start = time.perf_counter()
    with path.open("a") as f, ProcessPoolExecutor(workers, mp_context=mp.get_context("spawn")) as pool:
        for n, item in enumerate(pool.map(make, jobs_of(todo), chunksize=1)):
            f.write(json.dumps(item, separators=(",", ":")) + "\n")
            f.flush()
            done[item["key"]] = item
            if (n + 1) % 50 == 0:
                print(f"[{label}] {n + 1}/{len(todo)} in {time.perf_counter() - start:.0f} s", flush=True)
    return done, sum(done[r.key]["seconds"] for r in todo) / len(todo)


def _tokens_per_s(generator: Sampler, records: list[Record], batch: int, max_new: int, constrained: bool) -> float:
    prompts = sorted((generator.prompt(r) for r in records[:batch]), key=lambda p: -len(p.input_ids))
    options = DecodeOptions(constrained=constrained)
    generator.generate_batch(prompts, batch, max_new, 64, options)  # compile
    start = time.perf_counter()
    samples = generator.generate_batch(prompts, batch, max_new, 64, options)
    seconds = time.perf_counter() - start
    return sum(s[0].new_tokens for s in samples) / seconds


def main(argv: Sequence[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--data", nargs="+", required=True)
    p.add_argument("--split", default="test")
    p.add_argument("--limit", type=int, default=300)
    p.add_argument("--out", required=True)
    p.add_argument("--model", help="checkpoint folder (default: the shipped model)")
    p.add_argument("--sources", nargs="*", default=[], help="folders of the source objects of imported records")
    p.add_argument("--ks", type=int, nargs="+", default=[4, 8, 16])
    p.add_argument("--repair-k", type=int, default=8)
    p.add_argument("--repair-kinds", nargs="+", default=["pivot"], choices=["all", *KIND_NAMES],
                   help="alternatives a repair tries (default: pivot, the repair default)")
    p.add_argument("--batch", type=int, default=32, help="objects per greedy decode batch")
    p.add_argument("--sampled-rows", type=int, default=256, help="rows per best-of-K decode batch (rows / K objects)")
    p.add_argument("--max-new-tokens", type=int, default=1536)
    p.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    p.add_argument("--dtype", default="bfloat16")
    p.add_argument("--skip-throughput", action="store_true")
    a = p.parse_args(argv)

    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    split = None if a.split == "all" else a.split
    records = list(read_records(shard_paths(a.data, split), split))[: a.limit or None]
    refs = [reference_of(r) for r in records]
    generator = Sampler.load(a.model or default_structure_model(), dtype=a.dtype)
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

    cands = {r.key: candidates_of(lines["sampled"][r.key]) for r in records}
    chosen, cpu = _resumed(out / "verified.jsonl", records, _choose,
                           lambda todo: [(r, cands[r.key], sources, tuple(a.ks)) for r in todo], a.workers, "choose")
    if cpu is not None:
        summary["verify_cpu_seconds_per_object"] = cpu
    kinds = ALL_KINDS if a.repair_kinds == ["all"] else frozenset(KIND_NAMES[k] for k in a.repair_kinds)
    tag = "-".join(sorted(a.repair_kinds)) + f"-k{a.repair_k}"
    repaired, cpu = _resumed(out / f"repaired-{tag}.jsonl", records, _repair,
                             lambda todo: [(r, chosen[r.key], cands[r.key], sources, a.repair_k, kinds) for r in todo],
                             a.workers, "repair")
    if cpu is not None:
        summary[f"repair_{tag}_cpu_seconds_per_object"] = cpu

    systems = {
        "heuristic": {r.key: to_json(heuristic(ref.boxes, ref.structure.nodes.keys())) for r, ref in zip(records, refs)},
        "greedy": {k: v["text"] for k, v in lines["greedy"].items()},
        "constrained": {k: v["text"] for k, v in lines["constrained"].items()},
    }
    for k in a.ks:
        systems[f"best-of-{k}"] = {r.key: chosen[r.key][f"best_of_{k}"]["text"] for r in records}
    systems[f"constrained+repair({tag})"] = {r.key: repaired[r.key]["constrained_repair"]["text"] for r in records}
    systems[f"best-of-{a.repair_k}+repair({tag})"] = {r.key: repaired[r.key]["best_of_k_repair"]["text"] for r in records}
    metrics = {name: evaluate(build_cases(refs, preds)).metrics for name, preds in systems.items()}
    table = format_tables(list(metrics.items()))
    repairs = sum(len(repaired[r.key]["best_of_k_repair"]["repairs"]) for r in records)
    winners = np.bincount([chosen[r.key][f"best_of_{k_max}"]["index"] for r in records], minlength=k_max).tolist()
    summary.update({"metrics": metrics, f"repairs_best_of_{a.repair_k}_{tag}": repairs, f"winner_index_best_of_{k_max}": winners})
    (out / f"tables-{tag}.md").write_text(table + "\n")
    (out / f"summary-{tag}.json").write_text(json.dumps(summary, indent=1, default=float))
    print(table)
    print(json.dumps({k: v for k, v in summary.items() if k != "metrics"}, default=float))


if __name__ == "__main__":
    main()
