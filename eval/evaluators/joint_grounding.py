"""Joint grounding measured on predictions already made: each step on and off, every benchmark set.

    python3 -m eval.evaluate joint_grounding --bench runs/bench --out runs/grounding

``--bench`` is a folder that ``eval.evaluators.real_objects`` wrote (its ``sets/<source>_<kind>/`` shards and
``model/predictions.jsonl`` + ``model/references.jsonl``). Each variant rewrites every raw prediction
through ``jax3dc.grounding.ground_text`` — the function the sampler applies when decoding with
grounding on — against the legend boxes of the record's own prompt, and the result is scored per set
as ``eval.evaluators.real_objects`` scores it (records without a prediction yet are left out and counted).
Writes OUT/summary.json, OUT/summary.md and, per variant, OUT/<variant>.jsonl (predictions in the
format ``jax3dc eval run --predictions`` reads; the file name is the variant's, e.g.
``default_ground_joints.jsonl``).
"""

from __future__ import annotations

import argparse
import json
import re
from dataclasses import replace
from pathlib import Path
from typing import Iterable

from eval.evaluators.real_objects import score, set_keys
from eval.metrics.cases import load_predictions, load_references
from jax3dc.grounding import Grounding, JointPrior, ground_text, shipped_prior
from jax3dc.prompt import legend_boxes

COLUMNS = ("parse", "type_acc", "axis_acc", "pos_err", "success", "hinge_edge_acc", "fail_type", "fail_axis",
           "fail_origin", "fail_limit")


def variants(prior: JointPrior) -> dict[str, Grounding | None]:
    """The raw predictions; ``Grounding()`` (what ``--ground-joints`` runs); it with the hinge-line snap
    added, with the axis direction free, and with both (every step); each step alone; then the two
    decision constants of the prior varied."""
    default = Grounding(prior=prior)
    out: dict[str, Grounding | None] = {"raw": None, "default (--ground-joints)": default}
    out["+ line_snap"] = replace(default, line_snap=True)
    out["+ axis direction free"] = replace(default, axis_dim_kept=False)
    out["every step"] = replace(default, line_snap=True, axis_dim_kept=False)
    out["axis_snap only"] = replace(default, type_axis=False)
    out["type only"] = replace(default, axis_snap=False)
    out["axis_snap + line_snap"] = replace(default, type_axis=False, line_snap=True)
    for ratio in (1.0, 2.0, 16.0):
        out[f"keep_ratio {ratio:g}"] = replace(default, prior=replace(prior, keep_ratio=ratio))
    for sigma in (0.025, 0.1, 1e3):
        out[f"+ line_snap, line_sigma {sigma:g}"] = replace(default, line_snap=True,
                                                             prior=replace(prior, line_sigma=sigma))
    return out


def slug(variant: str) -> str:
    """A variant's name as a file name: ``default (--ground-joints)`` -> ``default_ground_joints``."""
    return re.sub(r"[^a-z0-9.]+", "_", variant.lower()).strip("_")


def main(argv: Iterable[str] | None = None) -> dict:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--bench", required=True, help="a eval.evaluators.real_objects output folder")
    p.add_argument("--out", required=True)
    p.add_argument("--prior", default="", help="a joint prior JSON (default: the shipped one)")
    p.add_argument("--sets", nargs="*", default=None, help="set names to score (default: every set)")
    a = p.parse_args(list(argv) if argv is not None else None)
    bench, out = Path(a.bench), Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    raw = load_predictions(bench / "model" / "predictions.jsonl")
    refs = load_references(bench / "model" / "references.jsonl")
    sets = {s.name: s for s in sorted((bench / "sets").iterdir()) if (s / "manifest.json").exists()}
    records = {name: [r for r in rs if r.key in raw] for name, rs in set_keys(sets).items()
               if a.sets is None or name in a.sets}
    prompts = {r.key: r.prompt for rs in records.values() for r in rs}
    results: dict[str, dict] = {}
    lines = ["| set | records | variant | " + " | ".join(COLUMNS) + " |", "|---" * (len(COLUMNS) + 3) + "|"]
    prior = JointPrior.load(a.prior) if a.prior else shipped_prior()
    for variant, grounding in variants(prior).items():
        preds = {k: raw[k] if grounding is None else ground_text(raw[k], legend_boxes(prompts[k]), grounding)
                 for k in prompts}
        with (out / f"{slug(variant)}.jsonl").open("w", encoding="utf-8") as f:
            for key, text in preds.items():
                f.write(json.dumps({"key": key, "text": text}, separators=(",", ":")) + "\n")
        for name, rs in records.items():
            if not rs:
                continue
            result = score(refs, preds, rs)
            results.setdefault(name, {})[variant] = result
            m = {**result["metrics"], "hinge_edge_acc": result.get("hinge_edge_acc")}
            cells = ["-" if m.get(c) is None else f"{m[c]:.3f}" if c == "pos_err" else f"{m[c]:.1f}" for c in COLUMNS]
            lines.append(f"| {name} | {len(rs)} | {variant} | " + " | ".join(cells) + " |")
    (out / "summary.json").write_text(json.dumps(results, indent=1) + "\n")
    text = "\n".join(sorted(lines[2:], key=lambda line: line.split("|")[1]))
    (out / "summary.md").write_text("\n".join(lines[:2]) + "\n" + text + "\n")
    print("\n".join(lines[:2]) + "\n" + text)
    return results


if __name__ == "__main__":
    main()
