"""`jax3dc predict IMAGE [IMAGE ...] --out DIR [--stage1 BACKEND] [--stage1-model DIR] [--code-model DIR]
[--structure-model DIR]`; the backends ``--stage1`` takes, and its help lists, are
``jax3dc.predict.stage1.BACKENDS``, the decoding flags ``jax3dc.decoding``'s. One image file is
predicted into DIR itself; several, or a folder of them, into one folder each (``batch``)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from jax3dc.cli_args import positive_int
from jax3dc.decoding import add_decoding_arguments, decoding_from_args
from jax3dc.errors import shorten
from jax3dc.predict.gallery import ERROR, GALLERY_FILE
from jax3dc.predict.segmentation import load_camera
from jax3dc.predict.stage1 import BACKENDS, Stage1Config, backend_help
from jax3dc.processing.processor import MAX_IMAGE_PIXELS
from jax3dc.release import default_structure_model
from jax3dc.xla_flags import GENERATION_GPU_FLAGS, apply_gpu_defaults

if TYPE_CHECKING:
    from jax3dc.predict.pipeline import PredictConfig

DESCRIPTION = """\
Predict the articulated structure of the object in IMAGE and write simulation-ready assets.

Given several images, or a folder of them (PNG, JPEG, WebP, BMP, GIF, TIFF), the models load once,
each image is predicted into its own folder of --out (named from its file name), and
--out/index.html shows them all with their verdicts and links to their viewers. Run the same
command again after it was stopped and it goes on where it stopped: an image whose folder holds
done.json (written last) for the same image is skipped; one that failed is tried again.

Stage 1 gives one mesh per part, from the backend --stage1 names (listed below). `parameters` lets
a stage-1 model (--stage1-model; default: the shipped one in jax3dc/release/stage1, when it
exists) write an object category and its parameters from the image, run by that category's
factory into parts; it is the default --stage1 when a stage-1 model ships, so `jax3dc predict
IMAGE --out DIR` needs nothing else. A mesh file's parts named 1..K keep those ids, other names
are numbered in natural name order. The parts are centred with largest extent 1 (the normalised
frame). The segmentation S is rendered from the image's camera (--camera), and the structure
model (--structure-model) reads the image, S and the part legend and writes the structure.

