"""The release benchmark on objects never trained on: real held-out objects beside procedural ones.

    python3 -m eval.evaluate real_objects --model runs/r3/release --compare jax3dc/release \\
        --heldout .carry/real_heldout --fixtures .carry/fixtures --procedural runs/r3/data --out runs/r3/bench

1. sets      the test records of each source, by kind — plain, split variant, merge variant, scene
             (procedural builds only) — capped per set, written as shards under OUT/sets/<source>_<kind>/
2. generate  one `jax3dc eval run` per model over all sets (OUT/<label>/predictions.jsonl); a rerun skips
             what is there, so a killed call resumes
3. baselines `jax3dc eval baselines` on the same references (star, heuristic)
4. score     per set and system: Table 1 (Table 2 for scenes) with failure attribution; on plain sets
             also success per category, per joint type and per look (a mixed build's records carry
             theirs), reference joints right over every category and over the door-like ones
             (DOOR_LIKE), and hinge-edge accuracy: the share of
             reference hinges (axis along a box axis) whose predicted line is the same one of the nine
             lines of the child's box — its four edges, four face centre lines and its centre line —
             nearest to the reference line (an unmatched hinge counts as wrong). OUT/summary.json,
             OUT/summary.md, and printed.

`--score-only` skips 1–3 and scores what OUT holds (predictions brought back from a GPU host).
"""

from __future__ import annotations

import argparse
import json
import os
from collections import defaultdict
from dataclasses import replace
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

import numpy as np

from data_pipeline.record import Record
from data_pipeline.shards import shard_paths, write_dataset
from eval.metrics.cases import Case, Reference, build_cases, load_predictions, load_references
from eval.metrics.joints import AXIS_TOLERANCE
from eval.metrics.score import evaluate
from eval.records import read_records
from jax3dc.cli import main as jax3dc
from jax3dc.structure import Box

KINDS = ("plain", "split", "merge", "scene")
BASELINES = ("heuristic", "star")
GRID = (-0.5, 0.0, 0.5)  # box-side fractions of the nine candidate hinge lines
PAPER = {"parse": 99.0, "parent_acc": 85.6, "edge_f1": 85.4, "presence_f1": 90.8, "type_acc": 96.3,
         "axis_acc": 89.5, "pos_err": 0.052, "range_iou": 71.3, "success": 82.4, "sym_f1": 54.2,
         "inst_f1": 19.4, "plane_acc": 98.4, "count_match": 99.5, "full_partition": 97.9, "cluster_acc": 99.1,
         "pair_f1": 99.2}


def kind_of(record: Record) -> str:
    meta = record.meta
    if meta.get("category") == "scene":
        return "scene"
    aug = str(meta.get("augmentation") or "")
    return "split" if aug.startswith("split") else "merge" if aug.startswith("merge") else "plain"


def write_sets(sources: Mapping[str, Path], out: Path, caps: Mapping[str, int]) -> dict[str, Path]:
    """OUT/sets/<source>_<kind>: the first ``caps[kind]`` test records of each source and kind. A
    record whose key an earlier source already holds (the same object in another look) gets the
    source's name after its key, so one `eval run` can score every set."""
    sets: dict[str, Path] = {}
    seen: set[str] = set()
    for source, folder in sources.items():
        by_kind: dict[str, list[Record]] = defaultdict(list)
        for record in read_records(shard_paths([str(folder)], "test"), split="test"):
            if record.key in seen:
                record = replace(record, key=f"{record.key}/{source}")
            seen.add(record.key)
            kind = kind_of(record)
            if len(by_kind[kind]) < caps[kind]:
                by_kind[kind].append(record)
        for kind, records in by_kind.items():
            target = out / "sets" / f"{source}_{kind}"
            if not (target / "manifest.json").exists():
                write_dataset(target, records, name="test-00000.array_record")
            sets[f"{source}_{kind}"] = target
    return sets


def set_keys(sets: Mapping[str, Path]) -> dict[str, list[Record]]:
    return {name: list(read_records(shard_paths([str(folder)], "test"))) for name, folder in sets.items()}


