"""``jax3dc data build`` (factory objects) and ``jax3dc data import`` (URDF / MJCF) → shards;
``jax3dc data card`` → statistics and contact sheet."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from data_pipeline.card import dataset_card
from jax3dc.errors import InputFileError, Jax3dcError
from jax3dc.processing.processor import MIN_IMAGE_SIDE

SPLIT_CHOICES = ("hash", "train", "val", "test")  # data_pipeline.build.SPLIT_CHOICES (not imported: keeps --help fast)
APPEARANCE_CHOICES = ("plain", "varied", "photo", "mixed", "all")  # data_pipeline.samples.BUILD_APPEARANCES (not imported: as above)

BUILD_DESCRIPTION = """\
Render procedural objects into ArrayRecord shards of training records (SPEC §4).

Each object gives --views records: view 0 at rest, later views with one joint moved. Objects are
split into train/val/test by a hash of their id, never by view. Files in --out:
  train-00000.array_record ...   the shards
  manifest.json                  settings, the finished shards (records, SHA-256) and the
                                 objects skipped because they failed to load or render (error)
If a build is interrupted, run the same command again: finished shards are kept, the rest are
rebuilt (byte-identical for the same --seed).

example:  jax3dc data build --out data/train --objects 200 --views 3 --workers 2 --seed 0
"""

IMPORT_DESCRIPTION = """\
Convert URDF / MJCF objects (e.g. PartNet-Mobility folders with mobility.urdf) and render them
into ArrayRecord shards, like `jax3dc data build`.

Each object's id (in its record keys, <category>/<id>/<view>) is its folder or file name; sources
that share a name are told apart by the folders above them (a/microwave.xml, b/microwave.xml ->
a__microwave.xml, b__microwave.xml). By default objects are split into train/val/test by a hash
of their id, as in `jax3dc data build`; --split train|val|test puts every imported object in that
one split (e.g. a held-out set of real objects for `jax3dc eval run`). The sources and the split
are part of the build's settings: resuming into the same --out with others is refused (a build is
not appended to).

An object that fails to load or render (a broken file, a mesh MuJoCo refuses) is skipped, not
the build: a warning line names it and its path, manifest.json lists it under "skipped" with
its error, and the summary says how many were skipped.