Outputs in --out (one image): structure.json, image.png, seg.png, parts/, object.urdf, object.xml (MJCF: the
model the physics check judges, its root free unless mounted),
object.usda, object.glb, object_blender.py, physics.json, report.html, report.png, viewer.html (the object in 3D
with a slider per joint; open it again with `jax3dc view DIR`), prediction.json (what `jax3dc edit DIR`
rewrites the files from after a joint is fixed by hand) (and parameters.txt and program.txt
for the parameters backend, program.txt for the code backend, slots.json for the slots backend,
structure_raw.txt when the model's JSON is invalid), prompt.txt (the structure model's prompt).
A bad input stops with one error line; the outputs written before it are kept. The parameters,
code and slots backends first refuse an image too small (under 32 px a side) or with no object in
it (one flat colour, or noise).
"""

CAMERA_HELP = ("JSON file with the image's camera in the normalised object frame (centre at the origin, "
               "largest extent 1), as in a record's meta: {\"lookat\": [0, 0, 0], \"distance\": 2.4, "
               "\"azimuth\": 100, \"elevation\": -20} (MuJoCo free camera, degrees); a meta JSON holding it "
               "under \"camera\" also works. Default: a front view from slightly above that fits the object")


def predict_config(args: argparse.Namespace) -> PredictConfig:
    """The PredictConfig of the options ``add_predict_options`` declared (`jax3dc predict` and
    `jax3dc serve` take the same ones); sets the GPU defaults first, before the backend starts."""
    apply_gpu_defaults(GENERATION_GPU_FLAGS)
    # lazy: the models, decoding and exporters: 0.25 s on top of `jax3dc --help`, which imports this module
    from jax3dc.predict.pipeline import PredictConfig

    camera = load_camera(args.camera) if args.camera else None
    stage1 = Stage1Config(args.stage1, args.stage1_model, args.code_model, args.mesh_up,
                          slots_model_dir=args.slots_model)
    return PredictConfig(stage1, args.structure_model, decoding=decoding_from_args(args), camera=camera,
                         scale=args.scale, mounted=args.mounted, num_joints=args.joints,
                         max_image_pixels=args.max_image_pixels)


def run(args: argparse.Namespace) -> int:
    config = predict_config(args)
    if len(args.image) == 1 and not Path(args.image[0]).is_dir():
        return _run_one(args.image[0], config, args.out)
    return _run_batch(args.image, config, args.out)


def _run_one(image: str, config: PredictConfig, out: str) -> int:
    """One image into --out itself, each output listed as it is written."""
    from jax3dc.predict.pipeline import predict  # lazy: as in run

    width = 18

    def show(name: str, path: Path) -> None:
        print(f"{name:<{width}} {path}", flush=True)

    result = predict(image, config, out, on_output=show, progress=True)
    verdict = "passes" if result.verdict and result.verdict.ok else "fails"
    joints = len(result.structure.joints()) if result.structure else 0
    held = " with its root held (mounted)" if result.mounted else ""
    print(f"{len(result.stage1.parts)} parts, {joints} joints; the physics check{held} {verdict} (see physics.json)")
    return 0


def _run_batch(paths: list[str], config: PredictConfig, out: str) -> int:
    """Several images (or folders of them) into a folder each of --out, one line per image; 1 when
    any failed (the gallery shows why)."""
    from tqdm import tqdm  # lazy: 30 ms that `jax3dc --help` does not need

    from jax3dc.predict.batch import BatchItem, batch_images, predict_batch  # lazy: as in run

    def show(item: BatchItem) -> None:
        card = item.card
        outcome = "skipped (done before)" if item.skipped else (
            f"error: {shorten(card.detail)}" if card.state == ERROR else f"{card.detail}; the physics check {card.state}")
        tqdm.write(f"{item.image} -> {item.folder}: {outcome}")

    items = predict_batch(batch_images(paths), config, out, progress=True, on_item=show)
    failed = sum(item.card.state == ERROR for item in items)
    print(f"{len(items)} images, {failed} failed; see {Path(out) / GALLERY_FILE}")
    return 1 if failed else 0


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("predict", help="image in, articulated simulation-ready object out",
                              description=DESCRIPTION, epilog=f"stage-1 backends (--stage1):\n{backend_help()}",
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("image", nargs="+", metavar="IMAGE",
                   help="the input image (PNG, JPEG, ...); several, or a folder of them, for a batch")
    p.add_argument("--out", required=True, metavar="DIR",
                   help="folder for the outputs (created if missing); for a batch, the folder of the images' folders "
                        "and index.html")
    add_predict_options(p)
    p.set_defaults(func=run)


def add_predict_options(p: argparse.ArgumentParser) -> None:
    """The options that make a PredictConfig (``predict_config``): the models, the camera, scale,
    decoding and image limit; `jax3dc serve` declares the same ones, so a server predicts as the
    command does."""
    p.add_argument("--stage1", metavar="|".join(b.usage for b in BACKENDS.values()),
                   help="where the part meshes come from: one of the stage-1 backends listed below (default: "
                        "parameters when a stage-1 model is given or ships)")
    p.add_argument("--structure-model", metavar="DIR", default=str(default_structure_model()),
                   help="stage-2 checkpoint folder (config.json + safetensors; default: the shipped model in "
                        "jax3dc/release, see its MODEL_CARD.md)")
    p.add_argument("--stage1-model", metavar="DIR",
                   help="stage-1 model folder for --stage1 parameters (a parameters language model's checkpoint "
                        "folder; default: jax3dc/release/stage1 when it ships)")
    p.add_argument("--code-model", metavar="DIR",
                   help="stage-1 code-model checkpoint folder (needed for --stage1 code)")
    p.add_argument("--slots-model", metavar="DIR",
                   help="slots-network folder for --stage1 slots (slots_net.json + model.safetensors, as "
                        "recipes/stage1_slots.py packages it)")
    p.add_argument("--camera", metavar="FILE", help=CAMERA_HELP)
    p.add_argument("--scale", type=float, metavar="M_PER_NU",
                   help="metres per normalised unit for the exports (default: the mesh file's units, "
                        "taken as metres; 1.0 for --stage1 code)")
    p.add_argument("--mesh-up", choices=("z", "y"), default="z",
                   help="up axis of the --stage1 mesh file: z (this project's frame, +Z up, front -Y; what "
                        "jax3dc exports write; the default) or y (glTF's convention, +Y up, front +Z, e.g. Blender's "
                        "glTF exporter)")
    add_decoding_arguments(p, "candidates.json", "repairs.json")
    p.add_argument("--joints", type=positive_int, metavar="N",
                   help="how many joints the object has, told to the structure model as in its training prompts "
                   "(default: the count of the object stage 1 names with --stage1 parameters; none for the other "
                   "backends, and without it the shipped model writes few or no joints)")
    p.add_argument("--mounted", action=argparse.BooleanOptionalAction, default=None,
                   help="the object is fixed in place in use (a faucet, a toilet, a door or window frame): the "
                        "physics check holds its root instead of standing it free on a floor, the candidates "
                        "and repairs are judged so, and object.xml keeps its base fixed (without it, its root "
                        "is free, as in the check; default: mounted when --stage1 parameters names such a "
                        "category (faucet, toilet, door, window), else not)")
    p.add_argument("--max-image-pixels", type=positive_int, default=MAX_IMAGE_PIXELS, metavar="N",
                   help="refuse an image of more pixels, read from its header before decoding (default: %(default)s)")
