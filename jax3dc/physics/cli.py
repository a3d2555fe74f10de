"""``jax3dc physics``: would a predicted articulated object work in a simulator, and why not.

``physics check STRUCTURE.json --parts DIR`` checks one object and prints its JSON verdict
(``physics check object.xml``: the MJCF file ``jax3dc export --format mjcf`` wrote, as it stands).
``physics sweep`` (a data build's report) is evaluation's: ``eval/physics_sweep.py`` adds it to this group.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import json
import math
import multiprocessing as mp
import os
import threading
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from jax3dc.cli_args import command_group, positive_int
from jax3dc.compilation import DEFAULT_DIR as DEFAULT_CACHE_DIR
from jax3dc.errors import InputFileError, Jax3dcError
from jax3dc.geometry.mesh_size import MAX_PART_FACES, PHYSICS_MAX_FACES, check_object_faces
from jax3dc.geometry.parts import load_parts
from jax3dc.physics.exported import is_mjcf, load_exported
from jax3dc.physics.verdict import check_object
from jax3dc.structure import parse_structure

VERDICT_HELP = (
    'The verdict is JSON: {"ok": bool, "joints": {"<part id>": {"ok": bool, "reasons": [...], "warnings": [...]}}, '
    '"checks": {"rest": [...], "combinations": [...], "gravity": [...]}, "findings": [...]}. Reasons (failures) '
    'and warnings are short strings such as "penetrates part 3 at q=1.200", "detached from parent at q=0.400", '
    '"pivot detached", "limit unreachable: hi (stops at q=0.9)", "disagrees with part 5 (symmetric): ..." (its '
    'mirror twin moves otherwise), "unstable under gravity: ..."; a limit a little past where the joint stops is '
    'the warning "limit past contact: hi (stops at q=2.772)". "findings" holds the same as data: check, severity, '
    'joints, parts, depth (nu), state ([[joint, value], ...]), reachable. Only failures fail a joint or the object. '
    "Joint values are radians (hinge) or normalised units (slide). Tolerances: jax3dc/physics/tolerances.py."
)


def register(subparsers: argparse._SubParsersAction) -> None:
    sub = command_group(subparsers, "physics", help="physics plausibility checks of an articulated structure",
                        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    check = sub.add_parser(
        "check", help="check one structure with its part meshes, or an exported MJCF file",
        description="Build a simulation model of STRUCTURE.json with the part meshes in --parts (or take the one of "
                    "an MJCF file written by jax3dc export --format mjcf or predict, object.xml, with its meshes/), "
                    "run the interpenetration, attachment, reachability and gravity checks, print the verdict and "
                    "write it to --out. An exported file gives the verdict its structure gives, unless it was edited: "
                    "its bodies, joints and collision pieces are what is checked. Exit code 0 whatever the verdict; "
                    "1 on unusable input. " + VERDICT_HELP)
    check.add_argument("structure", type=Path, help="structure O as JSON (SPEC §2), or an exported MJCF file (.xml)")
    check.add_argument("--parts", type=Path, help="folder of part meshes <id>.obj|.stl|.ply|.glb (nu); required "
                                                  "with a structure, not with an MJCF file (it has meshes/)")
    check.add_argument("--max-part-faces", type=positive_int, default=MAX_PART_FACES, metavar="N",
                       help="refuse a part mesh file of more triangles (default: %(default)s)")
    check.add_argument("--max-faces", type=positive_int, default=PHYSICS_MAX_FACES, metavar="N",
                       help="refuse an object of more triangles in all: the check's time and memory grow with "
                            "them (default: %(default)s)")
    check.add_argument("--scale", type=float, default=None,
                       help="metres per nu (default: 'scale' of a meta.json beside the structure, else 1; an MJCF "
                            "file carries its own)")
    check.add_argument("--out", type=Path, default=None, help="also write the verdict JSON here")
    check.add_argument("--backend", choices=("c", "mjx"), default="c",
                       help="kinematic checks through C MuJoCo (default; fast on CPU) or MJX (for a GPU)")
    check.add_argument("--mounted", action="store_true",
                       help="the object is fixed in place in use (a faucet, a toilet, a door frame): the gravity "
                            "test holds its root instead of standing it free on a floor (an MJCF file exported "
                            "as mounted is checked so without it)")
    check.set_defaults(func=run_check)


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
    if is_mjcf(args.structure):
        if args.parts is not None or args.scale is not None:
            raise Jax3dcError("--parts and --scale go with a structure: an MJCF file has its meshes and scale")
        exported = load_exported(args.structure, args.max_part_faces)
        check_object_faces(exported.parts, args.max_faces, "the physics check")
        verdict = check_object(exported.structure, exported.parts, exported.scale, backend=args.backend,
                               mounted=args.mounted or exported.mounted, pieces=exported.pieces)
    else:
        if args.parts is None:
            raise Jax3dcError("--parts DIR is required with a structure (the part meshes it articulates)")
        try:
            text = args.structure.read_text(encoding="utf-8")
        except OSError as e:
            raise InputFileError(args.structure, f"cannot read: {e.strerror or e}") from None
        parts = load_parts(args.parts, args.max_part_faces)
        check_object_faces(parts, args.max_faces, "the physics check")
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
