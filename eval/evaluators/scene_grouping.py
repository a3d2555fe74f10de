"""Scene grouping (``jax3dc.structure.scene_grouping``) measured on predictions already made.

    python3 -m eval.evaluate scene_grouping --bench runs/r3/bench --out runs/r3/grouping
    python3 -m eval.evaluate real_objects --score-only --out runs/r3/grouping --model grouped --compare raw

The greedy predictions of a ``eval.evaluators.real_objects`` folder were decoded without the step; this
applies it to each line exactly as the sampler does after decoding (``regroup_text`` with the
record's legend boxes), and lays out OUT as a ``eval.evaluators.real_objects`` folder (OUT/model: grouped,
OUT/compare: raw, the sets and baselines linked), so ``--score-only`` prints raw and grouped side
by side on every set. Lines whose key is in no set are dropped; changed keys go to OUT/changed.txt.

    python3 -m eval.evaluate scene_grouping --predictions RAW.jsonl --data SHARDS --out GROUPED.jsonl

applies it to one predictions file of `jax3dc eval run --no-scene-grouping` over SHARDS (every split),
for `jax3dc eval run --predictions GROUPED.jsonl` to score beside the raw run; with `--why` it also
counts the scenes whose object partition is still wrong after grouping by what the step saw: one
tree or several as the model wrote them, objects merged or split, whether the legend shows two
bodies on the floor or one body, and whether the model wrote a support relation.

    python3 -m eval.evaluate scene_grouping --built-scenes 200 [--seed 0]

measures the step without a model: the first N scenes of a `data build --scenes N --seed S` (no
rendering), their objects wired together as a model does it (each object root but the first two
hung rigidly from a random part of another object), regrouped from legend-rounded boxes; it prints
the share of scenes whose object partition comes back whole, per split and granularity (the
thresholds were set on the train split of seed 0; another seed is a check on scenes they never saw).
"""

from __future__ import annotations

import argparse
import json
import shutil
from collections import Counter
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Iterable

from data_pipeline.samples import derived_rng, split_of
from data_pipeline.scenes import make_scene
from data_pipeline.shards import shard_paths
from eval.records import read_records
from jax3dc.geometry.parts import part_boxes
from jax3dc.prompt import legend_boxes
from jax3dc.errors import StructureError
from jax3dc.structure import Box, Structure, parse_structure
from jax3dc.structure.scene_grouping import bodies, regroup, regroup_text, stands_apart


def legend_of_sets(sets: Path) -> dict[str, dict]:
    """Record key -> its legend boxes, over every set of a bench folder."""
    return {r.key: legend_boxes(r.prompt) for folder in sorted(sets.iterdir())
            if (folder / "manifest.json").exists() for r in read_records(shard_paths([str(folder)], None))}


def partition(s: Structure) -> list[list[int]]:
    """The parts of each tree, as sorted lists."""
    return sorted(sorted(s.subtree(r)) for r in s.roots())


def built_scenes(count: int, seed: int = 0) -> Counter:
    """(split, granularity, outcome) counts over the first ``count`` built scenes of a build with
    ``seed`` (module docstring)."""
    out: Counter = Counter()
    for index in range(count):
        for scene in make_scene(seed, index):
            boxes = {p: Box(tuple(round(v, 3) for v in b.centroid), tuple(round(v, 3) for v in b.extent))
                     for p, b in part_boxes(scene.parts).items()}
            ref, rng = scene.structure, derived_rng("wired", index, scene.granularity)
            roots, nodes = ref.roots(), dict(ref.nodes)
            for r in roots[2:]:
                others = sorted(set(nodes) - replace(ref, nodes=nodes).subtree(r))
                nodes[r] = replace(nodes[r], parent=int(rng.choice(others)))
            wired = replace(ref, nodes=nodes)
            where = (split_of(scene.object_id), scene.granularity)
            out[(*where, "scenes")] += 1
            out[(*where, "wired")] += partition(wired) == partition(ref)
            out[(*where, "regrouped")] += partition(regroup(wired, boxes)) == partition(ref)
            out[(*where, "reference kept")] += partition(regroup(ref, boxes)) == partition(ref)
    return out


@dataclass(frozen=True)
class Miss:
    """What the grouping step saw in a scene whose object partition it left wrong (module docstring)."""

    several_trees: bool  # as the model wrote it
    merged: bool  # some grouped object holds parts of several reference objects
    split: bool  # some reference object is spread over several grouped objects
    legend: str  # "two bodies on the floor", "one body" or "bodies off the floor"
    support: bool  # the model wrote a support relation


def miss(raw: Structure, grouped: Structure, reference: Structure, boxes: dict[int, Box]) -> Miss | None:
    """Why ``grouped`` (``raw`` after the step) is not ``reference``'s object partition; None if it is."""
    got, want = partition(grouped), partition(reference)
    if got == want:
        return None
    legend = ("two bodies on the floor" if stands_apart(boxes) else
              "one body" if len(bodies(boxes)) == 1 else "bodies off the floor")
    return Miss(len(raw.roots()) > 1, any(sum(bool(set(g) & set(w)) for w in want) > 1 for g in got),
                any(sum(bool(set(g) & set(w)) for g in got) > 1 for w in want), legend,
                any(r.type == "support" for r in raw.relations))