def _call(argv: list[str]) -> None:
    print(f"[bench] jax3dc {' '.join(argv)}", flush=True)
    if jax3dc(argv) != 0:
        raise SystemExit(f"`jax3dc {' '.join(argv)}` failed")


def generate(model: str, sets: Mapping[str, Path], out: Path, batch: int, max_new: int) -> None:
    _call(["eval", "run", "--checkpoint", model, "--data", *map(str, sets.values()), "--split", "test",
           "--batch-size", str(batch), "--bucket", "256", "--max-new-tokens", str(max_new), "--out", str(out),
           "--overlays", "0", "--viewers", "0"])


def hinge_lines(box: Box, pivot: Sequence[float], axis: Sequence[float]) -> tuple[int, int] | None:
    """Which of the nine lines of ``box`` along ``axis`` is nearest the line through ``pivot``; None
    when the axis is not along a box axis (no such lines)."""
    a = np.abs(np.asarray(axis, float))
    a = a / (np.linalg.norm(a) or 1.0)
    k = int(np.argmax(a))
    if np.arccos(min(1.0, a[k])) > AXIS_TOLERANCE:
        return None
    i, j = (d for d in range(3) if d != k)
    side = np.maximum(np.asarray(box.extent, float), 1e-9)
    f = (np.asarray(pivot, float) - np.asarray(box.centroid, float)) / side
    return int(np.argmin([abs(f[i] - g) for g in GRID])), int(np.argmin([abs(f[j] - g) for g in GRID]))


def hinge_edges(cases: Sequence[Case], refs: Mapping[str, Reference], rows: Sequence[Mapping[str, Any]]) -> dict:
    """Hinge-edge accuracy over the reference hinges of ``cases`` (module docstring)."""
    right = total = 0
    for case, row in zip(cases, rows):
        boxes = refs[case.key].boxes
        matches = {m["ref_child"]: m for m in row.get("matches", [])}
        for child, joint in case.reference.joints().items():
            if joint.type != "hinge":
                continue
            ref_line = hinge_lines(boxes[child], joint.pivot, joint.axis)
            if ref_line is None:
                continue
            total += 1
            m = matches.get(child)
            if case.prediction is None or m is None or m["angle"] > AXIS_TOLERANCE:
                continue
            pred = case.prediction.nodes[m["pred_child"]].joint
            right += pred is not None and hinge_lines(boxes[child], pred.pivot, joint.axis) == ref_line
    return {"hinge_edge_acc": 100.0 * right / total if total else None, "hinges": total}


DOOR_LIKE = ("Dishwasher", "Microwave", "Oven", "Refrigerator", "Safe", "WashingMachine", "Toilet", "TrashCan")
"""PartNet-Mobility categories whose joints are mostly doors and lids: where the hinge edge is read."""


def breakdown(cases: Sequence[Case], rows: Sequence[Mapping[str, Any]], group: Mapping[str, str]) -> dict[str, dict]:
    """Per group (a category, a look) of the cases' keys: records, matched joints, their successes,
    and the reference's joints, so that both the share of matched joints that pass (the paper's
    success) and the share of reference joints right can be read."""
    out: dict[str, dict] = defaultdict(lambda: {"records": 0, "joints": 0, "success": 0, "ref_joints": 0})
    for case, row in zip(cases, rows):
        g = out[group[case.key]]
        g["records"] += 1
        g["ref_joints"] += len(case.reference.joints())
        for m in row.get("matches", []):
            g["joints"] += 1
            g["success"] += m["gate"] == "success"
    return {k: {**v, "success_pct": 100.0 * v["success"] / v["joints"] if v["joints"] else None,
                "ref_right_pct": 100.0 * v["success"] / v["ref_joints"] if v["ref_joints"] else None}
            for k, v in sorted(out.items())}


def by_joint_type(cases: Sequence[Case], rows: Sequence[Mapping[str, Any]]) -> dict[str, dict]:
    out: dict[str, list[int]] = defaultdict(lambda: [0, 0])
    for case, row in zip(cases, rows):
        for m in row.get("matches", []):
            t = case.reference.nodes[m["ref_child"]].joint.type
            out[t][0] += 1
            out[t][1] += m["gate"] == "success"
    return {t: {"joints": n, "success_pct": 100.0 * s / n if n else None} for t, (n, s) in sorted(out.items())}


