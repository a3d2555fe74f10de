"""Scene grouping (``jax3dc.structure.scene_grouping``) measured on predictions already made.

    python3 -m bench.scene_grouping --bench runs/r3/bench --out runs/r3/grouping
    python3 -m bench.real_objects --score-only --out runs/r3/grouping --model grouped --compare raw

The greedy predictions of a ``bench.real_objects`` folder were decoded without the step; this
applies it to each line exactly as the sampler does after decoding (``regroup_text`` with the
record's legend boxes), and lays out OUT as a ``bench.real_objects`` folder (OUT/model: grouped,
OUT/compare: raw, the sets and baselines linked), so ``--score-only`` prints raw and grouped side
by side on every set. Lines whose key is in no set are dropped; changed keys go to OUT/changed.txt.
"""

from __future__ import annotations

import argparse
import json
import shutil
from pathlib import Path
from typing import Iterable

from data_pipeline.shards import shard_paths
from eval.records import read_records
from jax3dc.prompt import legend_boxes
from jax3dc.structure.scene_grouping import regroup_text


def legend_of_sets(sets: Path) -> dict[str, dict]:
    """Record key -> its legend boxes, over every set of a bench folder."""
    return {r.key: legend_boxes(r.prompt) for folder in sorted(sets.iterdir())
            if (folder / "manifest.json").exists() for r in read_records(shard_paths([str(folder)], None))}


def main(argv: Iterable[str] | None = None) -> list[str]:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--bench", required=True, help="a bench.real_objects output folder (sets/, model/)")
    p.add_argument("--out", required=True, help="folder to write (a bench.real_objects folder for --score-only)")
    a = p.parse_args(None if argv is None else list(argv))
    bench, out = Path(a.bench), Path(a.out)
    boxes = legend_of_sets(bench / "sets")
    for label in ("model", "compare"):
        (out / label).mkdir(parents=True, exist_ok=True)
        shutil.copy(bench / "model" / "references.jsonl", out / label / "references.jsonl")
    for name in ("sets", "baselines"):
        if (bench / name).exists() and not (out / name).exists():
            (out / name).symlink_to((bench / name).resolve())
    changed = []
    with (bench / "model" / "predictions.jsonl").open(encoding="utf-8") as f, \
            (out / "model" / "predictions.jsonl").open("w", encoding="utf-8") as grouped, \
            (out / "compare" / "predictions.jsonl").open("w", encoding="utf-8") as raw:
        for line in f:
            try:
                item = json.loads(line)
            except json.JSONDecodeError:  # the torn last line of a run still writing
                continue
            if item.get("key") not in boxes:
                continue
            raw.write(json.dumps(item, separators=(",", ":")) + "\n")
            text = regroup_text(item["text"], boxes[item["key"]])
            if text != item["text"]:
                changed.append(item["key"])
            grouped.write(json.dumps({**item, "text": text}, separators=(",", ":")) + "\n")
    (out / "changed.txt").write_text("".join(k + "\n" for k in changed))
    print(f"{len(changed)} predictions regrouped; wrote {out}")
    return changed


if __name__ == "__main__":
    main()