def misses(predictions: Path, grouped: Path, records: dict[str, tuple[dict[int, Box], str]]) -> Counter:
    """Miss -> count over the scene lines of ``predictions`` and their regrouped ``grouped`` lines."""
    def texts(path: Path) -> dict[str, str]:
        with path.open(encoding="utf-8") as f:
            return {item["key"]: item["text"] for item in map(json.loads, f) if item.get("key") in records}

    def parsed(text: str, boxes: dict[int, Box]) -> Structure:
        return parse_structure(text[text.find("{"):text.rfind("}") + 1], part_ids=boxes)

    out: Counter = Counter()
    after = texts(grouped)
    for key, text in texts(predictions).items():
        boxes, target = records[key]
        reference = parse_structure(target)
        if len(reference.roots()) < 2:
            continue
        try:
            why = miss(parsed(text, boxes), parsed(after[key], boxes), reference, boxes)
        except StructureError:
            continue  # a parse failure is scored as one by eval run
        if why is not None:
            out[why] += 1
    return out


def regroup_file(predictions: Path, boxes: dict[str, dict], out: Path) -> list[str]:
    """Writes ``predictions`` to ``out`` with each line regrouped as the sampler does; returns the
    keys whose text changed. Lines whose key has no legend are dropped (they are in no set)."""
    changed = []
    out.parent.mkdir(parents=True, exist_ok=True)
    with predictions.open(encoding="utf-8") as f, out.open("w", encoding="utf-8") as grouped:
        for line in f:
            try:
                item = json.loads(line)
            except json.JSONDecodeError:  # the torn last line of a run still writing
                continue
            if item.get("key") not in boxes:
                continue
            text = regroup_text(item["text"], boxes[item["key"]])
            if text != item["text"]:
                changed.append(item["key"])
            grouped.write(json.dumps({**item, "text": text}, separators=(",", ":")) + "\n")
    return changed


def main(argv: Iterable[str] | None = None) -> list[str]:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--bench", help="a eval.evaluators.real_objects output folder (sets/, model/)")
    p.add_argument("--out", help="folder to write (a eval.evaluators.real_objects folder for --score-only)")
    p.add_argument("--built-scenes", type=int, default=0, metavar="N", help="measure on N built scenes instead")
    p.add_argument("--seed", type=int, default=0, help="build seed of --built-scenes (default 0)")
    p.add_argument("--predictions", help="one predictions JSONL to regroup (with --data and --out FILE)")
    p.add_argument("--data", nargs="+", default=[], help="the shards --predictions was made on (every split)")
    p.add_argument("--why", action="store_true", help="with --predictions: count the scenes still wrong after "
                   "grouping by what the step saw")
    a = p.parse_args(None if argv is None else list(argv))
    if a.predictions:
        if not (a.data and a.out):
            p.error("--predictions needs --data and --out")
        records = {r.key: (legend_boxes(r.prompt), r.target) for r in read_records(shard_paths(a.data, None))}
        changed = regroup_file(Path(a.predictions), {k: b for k, (b, _) in records.items()}, Path(a.out))
        print(f"{len(changed)} predictions regrouped; wrote {a.out}")
        if a.why:
            for why, n in sorted(misses(Path(a.predictions), Path(a.out), records).items(), key=lambda x: -x[1]):
                print(f"{n:4d} still wrong: {'several trees' if why.several_trees else 'one tree'}, "
                      f"{' and '.join(w for w, on in (('merged', why.merged), ('split', why.split)) if on)}, "
                      f"legend: {why.legend}{', a support relation' if why.support else ''}")
        return changed
    if a.built_scenes:
        counts = built_scenes(a.built_scenes, a.seed)
        for split, granularity in sorted({k[:2] for k in counts}):
            n = counts[(split, granularity, "scenes")]
            print(f"{split:5s} {granularity:6s} {n:4d} scenes, whole object partition: "
                  + ", ".join(f"{what} {100.0 * counts[(split, granularity, what)] / n:.1f}%"
                              for what in ("wired", "regrouped", "reference kept")))
        return []
    if not (a.bench and a.out):
        p.error("--bench and --out are needed (or --built-scenes N)")
    bench, out = Path(a.bench), Path(a.out)
    boxes = legend_of_sets(bench / "sets")
    for label in ("model", "compare"):
        (out / label).mkdir(parents=True, exist_ok=True)
        shutil.copy(bench / "model" / "references.jsonl", out / label / "references.jsonl")
    for name in ("sets", "baselines"):
        if (bench / name).exists() and not (out / name).exists():
            (out / name).symlink_to((bench / name).resolve())
    with (bench / "model" / "predictions.jsonl").open(encoding="utf-8") as f, \
            (out / "compare" / "predictions.jsonl").open("w", encoding="utf-8") as raw:
        for line in f:
            try:
                item = json.loads(line)
            except json.JSONDecodeError:
                continue
            if item.get("key") in boxes:
                raw.write(json.dumps(item, separators=(",", ":")) + "\n")
    changed = regroup_file(bench / "model" / "predictions.jsonl", boxes, out / "model" / "predictions.jsonl")
    (out / "changed.txt").write_text("".join(k + "\n" for k in changed))
    print(f"{len(changed)} predictions regrouped; wrote {out}")
    return changed


if __name__ == "__main__":
    main()
