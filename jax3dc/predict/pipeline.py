"""`predict`: one image in, a structured, simulation-ready object out (SPEC §1, issue 9).

Steps, each writing its outputs into ``out`` as soon as they exist, so that a failure later on
leaves every output made before it (and the report says what failed):
  1. image I (any image Pillow reads; transparency on white, as the model's processor does) -> image.png,
     and the palette of this image (seeded from its bytes);
  2. stage 1: part meshes from the backend the config names (jax3dc.predict.stage1.BACKENDS: a
     stage-1 model -> factory parameters -> the factory, code model -> part program -> interpreter,
     a segmented mesh file, a parts folder, or one a caller registered) -> parts/ (+ parameters.txt
     and program.txt for the parameters backend, program.txt for the code backend) and the
     stage-2 prompt -> prompt.txt; the backends that read the image first refuse one with no
     object in it (jax3dc.predict.stage1.check_object_image);
  3. S rendered from the image's camera -> seg.png;
  4. stage 2: the structure model reads (I, S, SPEC §3 prompt) -> structure.json (validated,
     canonical); invalid output -> structure_raw.txt and a StructureError;
  5. exports -> object.urdf, object.xml, object.usda, object.glb, object_blender.py (+ meshes/);
  6. physics verdict -> physics.json;
  7. report.html / report.png (always, when stage 1 gave parts), and viewer.html (when there is a
     structure; viewer_files/ beside it): the object in 3D with its joints and verdict (jax3dc.viewer).
prediction.json, written with the parts, keeps what steps 5-7 are made from besides the structure
(scale, mounting, part names, camera, palette seed), so that a hand edit (jax3dc.edits) rewrites
them through the same functions (jax3dc.predict.outputs).

What to compute is one value, ``PredictConfig``; where to write it and whom to tell are
``predict``'s other arguments. The models are plain text-in/text-out callables: set
``generate_structure`` / ``Stage1Config.generate_program`` (or the image-in ``read_parameters``) to
stand in for a checkpoint (tests do; so can a caller with its own model server).
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from PIL import Image
from tqdm import tqdm

from jax3dc.decoding import Decoding
from jax3dc.errors import InputFileError, Jax3dcError, StructureError
from jax3dc.geometry.parts import part_boxes, save_parts
from jax3dc.mounted import is_mounted
from jax3dc.physics.findings import Verdict
from jax3dc.predict.models import TextModel, structure_candidates, structure_model
from jax3dc.predict.outputs import ObjectContext, OutputListener, write_checked, write_pages
from jax3dc.predict.report import ReportInputs
from jax3dc.predict.segmentation import default_camera, render_segmentation
from jax3dc.predict.stage1 import (Reader, ReaderSettings, Stage1, Stage1Backend, Stage1Config, Stage1Image,
                                   Stage1Settings, check_object_image, load_reader, parse_stage1)
from jax3dc.processing.processor import MAX_IMAGE_PIXELS, load_image, to_rgb
from jax3dc.prompt import build_prompt
from jax3dc.render import Camera, png_bytes
from jax3dc.sampler import Sampler
from jax3dc.structure import Structure, canonicalize, parse_structure
from jax3dc.structure.validate import json_text
from jax3dc.verify.repair import repair
from jax3dc.verify.select import Candidate, choose
from jax3dc.verify.verdicts import Physics, VerdictCache

MAX_SEG_SIDE = 1024  # px; S has the image's size and aspect, its longer side at most this

STEPS = ("stage 1", "segmentation", "structure model", "exports", "physics", "report")


@dataclass
class PredictResult:
    """What a prediction produced; ``files`` maps an output's name to its path."""

    out: Path
    stage1: Stage1
    camera: Camera
    palette: np.ndarray  # this image's part colours (S and the legend)
    prompt: str
    files: dict[str, Path] = field(default_factory=dict)
    raw_text: str | None = None
    structure: Structure | None = None
    verdict: Verdict | None = None
    mounted: bool = False  # whether the physics check held the root and object.xml keeps its base fixed


def _image_and_digest(image: str | Path | Image.Image, max_pixels: int) -> tuple[Image.Image, str]:
    if isinstance(image, Image.Image):
        rgb = to_rgb(image)
        return rgb, hashlib.sha256(png_bytes(np.asarray(rgb))).hexdigest()
    path = Path(image)
    rgb = to_rgb(load_image(path, max_pixels))
    return rgb, hashlib.sha256(path.read_bytes()).hexdigest()


