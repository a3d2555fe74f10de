"""``jax3dc data restyle``: re-render the images of a built split with another renderer."""

from __future__ import annotations

import argparse
from pathlib import Path

from tqdm import tqdm

from jax3dc.errors import InputFileError, Jax3dcError

RESTYLE_DESCRIPTION = """\
Re-render the image I of the records of a built dataset with Blender Cycles (a path tracer):
the same camera and posed parts, but other lights (sun and area lights of random colours, a lit
world), other materials (Principled BSDF: metal, coat, glass, wood grain, speckle), other
backgrounds and tone mapping than the MuJoCo renders of `jax3dc data build`. S, the prompt, the
target and the rest of each record are kept, and meta.renderer says "cycles", so
`jax3dc eval run --data OUT` scores the new shards as it scores the originals: an
appearance-shifted test set.

Each record's meta.cycles.mask_iou is the IoU of Cycles' object mask with S's parts; a record
below 0.8 stops the command (the two renderers disagree about the camera or pose).

Needs a Python with bpy 5.0.1 (bpy needs numpy < 2, so it has its own environment): set
JAX3DC_BLENDER_PYTHON to its bin/python, or create .venv-blender in the repository:
  python3 -m venv .venv-blender && .venv-blender/bin/pip install bpy==5.0.1
CPU only; about 1-2 s per 224 px image at 24 samples on 2 cores. Interrupted? Run the same
command again: finished shards are kept.

example:  jax3dc data restyle --from data/test --out data/test_cycles --split test --limit 100
"""


def register(subparsers: argparse._SubParsersAction) -> None:
    restyle = subparsers.add_parser("restyle", help="re-render the images of a built split with Blender Cycles",
                                    description=RESTYLE_DESCRIPTION,
                                    formatter_class=argparse.RawDescriptionHelpFormatter)
    restyle.add_argument("--from", dest="source", metavar="DIR", type=Path, required=True,
                         help="dataset folder written by `jax3dc data build` / `data import`")
    restyle.add_argument("--out", metavar="DIR", type=Path, required=True, help="output dataset folder")
    restyle.add_argument("--renderer", choices=("cycles",), default="cycles", help="renderer of the new images "
                         "(default cycles, the only one)")
    restyle.add_argument("--split", default="test", help="split to restyle: shard-name prefix and meta.split "
                         "(default test); 'all' takes every record")
    restyle.add_argument("--limit", type=int, default=0, help="only the first N records of the split (0 = all)")
    restyle.add_argument("--samples", type=int, default=24, help="Cycles samples per pixel (default 24)")
    restyle.add_argument("--no-denoise", action="store_true", help="skip OpenImageDenoise (noisier, a little faster)")
    restyle.add_argument("--threads", type=int, default=2, help="CPU threads Cycles uses (default 2)")
    restyle.add_argument("--sources", nargs="*", metavar="FOLDER", type=Path, default=[],
                         help="folders holding the source objects of imported records (their part meshes are "
                         "rebuilt from them), as for `jax3dc eval run --sources`")
    restyle.add_argument("--quiet", action="store_true", help="no progress bar and no summary")
    restyle.set_defaults(func=run_restyle_command)


def run_restyle_command(args: argparse.Namespace) -> int:
    # lazy: the Cycles restyler and its part rebuilder (45 ms after `jax3dc --help`, which imports this module)
    from data_pipeline.cycles import CyclesSettings, restyle_dataset, seconds_per_image

    if args.samples < 1 or args.threads < 1 or args.limit < 0:
        raise Jax3dcError("--samples and --threads must be >= 1 and --limit >= 0")
    settings = CyclesSettings(samples=args.samples, denoise=not args.no_denoise, threads=args.threads)
    for folder in args.sources:
        if not folder.is_dir():
            raise InputFileError(folder, "--sources names no such folder")
    sources = {p.name: p for folder in args.sources for p in folder.iterdir() if p.is_dir()}
    bar = tqdm(total=args.limit or None, unit="image", disable=args.quiet)
    try:
        manifest = restyle_dataset(args.source, args.out, split=args.split, limit=args.limit, settings=settings,
                                   sources=sources, on_batch=bar.update)
    finally:
        bar.close()
    if not args.quiet:
        records = sum(s["records"] for s in manifest["shards"].values())
        render, wall = seconds_per_image(manifest)
        print(f"{records} records restyled with Cycles in {args.out} ({render:.2f} s render, "
              f"{wall:.2f} s in all per image)")
    return 0
