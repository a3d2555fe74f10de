"""`jax3dc export`: a structure JSON plus its part meshes -> URDF, MJCF, glTF, USD or a Blender script."""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

from jax3dc.cli_args import positive_int
from jax3dc.errors import InputFileError, Jax3dcError
from jax3dc.export.blender import export_blender
from jax3dc.export.files import check_file_stem
from jax3dc.export.gltf import export_gltf
from jax3dc.export.mjcf import export_mjcf
from jax3dc.export.urdf import export_urdf
from jax3dc.geometry.mesh_size import MAX_PART_FACES, PHYSICS_MAX_FACES, check_object_faces
from jax3dc.geometry.parts import load_parts
from jax3dc.mounted import is_mounted
from jax3dc.structure import parse_structure

FORMATS = ("urdf", "mjcf", "gltf", "usd", "blender")
PIECE_FORMATS = ("urdf", "mjcf", "usd")  # they collide through the parts' convex pieces, whose cost --max-faces caps


def _exporter(fmt: str):
    if fmt == "usd":
        from jax3dc.export.usd import export_usd  # lazy: pxr, 0.10 s, for the one format that writes USD
        return export_usd
    return {"urdf": export_urdf, "mjcf": export_mjcf, "gltf": export_gltf, "blender": export_blender}[fmt]


def _scale_from_meta(structure_path: Path) -> float | None:
    """The ``scale`` (metres per nu) of a ``meta.json`` beside the structure file, if there is one."""
    meta_path = structure_path.with_name("meta.json")
    if not meta_path.is_file():
        return None
    try:
        scale = json.loads(meta_path.read_text(encoding="utf-8")).get("scale")
    except (OSError, UnicodeDecodeError, ValueError, AttributeError) as e:
        raise InputFileError(meta_path, f"cannot read the scale: {e}") from None
    if isinstance(scale, bool) or not isinstance(scale, (int, float)) or not (math.isfinite(scale) and scale > 0):
        raise InputFileError(meta_path, f"'scale' must be a positive number of metres per nu, got {scale!r}")
    return float(scale)


def _category_from_meta(structure_path: Path) -> str | None:
    """The ``category`` of a ``meta.json`` beside the structure file (a data build writes it), if any."""
    meta_path = structure_path.with_name("meta.json")
    try:
        category = json.loads(meta_path.read_text(encoding="utf-8")).get("category") if meta_path.is_file() else None
    except (OSError, UnicodeDecodeError, ValueError, AttributeError) as e:
        raise InputFileError(meta_path, f"cannot read the category: {e}") from None
    return category if isinstance(category, str) else None


def _run(args: argparse.Namespace) -> int:
    structure_path = Path(args.structure)
    try:
        text = structure_path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise InputFileError(structure_path, f"cannot read the structure: {getattr(e, 'strerror', None) or e}") from None
    parts = load_parts(args.parts, args.max_part_faces)
    structure = parse_structure(text, part_ids=parts.keys())
    scale = args.scale
    source = "--scale"
    if scale is None:
        scale, source = _scale_from_meta(structure_path), "meta.json"
    if scale is None:
        scale, source = 1.0, "default: no --scale and no meta.json"
    if not (math.isfinite(scale) and scale > 0):
        raise InputFileError(structure_path, f"--scale must be a positive number of metres per nu, got {scale}")
    try:
        name = check_file_stem(args.name or structure_path.stem)
    except ValueError as e:
        raise InputFileError(structure_path, str(e)) from None
    if args.format != "mjcf" and (args.free or args.actuators or args.mounted is not None):
        raise Jax3dcError("--free, --mounted and --actuators are options of --format mjcf")
    base = ""
    if args.format in PIECE_FORMATS:
        check_object_faces(parts, args.max_faces, f"the {args.format.upper()} export (its convex collision pieces)")
    if args.format == "mjcf":
        category = _category_from_meta(structure_path)
        mounted = is_mounted(category) if args.mounted is None else args.mounted
        path = _exporter(args.format)(structure, parts, args.out, scale, model_name=name, free=args.free,
                                      mounted=mounted, actuators=args.actuators)
        base = f", {'free' if args.free and not mounted else 'fixed'} base"
        if mounted:
            base += " (mounted: " + ("--mounted" if args.mounted else f"category {category}") + ")"
    else:
        path = _exporter(args.format)(structure, parts, args.out, scale, model_name=name)
    joints = len(structure.joints())
    print(f"wrote {path} ({len(structure.nodes)} parts, {joints} joints, {scale:g} m per nu from {source}{base})")
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "export", help="export a structure and its part meshes to URDF, MJCF, glTF, USD or Blender",
        description="Turn a structure (SPEC §2 JSON) and one mesh per part into a simulation or content "
                    "asset, in metres. The parts folder holds <id>.obj (or .stl, .ply, .glb) per part in the "
                    "normalised frame, as written by `jax3dc program run --out` or the dataset tools. "
                    "Example: jax3dc export structure.json --parts parts/ --scale 0.9 --format mjcf --out sim/",
    )
    parser.add_argument("structure", metavar="FILE.json", help="the structure document")
    parser.add_argument("--parts", required=True, metavar="DIR", help="folder with one mesh per part, named <id>.obj")
    parser.add_argument("--max-part-faces", type=positive_int, default=MAX_PART_FACES, metavar="N",
                        help="refuse a part mesh file of more triangles (default: %(default)s)")
    parser.add_argument("--max-faces", type=positive_int, default=PHYSICS_MAX_FACES, metavar="N",
                        help="--format urdf, mjcf or usd: refuse an object of more triangles in all; its convex "
                             "collision pieces cost time and memory with them, as the physics check's do "
                             "(default: %(default)s)")
    parser.add_argument("--scale", type=float, metavar="METRES_PER_NU",
                        help="metres per normalised unit (default: 'scale' of meta.json beside FILE.json, else 1)")
    parser.add_argument("--format", required=True, choices=FORMATS,
                        help="urdf (+ meshes/), mjcf (MuJoCo XML + meshes/), gltf (one .glb), "
                             "usd (one .usda with UsdPhysics), blender (a Python script to run in Blender)")
    parser.add_argument("--out", required=True, metavar="DIR", help="output folder (created if missing)")
    parser.add_argument("--name", help="model and main file name (default: the stem of FILE.json)")
    parser.add_argument("--free", action="store_true",
                        help="mjcf: a free joint on the root, so the object stands on a floor, falls or can be pushed "
                             "(default: the root is fixed to the world); a mounted object keeps its fixed base")
    parser.add_argument("--mounted", action=argparse.BooleanOptionalAction, default=None,
                        help="mjcf: the object is fixed in place in use (a faucet, a toilet, a door or window frame), "
                             "so its base stays fixed even with --free (default: from the 'category' of meta.json "
                             "beside FILE.json: faucet, toilet, door and window are mounted)")
    parser.add_argument("--actuators", action="store_true",
                        help="mjcf: a position servo per joint (servo_<id>, control = target angle in radians or "
                             "position in metres)")
    parser.set_defaults(func=_run)