def seg_size(image: Image.Image) -> tuple[int, int]:
    """(width, height) of S: the image's, shrunk so the longer side is at most MAX_SEG_SIDE."""
    shrink = min(1.0, MAX_SEG_SIDE / max(image.width, image.height))
    return max(1, round(image.width * shrink)), max(1, round(image.height * shrink))


class Checkpoints:
    """Loads each checkpoint folder once: one model may have learned both tasks (issue 9), and a
    4B model loaded twice would hold its weights twice. A caller predicting many images (``jax3dc
    predict`` given several, jax3dc.predict.batch) passes one to every ``predict``, so the models,
    the stage-1 network's reader included (0.3 s to load, and its compiled program), load once."""

    def __init__(self, dtype: str):
        self.dtype = dtype
        self.loaded: dict[Path, Sampler] = {}
        self.readers: dict[tuple[Path, int, bool], Reader] = {}

    def get(self, folder: str | Path) -> Sampler:
        key = Path(folder).resolve()
        if key not in self.loaded:
            self.loaded[key] = Sampler.load(folder, self.dtype)
        return self.loaded[key]

    def reader(self, folder: str | Path, decoding: Decoding) -> Reader:
        """The reader of the stage-1 model folder (``jax3dc.predict.stage1.load_reader``), decoding
        a language model's text as ``decoding`` says."""
        constrained = decoding.options.constrained
        key = (Path(folder).resolve(), decoding.max_new_tokens, constrained)
        if key not in self.readers:
            self.readers[key] = load_reader(folder, ReaderSettings(self.get, decoding.max_new_tokens, constrained))
        return self.readers[key]


class _Outputs:
    """The files of one prediction: each is written, recorded under its name and announced to the
    listener (the CLI prints them) as soon as it exists."""

    def __init__(self, out: Path, on_output: OutputListener | None):
        self.out = out
        self.files: dict[str, Path] = {}
        self.on_output = on_output

    def wrote(self, name: str, path: Path) -> Path:
        self.files[name] = path
        if self.on_output is not None:
            self.on_output(name, path)
        return path

    def text(self, name: str, filename: str, text: str) -> Path:
        (self.out / filename).write_text(text, encoding="utf-8")
        return self.wrote(name, self.out / filename)

    def binary(self, name: str, filename: str, data: bytes) -> Path:
        (self.out / filename).write_bytes(data)
        return self.wrote(name, self.out / filename)


class _Progress:
    """A bar over STEPS on stderr (only on a terminal, and only when asked)."""

    def __init__(self, enabled: bool):
        self.bar = tqdm(total=len(STEPS), desc="predict", unit="step", leave=False,
                        disable=None if enabled else True)  # None: only on a terminal

    def step(self, name: str) -> None:
        self.bar.set_postfix_str(name)
        self.bar.n = STEPS.index(name)
        self.bar.refresh()


def _chosen(replies: list[tuple[str, float]], boxes: dict, check: VerdictCache,
            outputs: _Outputs) -> tuple[str, Structure | None]:
    """The candidate the physics verdict prefers, as text and, when it parses, as the canonical
    structure ``choose`` made of it; candidates.json holds every one's row and the reason."""
    candidates = [Candidate(text, logprob) for text, logprob in replies]
    choice = choose(candidates, boxes, check)
    rows = [{"parsed": r.parsed, "rule": r.rule, "physics_ok": r.ok, "flagged_joints": r.flagged, "logprob": round(r.logprob, 4),
             "text": c.text} for r, c in zip(choice.rows, candidates)]
    doc = {"winner": choice.index, "reason": choice.reason, "candidates": rows}
    outputs.text("candidates", "candidates.json", json.dumps(doc, indent=1) + "\n")
    return candidates[choice.index].text, choice.structure


def _repaired(structure: Structure, boxes: dict, check: VerdictCache, outputs: _Outputs) -> Structure:
    """``structure`` with flagged hinges repaired where the verdict improves; repairs.json lists them."""
    fixed = repair(structure, boxes, check)
    outputs.text("repairs", "repairs.json", json.dumps([r.to_dict() for r in fixed.repairs], indent=1) + "\n")
    return fixed.structure


