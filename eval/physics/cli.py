"""``jax3dc physics``: would a predicted articulated object work in a simulator, and why not.

``physics check STRUCTURE.json --parts DIR`` checks one object and prints its JSON verdict;
``physics sweep SHARDS`` checks every object of a data build and writes a report folder.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

from jax3dc.cli import command_group
from jax3dc.errors import InputFileError

VERDICT_HELP = (
    'The verdict is JSON: {"ok": bool, "joints": {"<part id>": {"ok": bool, "reasons": [...]}}, '
    '"checks": {"rest": [...], "combinations": [...], "gravity": [...]}}. Reasons are short strings such as '
    '"penetrates part 3 at q=1.200", "detached from parent at q=0.400", "pivot detached", '
    '"limit unreachable: hi (stops at q=0.9)", "disagrees with part 5 (symmetric): ..." (its mirror twin '
    'moves otherwise), "unstable under gravity: ..."; joint values are radians '
    "(hinge) or normalised units (slide). Tolerances: eval/physics/tolerances.py."
)


def register(subparsers: argparse._SubParsersAction) -> None:
    sub = command_group(subparsers, "physics", help="physics plausibility checks of an articulated structure",
                        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    check = sub.add_parser(
        "check", help="check one structure with its part meshes",
        description="Build a simulation model of STRUCTURE.json with the part meshes in --parts, run the "
                    "interpenetration, attachment, reachability and gravity checks, print the verdict and "
                    "write it to --out. Exit code 0 whatever the verdict; 1 on unusable input. " + VERDICT_HELP)
    check.add_argument("structure", type=Path, help="structure O as JSON (SPEC §2)")
    check.add_argument("--parts", type=Path, required=True, help="folder of part meshes <id>.obj|.stl|.ply|.glb (nu)")
    check.add_argument("--scale", type=float, default=None,
                       help="metres per nu (default: 'scale' of a meta.json beside the structure, else 1)")
    check.add_argument("--out", type=Path, default=None, help="also write the verdict JSON here")
    check.add_argument("--backend", choices=("c", "mjx"), default="c",
                       help="kinematic checks through C MuJoCo (default; fast on CPU) or MJX (for a GPU)")
    check.add_argument("--mounted", action="store_true",
                       help="the object is fixed in place in use (a faucet, a toilet, a door frame): the gravity "
                            "test holds its root instead of standing it free on a floor")
    check.set_defaults(func=run_check)
    sweep = sub.add_parser(
        "sweep", help="check every object of a data build and write a report",
        description="Check the first rest-pose record of every object in a data build (ArrayRecord shards: "
                    "target structure + part program) and write OUT/verdicts.jsonl, OUT/summary.json, "
                    "OUT/index.md and OUT/plots/<object>.png (deepest penetration against each joint's value). "
                    "Records without a part program (imports) are listed as skipped. Objects of a factory "
                    "category mounted in use (faucet, toilet, door, window) are checked as --mounted. " + VERDICT_HELP)
    sweep.add_argument("shards", type=Path, help="data build folder (manifest.json + *.array_record)")
    sweep.add_argument("--out", type=Path, default=Path("physics_report"), help="report folder (default: %(default)s)")
    sweep.add_argument("--limit", type=int, default=None, help="check at most this many objects")
    sweep.set_defaults(func=run_sweep)


def _scale_beside(structure_path: Path) -> float:
    meta = structure_path.with_name("meta.json")
    if not meta.exists():
        return 1.0
    try:
        scale = json.loads(meta.read_text(encoding="utf-8")).get("scale", 1.0)
    except (OSError, ValueError) as e:
        raise InputFileError(meta, f"cannot read the scale: {e}") from None
    return float(scale)


def _checked_scale(scale: float, where: Path) -> float:
    if isinstance(scale, bool) or not (math.isfinite(scale) and scale > 0):
        raise InputFileError(where, f"scale must be a positive number of metres per nu, got {scale!r}")
    return scale


def run_check(args: argparse.Namespace) -> int:
    from eval.physics.verdict import check_object
    from jax3dc.geometry.parts import load_parts
    from jax3dc.structure import parse_structure

    try:
        text = args.structure.read_text(encoding="utf-8")
    except OSError as e:
        raise InputFileError(args.structure, f"cannot read: {e.strerror or e}") from None
    parts = load_parts(args.parts)
    structure = parse_structure(text, part_ids=parts.keys())
    scale = _checked_scale(args.scale if args.scale is not None else _scale_beside(args.structure), args.structure)
    verdict = check_object(structure, parts, scale, backend=args.backend, mounted=args.mounted)
    text = json.dumps(verdict, indent=1)
    print(text)
    if args.out:
        try:
            args.out.parent.mkdir(parents=True, exist_ok=True)
            args.out.write_text(text + "\n", encoding="utf-8")
        except OSError as e:
            raise InputFileError(args.out, f"cannot write the verdict: {e.strerror or e}") from None
    return 0


def run_sweep(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from data_pipeline.factories import FACTORIES
    from eval.physics.report import write_report
    from eval.physics.verdict import check_object_with_curves
    from jax3dc.program import run_program
    from jax3dc.structure import parse_structure
    from data_pipeline.shards import read_dataset

    chosen: dict[str, Any] = {}
    for record in read_dataset(args.shards):
        object_id = record.meta.get("object_id", record.key)
        if object_id in chosen or record.meta.get("moved_joint") is not None or record.meta.get("augmentation"):
            continue
        chosen[object_id] = record
        if args.limit and len(chosen) >= args.limit:
            break
    results, skipped = [], []
    for object_id, record in tqdm(chosen.items(), desc="physics sweep", unit="object"):
        if not record.program:
            skipped.append({"object": object_id, "why": "no part program in the record"})
            continue
        parts = run_program(record.program).parts
        structure = parse_structure(record.target, part_ids=parts.keys())
        category = record.meta.get("category")
        mounted = category in FACTORIES and FACTORIES[category].mounted
        verdict, curves = check_object_with_curves(structure, parts, float(record.meta.get("scale", 1.0)),
                                                   mounted=mounted)
        results.append({"object": object_id, "category": category, "verdict": verdict,
                        "curves": curves})
    summary = write_report(results, skipped, args.out)
    print(json.dumps(summary, indent=1))
    return 0
