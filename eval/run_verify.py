"""The verification stage of ``jax3dc eval run``: candidates chosen by the physics verdict, the
winner repaired, one line per object in ``verified.jsonl`` (resumable like predictions.jsonl).
The objects are verified in the core's worker pool (``jax3dc.verify.pool``); each worker rebuilds
its record's parts (``record_object``).

A line says which candidate won and why, its verdict, and each repair (part, kind, joint before
and after); its ``text`` is the structure that is scored: the repaired one where a repair was
kept, else the winner (canonical JSON), else the winner's raw text when nothing parses.
"""

from __future__ import annotations

import json
import time
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path
from typing import Any

from tqdm import tqdm

from data_pipeline.record import Record
from data_pipeline.record_parts import record_parts
from eval.generation import read_predictions_file
from jax3dc.structure import boxes_from_dict, to_json
from jax3dc.verify.pool import Job, verify_many
from jax3dc.verify.select import Candidate
from jax3dc.verify.verified import ObjectParts, Verified


@dataclass
class VerifyStats:
    """What this call verified (objects already in verified.jsonl are not counted)."""

    objects: int = 0
    reasons: Counter = field(default_factory=Counter)
    repaired_objects: int = 0
    repairs: int = 0
    seconds: float = 0.0

    def summary(self) -> str:
        if not self.objects:
            return "nothing to verify: every key is already in verified.jsonl"
        reasons = "; ".join(f"{n}× {r}" for r, n in self.reasons.most_common())
        return (f"verified {self.objects} objects in {self.seconds:.1f} s ({self.seconds / self.objects:.2f} s each): "
                f"{reasons}; {self.repairs} repairs kept on {self.repaired_objects} objects")


def candidates_of(line: Mapping[str, Any]) -> tuple[Candidate, ...]:
    """A predictions.jsonl line's candidates (one line without ``candidates`` is one candidate)."""
    items = line.get("candidates") or [line]
    return tuple(Candidate(str(c["text"]), float(c.get("logprob", 0.0))) for c in items)


def record_object(record: Record, sources: Mapping[str, Path]) -> ObjectParts:
    """A record's object as verification needs it: its parts rebuilt (``sources``: object id ->
    source folder, for imported records; see ``record_parts``) and its legend's boxes."""
    parts, scale, mounted = record_parts(record, sources)
    return ObjectParts(parts, scale, mounted, boxes_from_dict(record.meta["boxes"]))


def record_jobs(records: Sequence[Record], lines: Mapping[str, Mapping[str, Any]], repair: bool) -> list[Job]:
    """One job per record, its candidates from its predictions line; the records travel to the
    workers without their images (they need only the text fields)."""
    return [Job(r.key, candidates_of(lines[r.key]), replace(r, image_png=b"", seg_png=b""), repair) for r in records]


def verified_line(result: Verified, candidates: Sequence[Candidate]) -> dict[str, Any]:
    choice, fixed = result.choice, result.repaired
    row = choice.rows[choice.index]
    line: dict[str, Any] = {"key": result.key, "candidate": choice.index, "of": len(candidates), "reason": choice.reason,
                            "ok": row.ok, "flagged": row.flagged, "repairs": []}
    if fixed is not None and fixed.repairs:
        line["text"] = to_json(fixed.structure)
        line["ok"] = fixed.after.ok
        line["repairs"] = [r.to_dict() for r in fixed.repairs]
    elif choice.structure is not None:
        line["text"] = to_json(choice.structure)
    else:
        line["text"] = candidates[choice.index].text
    return line


def verify_predictions(records: Sequence[Record], lines: Mapping[str, Mapping[str, Any]], out_path: Path, workers: int,
                       repair: bool, sources: Mapping[str, Path] | None = None, backend: str = "c",
                       chunk: int | None = None) -> tuple[dict[str, str], VerifyStats]:
    """Key -> the text to score for every record, verifying only keys not yet in ``out_path``."""
    done = read_predictions_file(out_path)
    todo = [r for r in records if r.key not in done]
    stats = VerifyStats()
    load = partial(record_object, sources=dict(sources or {}))
    chunk = chunk or max(1, 2 * workers)
    start = time.perf_counter()
    with out_path.open("a", encoding="utf-8") as f, tqdm(total=len(todo), desc="verifying", unit="obj") as bar:
        for lo in range(0, len(todo), chunk):
            batch = todo[lo:lo + chunk]
            jobs = record_jobs(batch, lines, repair)
            for job, result in zip(jobs, verify_many(jobs, load, workers, backend)):
                line = verified_line(result, job.candidates)
                f.write(json.dumps(line, separators=(",", ":")) + "\n")
                done[line["key"]] = line
                stats.objects += 1
                stats.reasons[line["reason"]] += 1
                stats.repairs += len(line["repairs"])
                stats.repaired_objects += bool(line["repairs"])
            f.flush()
            bar.update(len(batch))
    stats.seconds = time.perf_counter() - start
    return {r.key: done[r.key]["text"] for r in records}, stats