@dataclass(frozen=True)
class PredictConfig:
    """What ``predict`` makes of an image, as one value (the CLI builds it from its flags).

    ``stage1``: where the parts come from (the backend and its models; jax3dc.predict.stage1).
    ``structure_model_dir``: the structure model's checkpoint folder (``jax3dc.sampler.Sampler.load``);
    ``generate_structure`` (SPEC §3 prompt text -> structure JSON text, seeing I and S) replaces it.
    ``decoding``: the decoding flags (jax3dc.decoding). Its options: ``constrained`` decodes under
    the structure grammar and, for the parameters and code backends, the parameter or part-program
    grammar (all always parse); ``candidates`` K > 1: K answers from one decode (the first greedy),
    chosen by the physics verdict (candidates.json says which and why); ``grounding``: correct the
    decoded joints with the part boxes (jax3dc.grounding). ``repair``: move the pivots of flagged
    hinges where the verdict improves (repairs.json lists them). Candidates and grounding need a
    structure model folder, not a ``generate_structure``.
    ``camera``: the image's camera in the normalised frame (default: a front view fitting the object).
    ``scale``: metres per nu for the exports (default: ``Stage1.metres()``: the mesh file's units per
    nu, assumed metres; the factory's for the parameters backend; 1.0 for the code backend, whose
    programs are in nu).
    ``mounted``: the object is fixed in place in use (a faucet, a toilet): the physics checks hold its
    root instead of standing it on a floor, and object.xml keeps its base fixed instead of free.
    None: mounted when stage 1 names a category fixed in place in use (the parameters backend's
    factory: ``jax3dc.mounted``), else not (the other backends name no category).
    ``num_joints``: how many joints the object has, written into the prompt's ``Joints:`` line as in
    training (SPEC §3); None: the count stage 1 knows (the parameters backend's factory object), else
    no line (the shipped structure model then writes few or no joints).
    ``max_image_pixels``: a larger image file is refused from its header, before decoding.
    """

    stage1: Stage1Config = field(default_factory=Stage1Config)
    structure_model_dir: str | Path | None = None
    generate_structure: TextModel | None = None
    decoding: Decoding = field(default_factory=Decoding)
    camera: Camera | None = None
    scale: float | None = None
    mounted: bool | None = None
    num_joints: int | None = None
    max_image_pixels: int = MAX_IMAGE_PIXELS


def _stage1(image: str | Path | Image.Image, backend: Stage1Backend, argument: str | None, config: PredictConfig,
            checkpoints: Checkpoints, outputs: _Outputs) -> tuple[Image.Image, bytes, str, Stage1]:
    """I (image.png) and the part meshes of ``backend`` (with the files it writes): (I in RGB, its
    PNG bytes, the sha256 of the input, the parts)."""
    rgb, digest = _image_and_digest(image, config.max_image_pixels)
    pixels = np.asarray(rgb)
    image_png = png_bytes(pixels)  # I as the models saw it (RGB): the viewer shows it
    target = outputs.out / "image.png"
    if isinstance(image, (str, Path)) and Path(image).resolve() == target.resolve():
        outputs.wrote("image", target)  # never written over the input itself
    else:
        outputs.binary("image", "image.png", image_png)
    seen = Stage1Image(pixels, image_png, str(image) if isinstance(image, (str, Path)) else "the input image")
    if backend.reads_image:
        check_object_image(seen.rgb, seen.where)
    settings = Stage1Settings(config.stage1, argument, config.decoding, checkpoints.get,
                              lambda folder: checkpoints.reader(folder, config.decoding), outputs.text)
    return rgb, image_png, digest, backend.run(seen, settings)