example:  jax3dc data import partnet/door_8877 partnet/microwave_7119 --out data/imported
example:  jax3dc data import real/* --out data/real_test --split test
"""


def _common(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--out", metavar="DIR", type=Path, required=True, help="output directory")
    parser.add_argument("--views", type=int, default=3, help="records per object (default 3)")
    parser.add_argument("--workers", type=int, default=1, help="parallel render processes (default 1)")
    parser.add_argument("--seed", type=int, default=0, help="build seed (default 0)")
    parser.add_argument("--size", type=int, default=448, help="image side in pixels (default 448)")
    parser.add_argument("--objects-per-shard", type=int, default=8, help="objects in one shard (default 8)")
    parser.add_argument("--augment", action="store_true",
                        help="also render a split variant (an articulated leaf cut in two) and a merge variant "
                        "(two compatible sibling leaves joined) of each object, one view each")
    parser.add_argument("--appearance", choices=APPEARANCE_CHOICES, default="plain",
                        help="look of the images I (S is the same either way): plain = one lighting, black "
                        "background, material colours, fixed field of view (default); varied = random lights, "
                        "sky / floor, jittered part colours and textures, camera distance and field of view, "
                        "all from the build seed; photo = varied, then exposure, white balance, blur, noise, "
                        "vignetting, resizing and JPEG as a camera and a file leave a photo; mixed = each view "
                        "plain or varied with equal odds, so that no look marks where an object comes from; "
                        "all = each view plain, varied or photo with equal odds")
    parser.add_argument("--mirror", action="store_true",
                        help="also render every view of each object's mirror image (x -> -x; hinges change side)")
    parser.add_argument("--fuse-handles", action="store_true",
                        help="also render every view of each object with its handles, knobs and the rigid pieces "
                        "of its moving parts fused into the parts they sit on, as real meshes have them")
    parser.add_argument("--palette-per-view", action="store_true",
                        help="permute S's colours per view instead of per object (a training augmentation)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar and no summary")


def register(subparsers: argparse._SubParsersAction) -> None:
    build = subparsers.add_parser("build", help="render procedural objects into ArrayRecord shards",
                                  description=BUILD_DESCRIPTION,
                                  formatter_class=argparse.RawDescriptionHelpFormatter)
    build.add_argument("--objects", type=int, required=True, help="number of factory objects (cycling categories)")
    build.add_argument("--categories", metavar="NAMES", default=None,
                       help="comma-separated factory categories to cycle through (default: every factory), "
                       "e.g. camera,knife to add new families to a dataset without rendering the others")
    build.add_argument("--composed", type=int, default=0,
                       help="number of objects composed from the real part meshes of --parts: bodies, doors, "
                       "drawers, flaps and lids laid out anew, hinges on the edge away from the handle (default 0)")
    build.add_argument("--parts", metavar="DIR", type=Path, default=None,
                       help="part library for --composed: a folder of partnet_uv/<kind>/*.obj (cabinet_frames, "
                       "doorLs, doorRs, drawers, handles, knobs), e.g. ../shared/real_parts")
    build.add_argument("--scenes", type=int, default=0,
                       help="number of multi-object scenes (furniture with items on top), each written at "
                       "part and object granularity (default 0)")
    _common(build)
    build.set_defaults(func=run_build_command)

    imp = subparsers.add_parser("import", help="render URDF / MJCF objects into ArrayRecord shards",
                                description=IMPORT_DESCRIPTION,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    imp.add_argument("paths", nargs="+", metavar="PATH", type=Path, help="URDF / MJCF files or object folders")
    imp.add_argument("--split", choices=SPLIT_CHOICES, default="hash",
                     help="hash: each object's split from SHA-256 of its folder name (default); "
                     "train / val / test: every object in that split")
    _common(imp)
    imp.set_defaults(func=run_import_command)

    card = subparsers.add_parser("card", help="statistics and a contact sheet of a built dataset",
                                 description="Write DIR/card.json (records, objects per category, joints, "
                                 "relations, parts, Qwen3 token counts of prompt and target) and "
                                 "DIR/contact_sheet.png (sample images I above their segmentations S).")
    card.add_argument("dir", metavar="DIR", type=Path, help="dataset directory (from `jax3dc data build`)")
    card.add_argument("--samples", type=int, default=16, help="records on the contact sheet (default 16)")
    card.add_argument("--quiet", action="store_true", help="no progress bar and no summary")
    card.set_defaults(func=run_card_command)


def _run(args: argparse.Namespace, sources: list) -> int:
    from data_pipeline.build import BuildConfig, run_build  # lazy: array_record, factories (52 ms after `jax3dc --help`)

    if args.views < 1 or args.workers < 1 or args.size < MIN_IMAGE_SIDE or args.objects_per_shard < 1:
        raise SystemExit(f"--views, --workers, --objects-per-shard must be >= 1 and --size >= {MIN_IMAGE_SIDE}")
    config = BuildConfig(views=args.views, seed=args.seed, size=args.size, objects_per_shard=args.objects_per_shard,
                         augment=args.augment, split=getattr(args, "split", "hash"),
                         appearance=args.appearance, mirror=args.mirror, palette_per_view=args.palette_per_view,
                         fuse_handles=args.fuse_handles)
    manifest = run_build(args.out, sources, config, args.workers, progress=not args.quiet)
    total = sum(s["records"] for s in manifest["shards"].values())
    skipped = len(manifest.get("skipped", {}))
    if not args.quiet:
        summary = f"{total} records in {len(manifest['shards'])} shards in {args.out}"
        if skipped:
            summary += f"; {skipped} object{'s' if skipped != 1 else ''} skipped (errors in manifest.json)"
        print(summary)
    if skipped and total == 0:
        raise InputFileError(args.out, f"every object was skipped ({skipped}): no records; errors in manifest.json")
    return 0


def run_build_command(args: argparse.Namespace) -> int:
    from data_pipeline.build import composed_sources, factory_sources, part_library, scene_sources  # lazy: as in _run

    if min(args.objects, args.scenes, args.composed) < 0 or args.objects + args.scenes + args.composed < 1:
        raise SystemExit("--objects, --scenes and --composed must be >= 0, and not all 0")
    composed = []
    if args.composed:
        if args.parts is None:
            raise SystemExit("--composed needs --parts DIR (a part library, e.g. ../shared/real_parts)")
        try:
            part_library(str(args.parts.resolve()))
        except FileNotFoundError as e:
            raise InputFileError(args.parts, str(e)) from None
        composed = composed_sources(args.composed, args.seed, args.parts)
    categories = None if args.categories is None else [c.strip() for c in args.categories.split(",") if c.strip()]
    try:
        factories = factory_sources(args.objects, args.seed, categories)
    except Jax3dcError as e:
        raise SystemExit(f"--categories: {e}") from None
    return _run(args, factories + scene_sources(args.scenes, args.seed) + composed)


def run_import_command(args: argparse.Namespace) -> int:
    from data_pipeline.build import import_sources  # lazy: as in _run (52 ms)

    return _run(args, import_sources(args.paths))


def run_card_command(args: argparse.Namespace) -> int:
    stats = dataset_card(args.dir, samples=args.samples, progress=not args.quiet)
    if not args.quiet:
        print(json.dumps({k: stats[k] for k in ("records", "splits", "joints", "relations", "target_tokens")}))
    return 0
