"""``jax3dc data convert``: one URDF / MJCF object into structure + part meshes + boxes + meta."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from data_pipeline.importers.frames import FRONTS
from data_pipeline.importers.limits import DEFAULT_MAX_BODIES, DEFAULT_MAX_FACES, ImportLimits
from data_pipeline.importers.output import write_imported
from data_pipeline.importers.source import import_object
from jax3dc.cli_args import positive_int

DESCRIPTION = """\
Convert one articulated object into the project's format.

PATH is a URDF or MJCF file, or an object directory: a PartNet-Mobility / PhysX-Mobility
folder (mobility.urdf, semantics.txt, textured_objs/) or a folder with exactly one URDF or
MJCF file. DIR receives:
  structure.json   the structure O (canonical JSON, normalised frame)
  parts/<id>.obj   one mesh per part, normalised: bounding box centred, largest extent 1
  boxes.json       per-part centroid and extent
  meta.json        scale (metres per normalised unit), source, part names, warnings

Links with geometry become parts; revolute/continuous joints become hinges, prismatic joints
slides, fixed joints rigid attachments. URDF lengths are taken as metres (PartNet-Mobility's
are not really metres: pass --metres-per-unit if you know better). Example:
  jax3dc data convert ../shared/fixtures/partnet_mobility/door_8877 --out out/door_8877
"""


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "convert",
        help="convert one URDF / MJCF object into structure.json, parts/, boxes.json, meta.json",
        description=DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("path", metavar="PATH", type=Path, help="URDF / MJCF file or object directory")
    parser.add_argument("--out", metavar="DIR", type=Path, required=True, help="output directory")
    parser.add_argument(
        "--front", choices=FRONTS, default=None,
        help="direction the source object faces; it is turned to face -Y "
        "(default: -x for PartNet-Mobility's mobility.urdf, else -y)",
    )
    parser.add_argument(
        "--metres-per-unit", type=float, default=None, metavar="M",
        help="metres per source length unit (default 1: URDF and MJCF lengths are metres)",
    )
    parser.add_argument("--category", default=None, help="category written to meta.json (default: from the source)")
    parser.add_argument("--object-id", default=None, help="object id written to meta.json (default: folder name)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar and no summary")
    parser.add_argument("--max-faces", type=positive_int, default=DEFAULT_MAX_FACES, metavar="N",
                        help=f"refuse an object whose meshes (and height fields) hold more than N triangles "
                             f"(default: {DEFAULT_MAX_FACES})")
    parser.add_argument("--max-bodies", type=positive_int, default=DEFAULT_MAX_BODIES, metavar="N",
                        help=f"refuse a URDF with more than N links, or an MJCF with more than N bodies and geoms "
                             f"once <replicate> is expanded (default: {DEFAULT_MAX_BODIES})")
    parser.add_argument("--allow-outside", action="store_true",
                        help="read mesh files outside the object's folder (../, absolute paths, symbolic links "
                             "that point out); refused by default")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    limits = ImportLimits(args.max_faces, args.max_bodies, args.allow_outside)
    obj = import_object(args.path, args.metres_per_unit, args.front, progress=not args.quiet, limits=limits)
    if args.category is not None:
        obj.meta["category"] = args.category
    if args.object_id is not None:
        obj.meta["object_id"] = args.object_id
    write_imported(obj, args.out)
    if not args.quiet:
        for warning in obj.meta["warnings"]:
            print(f"warning: {warning}", file=sys.stderr)
        joints = obj.structure.joints()
        kinds = ", ".join(sorted(j.type for j in joints.values())) or "none"
        print(
            f"{obj.meta['source']}: {len(obj.parts)} parts, {len(joints)} joints ({kinds}), "
            f"scale {obj.meta['scale']:.4g} m/nu -> {args.out}"
        )
    return 0