def _stage2(result: PredictResult, image_png: bytes, seg_png: bytes, boxes: dict, context: ObjectContext,
            config: PredictConfig, checkpoints: Checkpoints, outputs: _Outputs, progress: _Progress) -> None:
    """Structure model -> structure.json, exports and physics.json, filling ``result``; raises a
    Jax3dcError at the first step that fails (the outputs before it stay). The winner of several
    candidates is parsed once, and each structure's verdict computed once (one VerdictCache serves
    the choice, the repair and physics.json)."""
    progress.step("structure model")
    parts_in = result.stage1
    check = VerdictCache(Physics(parts_in.parts, context.scale, context.mounted))
    decoding = config.decoding
    generate = config.generate_structure
    structure = None
    if generate is None:
        if config.structure_model_dir is None:
            raise InputFileError("--structure-model", "a structure model checkpoint (--structure-model DIR) is needed")
        sampler = checkpoints.get(config.structure_model_dir)
        if decoding.options.candidates > 1:
            replies = structure_candidates(sampler, image_png, seg_png, decoding.max_new_tokens,
                                           decoding.options)(result.prompt)
            result.raw_text, structure = _chosen(replies, boxes, check, outputs)
        else:
            generate = structure_model(sampler, image_png, seg_png, decoding.max_new_tokens, decoding.options)
    if result.raw_text is None:
        result.raw_text = generate(result.prompt)
    if structure is None:
        try:
            parsed = parse_structure(json_text(result.raw_text), part_ids=parts_in.parts)
        except StructureError as e:
            raw = outputs.text("structure_raw", "structure_raw.txt", result.raw_text)
            raise StructureError(e.rule, e.where, f"{e.message} (the model's raw output is in {raw})") from None
        structure = canonicalize(parsed, boxes)
    progress.step("exports")
    if decoding.repair:
        structure = _repaired(structure, boxes, check, outputs)
    result.structure = structure
    result.verdict = write_checked(structure, parts_in.parts, context, outputs.out, check, outputs.wrote, progress.step)


def predict(image: str | Path | Image.Image, config: PredictConfig, out: str | Path = "prediction",
            on_output: OutputListener | None = None, progress: bool = False,
            checkpoints: Checkpoints | None = None) -> PredictResult:
    """Runs both stages on ``image`` as ``config`` says and writes every output into ``out``.

    ``on_output``: told each output's name and path as it is written (the CLI prints them).
    ``progress``: a progress bar of the steps on stderr when it is a terminal (the CLI's).
    ``checkpoints``: the loaded models to use (and add to), so that a caller predicting many images
    loads each checkpoint once; their dtype, not ``config.decoding.dtype``, applies (default: a fresh one).
    Raises a Jax3dcError subclass on bad input, after writing every output it could; a bad stage-1
    backend before writing anything.
    """
    out = Path(out)
    backend, argument = parse_stage1(config.stage1.backend, config.stage1.model_dir)
    out.mkdir(parents=True, exist_ok=True)
    outputs = _Outputs(out, on_output)
    checkpoints = checkpoints if checkpoints is not None else Checkpoints(config.decoding.dtype)
    steps = _Progress(progress)
    try:
        steps.step("stage 1")
        rgb, image_png, digest, parts_in = _stage1(image, backend, argument, config, checkpoints, outputs)
        mounted = config.mounted if config.mounted is not None else is_mounted(parts_in.category)
        boxes = part_boxes(parts_in.parts)
        camera = config.camera or default_camera(parts_in.parts)
        context = ObjectContext(config.scale if config.scale is not None else parts_in.metres(), mounted,
                                dict(parts_in.names), camera.to_dict(), config.camera is not None, digest)
        palette = context.palette()
        joints = config.num_joints if config.num_joints is not None else parts_in.joints
        result = PredictResult(out, parts_in, camera, palette, build_prompt(boxes, palette, joints), outputs.files,
                               mounted=mounted)
        outputs.text("prompt", "prompt.txt", result.prompt)
        save_parts(parts_in.parts, out / "parts")
        outputs.wrote("parts", out / "parts")
        outputs.wrote("context", context.write(out))
        steps.step("segmentation")
        width, height = seg_size(rgb)
        seg, _ids = render_segmentation(parts_in.parts, camera, palette, width, height=height)
        seg_png = png_bytes(seg)
        outputs.binary("seg", "seg.png", seg_png)

        error: Jax3dcError | None = None
        try:
            _stage2(result, image_png, seg_png, boxes, context, config, checkpoints, outputs, steps)
        except Jax3dcError as e:
            error = e
        steps.step("report")
        report = ReportInputs(rgb, seg, palette, parts_in.names, boxes, context.camera, context.camera_given,
                              result.structure, result.verdict, None if error is None else str(error))
        write_pages(report, outputs.files.get("glb"), image_png, seg_png, out, out.resolve().name, outputs.wrote)
    finally:
        steps.bar.close()  # before the caller prints an error line
    if error is not None:
        raise error
    return result