def score(refs: Sequence[Reference], preds: Mapping[str, Any], records: Sequence[Record]) -> dict:
    keys = {r.key for r in records}
    subset = [r for r in refs if r.key in keys]
    cases = build_cases(subset, preds)
    evaluation = evaluate(cases)
    out: dict[str, Any] = {"metrics": evaluation.metrics}
    if records and kind_of(records[0]) != "scene":
        category = {r.key: str(r.meta.get("category")) for r in records}
        out["per_category"] = breakdown(cases, evaluation.rows, category)
        kinds = {k: "door-like" if c in DOOR_LIKE else "other" for k, c in category.items()}
        out["door_like"] = breakdown(cases, evaluation.rows, kinds).get("door-like")
        out["all_joints"] = breakdown(cases, evaluation.rows, {k: "all" for k in category})["all"]
        out["per_look"] = breakdown(cases, evaluation.rows, {r.key: str(r.meta.get("appearance") or "plain")
                                                             for r in records})
        out["per_joint_type"] = by_joint_type(cases, evaluation.rows)
        out.update(hinge_edges(cases, {r.key: r for r in subset}, evaluation.rows))
    return out


def _cell(v: Any, key: str) -> str:
    return "-" if v is None else f"{v:.3f}" if key == "pos_err" else f"{v:.1f}"


def _right(group: Mapping[str, Any] | None) -> str:
    """"k of n" reference joints right, or "-" for no group."""
    return "-" if not group else f"{group['success']} of {group['ref_joints']}"


def table(title: str, columns: Sequence[str], rows: Mapping[str, Mapping[str, Any]]) -> str:
    lines = [f"### {title}", "", "| system | " + " | ".join(columns) + " |", "|---" * (len(columns) + 1) + "|"]
    lines += [f"| {name} | " + " | ".join(_cell(r.get(c), c) for c in columns) + " |" for name, r in rows.items()]
    return "\n".join(lines) + "\n"


T1 = ("parse", "parent_acc", "edge_f1", "presence_f1", "type_acc", "axis_acc", "pos_err", "range_iou", "success",
      "hinge_edge_acc", "fail_type", "fail_axis", "fail_origin", "fail_limit", "sym_f1", "inst_f1")
T2 = ("parse", "objects_per_scene", "objects_per_scene_ref", "count_match", "full_partition", "cluster_acc",
      "pair_f1")


def report(results: Mapping[str, Mapping[str, dict]]) -> str:
    """Markdown: one table per set (systems as rows, the paper's row where it applies), then the
    per-category and per-joint-type success of every system on the plain sets."""
    parts = []
    for name, systems in results.items():
        scene = name.endswith("_scene")
        rows = {s: {**r["metrics"], **{k: r.get(k) for k in ("hinge_edge_acc",)}} for s, r in systems.items()}
        rows["paper (PhysX-Mobility, real)"] = PAPER
        n = next(iter(systems.values()))["metrics"]["counts"]["objects"]
        parts.append(table(f"{name} ({n} records)", T2 if scene else T1, rows))
    for name, systems in results.items():
        if not name.endswith("_plain"):
            continue
        cats = sorted({c for r in systems.values() for c in r.get("per_category", {})})
        lines = [f"### {name}: success per category (matched joints)", "",
                 "| category | joints | " + " | ".join(systems) + " |", "|---" * (len(systems) + 2) + "|"]
        for c in cats:
            first = next(iter(systems.values()))["per_category"].get(c, {})
            cells = [_cell(r.get("per_category", {}).get(c, {}).get("success_pct"), "") for r in systems.values()]
            lines.append(f"| {c} | {first.get('joints', 0)} | " + " | ".join(cells) + " |")
        for t in ("hinge", "slide"):
            cells = [_cell(r.get("per_joint_type", {}).get(t, {}).get("success_pct"), "") for r in systems.values()]
            lines.append(f"| all {t}s | - | " + " | ".join(cells) + " |")
        for label, field in (("door-like categories", "door_like"), ("every category", "all_joints")):
            first = next(iter(systems.values())).get(field) or {}
            cells = [_right(r.get(field)) for r in systems.values()]
            lines.append(f"| {label}: reference joints right | {first.get('ref_joints', 0)} | " + " | ".join(cells) + " |")
        looks = sorted({look for r in systems.values() for look in r.get("per_look", {})})
        if len(looks) > 1:
            for look in looks:
                cells = [_cell((r.get("per_look", {}).get(look) or {}).get("success_pct"), "") for r in systems.values()]
                lines.append(f"| {look} look: success | - | " + " | ".join(cells) + " |")
        parts.append("\n".join(lines) + "\n")
    return "\n".join(parts)


