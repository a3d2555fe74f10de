"""`jax3dc validate` and `jax3dc canonicalize`: check and normalise structure documents (SPEC §2)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from jax3dc.cli_args import positive_int
from jax3dc.errors import InputFileError, StructureError
from jax3dc.structure import MAX_DOCUMENT_BYTES, canonicalize, load_boxes, parse_structure, to_json, validate


def read_document(path: str | Path) -> bytes:
    """The bytes of a structure file; refuses files over MAX_DOCUMENT_BYTES without reading them whole."""
    path = Path(path)
    try:
        with path.open("rb") as f:
            data = f.read(MAX_DOCUMENT_BYTES + 1)
            size = path.stat().st_size
    except FileNotFoundError:
        raise InputFileError(path, "no such file") from None
    except IsADirectoryError:
        raise InputFileError(path, "is a directory, not a structure JSON file") from None
    except OSError as e:
        raise InputFileError(path, f"cannot read: {e.strerror or e}") from None
    if len(data) > MAX_DOCUMENT_BYTES:
        raise InputFileError(path, f"the document is {max(size, len(data))} bytes; the limit is "
                                   f"{MAX_DOCUMENT_BYTES} (far above any real structure) [document_size]")
    return data


def _part_id_list(text: str) -> list[int]:
    try:
        ids = [int(t) for t in text.split(",") if t.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated integers such as 1,2,3, got {text!r}") from None
    if not ids:
        raise argparse.ArgumentTypeError("expected at least one part id")
    return ids


MAX_PARTS = 100_000
"""Default cap on --parts / --part-ids: a 1 MiB document holds fewer nodes than this, so a larger
count can only be a mistake (or an attempt to make validate build a list of 20 million ids)."""


def run_validate(args: argparse.Namespace) -> int:
    count = args.parts if args.parts else len(args.part_ids or ())
    if count > args.max_parts:
        raise InputFileError(args.file, f"{count} part ids requested; the cap is {args.max_parts} "
                                        "(raise it with --max-parts) [max_parts]")
    doc = read_document(args.file)
    part_ids = list(range(1, args.parts + 1)) if args.parts else args.part_ids
    errors = validate(doc, part_ids=part_ids)
    if errors:
        for e in errors:
            print(f"{args.file}: {e}", file=sys.stderr)
        return 1
    s = parse_structure(doc, part_ids=part_ids)
    print(f"valid: {len(s.nodes)} parts, {len(s.joints())} joints, {len(s.relations)} relations")
    return 0


def run_canonicalize(args: argparse.Namespace) -> int:
    try:
        s = parse_structure(read_document(args.file))
    except StructureError as e:
        raise InputFileError(args.file, str(e)) from None
    boxes = load_boxes(args.boxes)
    text = to_json(canonicalize(s, boxes), names=args.names)
    if args.out:
        try:
            Path(args.out).write_text(text + "\n", encoding="utf-8")
        except OSError as e:
            raise InputFileError(args.out, f"cannot write: {e.strerror or e}") from None
    else:
        print(text)
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "validate",
        help="check a structure JSON document against every rule of SPEC §2",
        description="Check a structure document (materials / nodes / relations). Prints "
                    "'valid: N parts, J joints, R relations' and exits 0, or prints every problem "
                    "(location, message and [rule]) on stderr, one per line, and exits 1.",
        epilog="example: jax3dc validate out/cabinet/structure.json --parts 7",
    )
    p.add_argument("file", metavar="FILE.json", help="the structure document")
    ids = p.add_mutually_exclusive_group()
    ids.add_argument("--parts", type=positive_int, metavar="N",
                     help="the segmentation has parts 1..N: node ids must be exactly these")
    ids.add_argument("--part-ids", type=_part_id_list, metavar="1,2,3",
                     help="the part ids of the segmentation (comma-separated): node ids must be exactly these")
    p.add_argument("--max-parts", type=positive_int, default=MAX_PARTS, metavar="N",
                   help=f"refuse --parts / --part-ids above N (default: {MAX_PARTS})")
    p.set_defaults(func=run_validate)

    c = subparsers.add_parser(
        "canonicalize",
        help="write a structure in canonical form (sorted, re-rooted, axis signs, instance stars)",
        description="Validate a structure document and print its canonical form (SPEC §2): sorted ids, "
                    "degenerate joints removed, each tree re-rooted at its largest part (by box volume "
                    "from --boxes), axis signs fixed and instance groups written as stars; compact JSON "
                    "with 3-decimal numbers.",
        epilog="example: jax3dc canonicalize structure.json --boxes boxes.json --out canonical.json",
    )
    c.add_argument("file", metavar="FILE.json", help="the structure document")
    c.add_argument("--boxes", required=True, metavar="BOXES.json",
                   help='per-part boxes: {"<id>": {"centroid": [x,y,z], "extent": [x,y,z]}} (as written by '
                        "jax3dc data convert)")
    c.add_argument("--out", metavar="FILE", help="write here instead of printing")
    c.add_argument("--names", action="store_true", help="keep each node's semantic name")
    c.set_defaults(func=run_canonicalize)
