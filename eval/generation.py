"""Generating predictions for a set of records into ``predictions.jsonl``, resumable.

Predictions are appended batch by batch (with K > 1 candidates, every candidate and its
log-likelihood too); a rerun skips the keys already there, so a killed run resumes where it
stopped. Only the evaluation writes such files; ``jax3dc.sampler`` decodes.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

from tqdm import tqdm

from jax3dc.decoding import DecodeOptions
from jax3dc.sampler import Example, Sampler


def read_predictions_file(path: Path) -> dict[str, dict[str, Any]]:
    """Lines already written by an earlier (possibly killed) run, by key.

    A torn last line (the run died mid-write) is dropped and the file rewritten without it.
    """
    if not path.exists():
        return {}
    done: dict[str, dict[str, Any]] = {}
    lines = path.read_text(encoding="utf-8").splitlines()
    torn = False
    for line in lines:
        try:
            item = json.loads(line)
        except json.JSONDecodeError:
            torn = True
            continue
        if isinstance(item, dict) and isinstance(item.get("key"), str) and isinstance(item.get("text"), str):
            done[item["key"]] = item
    if torn:
        path.write_text("".join(json.dumps(v, separators=(",", ":")) + "\n" for v in done.values()), encoding="utf-8")
    return done



@dataclass
class GenerationStats:
    """What this call generated (keys already in the predictions file are not counted)."""

    objects: int = 0
    new_tokens: int = 0
    unstopped: int = 0  # cut at max_new_tokens before a stop token
    seconds: float = 0.0  # wall time of the batches, compiles included

    def summary(self) -> str:
        if not self.objects:
            return "nothing to generate: every key is already in predictions.jsonl"
        rate = self.new_tokens / self.seconds if self.seconds else float("nan")
        return (f"generated {self.objects} objects, {self.new_tokens} tokens in {self.seconds:.1f} s "
                f"({rate:.1f} tokens/s, compiles included); {self.unstopped} hit --max-new-tokens")


def generate_predictions(generator: Sampler, records: Sequence[Example], out_path: Path, batch_size: int,
                         max_new_tokens: int, bucket: int = 64, options: DecodeOptions = DecodeOptions(),
                         task: str = "structure") -> tuple[dict[str, dict[str, Any]], GenerationStats]:
    """Key -> prediction line for every record (``text``: the greedy candidate; ``candidates``
    when there are several), generating only the keys not yet in ``out_path``."""
    done = read_predictions_file(out_path)
    todo = [r for r in records if r.key not in done]
    stats = GenerationStats()
    if todo:
        prompts = sorted((generator.prompt(r, task) for r in todo), key=lambda p: (-len(p.input_ids), p.key))
        start_time = time.perf_counter()
        with out_path.open("a", encoding="utf-8") as f, tqdm(total=len(prompts), desc="generating", unit="obj") as bar:
            for start in range(0, len(prompts), batch_size):
                batch = prompts[start:start + batch_size]
                results = generator.generate_batch(batch, batch_size, max_new_tokens, bucket, options)
                for p, samples in zip(batch, results):
                    item = {"key": p.key, **samples[0].to_dict()}
                    if len(samples) > 1:
                        item["candidates"] = [x.to_dict() for x in samples]
                    f.write(json.dumps(item, separators=(",", ":")) + "\n")
                    done[p.key] = item
                    stats.objects += 1
                    stats.new_tokens += sum(x.new_tokens for x in samples)
                    stats.unstopped += sum(not x.stopped for x in samples)
                f.flush()
                bar.update(len(batch))
        stats.seconds = time.perf_counter() - start_time
    return {r.key: done[r.key] for r in records}, stats