def run(a: argparse.Namespace) -> dict:
    os.environ.setdefault("MUJOCO_GL", "egl")  # the overlays of `eval run` render headless
    out = Path(a.out)
    sources = {name: Path(p) for name, p in (("heldout", a.heldout), ("heldout_varied", a.heldout_varied),
                                              ("fixtures", a.fixtures), ("fixtures_varied", a.fixtures_varied),
                                              ("procedural", a.procedural)) if p}
    caps = {"plain": a.plain, "split": a.variants, "merge": a.variants, "scene": a.scenes}
    models = {"model": a.model, **({"compare": a.compare} if a.compare else {})}
    if a.score_only:
        sets = {p.name: p for p in sorted((out / "sets").iterdir()) if (p / "manifest.json").exists()}
    else:
        sets = write_sets(sources, out, caps)
        for label, model in models.items():
            generate(model, sets, out / label, a.batch, a.max_new_tokens)
        if not (out / "baselines" / "heuristic" / "predictions.jsonl").exists():
            _call(["eval", "baselines", "--ref", str(out / "model" / "references.jsonl"), "--out", str(out / "baselines")])
    refs = load_references(out / "model" / "references.jsonl")
    systems = {label: load_predictions(out / label / "predictions.jsonl") for label in models}
    systems.update({b: load_predictions(out / "baselines" / b / "predictions.jsonl") for b in BASELINES})
    names = dict(zip(systems, [Path(a.model).name, *([Path(a.compare).name] if a.compare else []), *BASELINES]))
    results: dict[str, dict[str, dict]] = {}
    for name, records in set_keys(sets).items():
        results[name] = {f"{label} ({names[label]})" if label in models else label: score(refs, preds, records)
                         for label, preds in systems.items()}
    (out / "summary.json").write_text(json.dumps(results, indent=1) + "\n")
    text = report(results)
    (out / "summary.md").write_text(text)
    print(text)
    return results


def main(argv: Iterable[str] | None = None) -> dict:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--model", default="jax3dc/release", help="model folder to benchmark")
    p.add_argument("--compare", default="", help="another model folder scored on the same records (the shipped one)")
    p.add_argument("--heldout", default="", help="shards of the held-out fifth of the real pool (scripts/real_split.py)")
    p.add_argument("--fixtures", default="", help="shards of the 9 real test fixtures")
    p.add_argument("--heldout-varied", default="", help="the held-out fifth imported in the varied look "
                   "(`data import --appearance varied`): the same objects, to measure what the look changes")
    p.add_argument("--fixtures-varied", default="", help="the fixtures imported in the varied look")
    p.add_argument("--procedural", default="", help="a `jax3dc data build` folder; its test split is scored")
    p.add_argument("--out", required=True)
    p.add_argument("--plain", type=int, default=300, help="records per plain set at most")
    p.add_argument("--variants", type=int, default=120, help="records per split / merge set at most")
    p.add_argument("--scenes", type=int, default=60, help="scene records at most")
    p.add_argument("--batch", type=int, default=100)
    p.add_argument("--max-new-tokens", type=int, default=1536)
    p.add_argument("--score-only", action="store_true", help="score the predictions already in OUT")
    return run(p.parse_args(list(argv) if argv is not None else None))


if __name__ == "__main__":
    main()
