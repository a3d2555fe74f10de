"""Stage 1 (f_geo) at inference: one triangle mesh per part, in the normalised frame (SPEC §1).

Backends:
* ``parameters``: a stage-1 model reads the image and writes a factory's category and parameters
  (``jax3dc.parameters``, one line); the factory runs them into parts with ids 1..N, semantic
  names and a metric scale (``jax3dc.factories.run_parameters``). The default when a stage-1 model
  ships (``jax3dc/release/stage1/``). The model folder's marker file picks its reader (``READERS``);
* ``code``: a part program (written by the code model from the image, or handed in) runs in the
  interpreter (parsed, never exec-ed) into part meshes with semantic names (the program's materials
  are not used: materials are stage 2's to predict, from the image);
* ``mesh:FILE``: a part-segmented mesh from any tool (see :mod:`jax3dc.predict.mesh_input`);
* ``parts:DIR``: ground-truth parts, a folder of ``<id>.obj`` (``.stl``, ``.ply``, ``.glb``) as
  ``jax3dc.geometry.parts`` writes it (a dataset object's parts, or a previous prediction's
  ``parts/``): stage 2 alone, for evaluation.

The two backends that read the image first refuse one that cannot hold an object
(``check_object_image``): a model asked about a blank or a noise image still answers (its grammar
makes sure the answer runs), so the object it invents would go all the way to the exports.

Either way the parts are centred with largest extent 1 (``normalise_parts``; a factory's already
are); the factor is kept as the scale (mesh: file units per nu, metres for a mesh in metres;
parameters: metres per nu).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np
import trimesh
from PIL import Image
from scipy.ndimage import maximum_filter, minimum_filter

from jax3dc.errors import InputFileError, ProgramError
from jax3dc.factories.registry import SCHEMAS, run_parameters
from jax3dc.geometry.parts import load_parts, normalise_parts, part_boxes
from jax3dc.parameters import parse_parameters
from jax3dc.predict.mesh_input import load_segmented_mesh
from jax3dc.predict.models import parameters_model
from jax3dc.program.interpreter import run_program
from jax3dc.release import default_stage1_model
from jax3dc.stage1_net import load_reader as load_image_network
from jax3dc.structure import canonicalize

PARAMETERS = "parameters"
CODE = "code"
MESH = "mesh"
PARTS = "parts"
CHOICES = ("`parameters` (a stage-1 model, --stage1-model DIR), `code` (a code model, --code-model DIR), `mesh:FILE` "
           "(a GLB with one node per part, or an OBJ with groups) or `parts:DIR` (a folder of <id>.obj part meshes)")


@dataclass(frozen=True)
class Stage1:
    """The parts of one image: meshes (nu), names by part id, and where they came from."""

    parts: dict[int, trimesh.Trimesh]
    names: dict[int, str]
    scale: float  # source units per nu
    source: str  # "parameters", "code", or the mesh file's / parts folder's path
    program: str | None = None
    category: str | None = None  # the factory's, for the parameters backend (it decides whether the object is mounted)
    joints: int | None = None  # the factory's object's joint count, for the parameters backend (the prompt's Joints: line)


def parse_stage1(spec: str | None, stage1_model: str | Path | None = None) -> tuple[str, Path | None]:
    """``parameters`` -> ("parameters", the stage-1 model folder: ``stage1_model``, else the shipped
    one, else None); ``code`` -> ("code", None); ``mesh:FILE`` -> ("mesh", FILE); ``parts:DIR`` ->
    ("parts", DIR). No spec means ``parameters`` when a stage-1 model is given or ships; otherwise,
    and for anything else, an InputFileError naming what to pass."""
    if spec is None:
        if stage1_model is None and default_stage1_model() is None:
            raise InputFileError("--stage1", f"no stage-1 model ships with this install, so say where the parts come "
                                             f"from: --stage1 {CHOICES}")
        spec = PARAMETERS
    if spec == PARAMETERS:
        folder = stage1_model if stage1_model is not None else default_stage1_model()
        return PARAMETERS, None if folder is None else Path(folder)
    if spec == CODE:
        return CODE, None
    kind, _, path = spec.partition(":")
    if kind in (MESH, PARTS) and path:
        return kind, Path(path)
    raise InputFileError(spec, f"--stage1 must be {CHOICES}")


def _normalised(parts: dict[int, trimesh.Trimesh], where: str) -> tuple[dict[int, trimesh.Trimesh], float]:
    try:
        return normalise_parts(parts)
    except ValueError as e:
        raise InputFileError(where, str(e)) from None


def stage1_from_mesh(path: str | Path, up: str = "z") -> Stage1:
    """Parts of a segmented mesh file whose up axis is ``up`` ("z", ours, or "y", glTF's)."""
    parts, names = load_segmented_mesh(path, up=up)
    normalised, scale = _normalised(parts, str(path))
    return Stage1(normalised, names, scale, str(path))


def stage1_from_parts_dir(directory: str | Path) -> Stage1:
    """Parts of a parts folder (``load_parts``), re-normalised like every other backend's."""
    normalised, scale = _normalised(load_parts(directory), str(directory))
    return Stage1(normalised, {}, scale, str(directory))


def stage1_from_program(text: str) -> Stage1:
    """Runs a part program; a program that fails raises ProgramError naming the line."""
    result = run_program(text)
    try:
        parts, scale = normalise_parts(result.parts)
    except ValueError as e:
        raise ProgramError(None, f"the program's parts have no normalised frame: {e}") from None
    return Stage1(parts, dict(result.names), scale, CODE, text)


def stage1_from_parameters(text: str) -> Stage1:
    """Runs a factory parameter text; a text that does not fit its schema raises ParameterError naming the entry."""
    obj = run_parameters(parse_parameters(text, SCHEMAS))
    joints = len(canonicalize(obj.structure, part_boxes(obj.parts)).joints())  # as a record's prompt counts them
    return Stage1(obj.parts, dict(obj.names), obj.scale_m_per_nu, PARAMETERS, obj.program_text, obj.category, joints)


# The image check. Three refusals, each one error line, in this order:
# * too small: fewer than MIN_SIDE pixels on a side, less than one merged vision token of the
#   models (16 px patches, 2 x 2 merged);
# * noise: almost no pixel has a smooth 3 x 3 neighbourhood. Renders are mostly smooth (sky, floor,
#   the faces of parts), i.i.d. noise nowhere;
# * blank: almost nothing differs from the background colour (the median of the border), measured on
#   the image shrunk to at most COVERAGE_SIDE px so that sensor or JPEG noise does not count.
# The thresholds leave a wide margin on the data (`python3 -m bench.image_check --data DIR ...`):
# over 10,140 renders, none refused (procedural objects in the plain look on black at 32, 64 and 448
# px and in varied looks with sky, floor and textures at 32 to 224 px, varied scenes, and the
# PartNet-Mobility fixtures on black at 224 px), the lowest foreground coverage is 1.3 % (a knife)
# and the lowest smooth share 60 % (a stool on a checker floor); uniform (colour or grey) and
# Gaussian noise images of 32 to 640 px have a smooth share of at most 5.3 %.

MIN_SIDE = 32  # px
COVERAGE_SIDE = 64  # px: the longer side of the image the foreground is measured on
FOREGROUND_STEP = 0.04  # a pixel differs from the background by more than this in some channel (0..1)
MIN_COVERAGE = 0.002  # share of the shrunk image that must differ from the background
SMOOTH_RANGE = 0.2  # a pixel is smooth when its 3 x 3 neighbourhood spans at most this in every channel
MIN_SMOOTH = 0.2  # share of smooth pixels below which the image is noise


def foreground_coverage(rgb: np.ndarray) -> float:
    """Share of the image (shrunk to at most COVERAGE_SIDE px) that differs from the border's median colour."""
    image = Image.fromarray(rgb)
    factor = -(-max(image.size) // COVERAGE_SIDE)
    small = np.asarray(image.reduce(factor) if factor > 1 else image, np.float32) / 255.0
    border = np.concatenate([small[0], small[-1], small[:, 0], small[:, -1]])
    background = np.median(border, axis=0)
    return float((np.abs(small - background).max(axis=-1) > FOREGROUND_STEP).mean())


def smooth_share(rgb: np.ndarray) -> float:
    """Share of pixels whose 3 x 3 neighbourhood spans at most SMOOTH_RANGE in every channel."""
    x = rgb.astype(np.float32) / 255.0
    span = maximum_filter(x, size=(3, 3, 1)) - minimum_filter(x, size=(3, 3, 1))
    return float((span.max(axis=-1) <= SMOOTH_RANGE).mean())


def check_object_image(rgb: np.ndarray, where: str) -> None:
    """Raises InputFileError naming ``where`` when the RGB uint8 image (H, W, 3) is too small, blank or noise."""
    height, width = rgb.shape[:2]
    if min(height, width) < MIN_SIDE:
        raise InputFileError(where, f"the image is {width}x{height} px, too small for stage 1 to read: it needs "
                                    f"at least {MIN_SIDE} px on each side")
    smooth = smooth_share(rgb)
    if smooth < MIN_SMOOTH:
        raise InputFileError(where, f"no object found: the image is noise (only {100 * smooth:.1f} % of its "
                                    "pixels lie in a smooth neighbourhood)")
    coverage = foreground_coverage(rgb)
    if coverage < MIN_COVERAGE:
        raise InputFileError(where, f"no object found: the image is one flat colour ({100 * coverage:.1f} % of it "
                                    "differs from the background)")


# The readers of the parameters backend: ``--stage1 parameters --stage1-model DIR`` hands the
# folder to ``load_reader``, which picks the kind of model by the marker file the folder holds (the
# first of READERS that matches): the image network (``stage1_net.json``; the shipped one) before
# the language model's ``config.json``, the more specific marker first. Another kind of model plugs
# in with one entry.

Reader = Callable[[np.ndarray], str]
"""RGB uint8 image (H, W, 3) -> the one-line parameter text, e.g. ``stapler(length=0.31, ...)``."""


@dataclass(frozen=True)
class ReaderSettings:
    """What a reader may need from predict: a loaded language model is shared with stage 2 when both
    stages name one folder (``sampler`` loads each folder once), and the decoding flags."""

    sampler: Callable[[Path], Any]  # folder -> jax3dc.sampler.Sampler
    max_new_tokens: int
    constrained: bool


@dataclass(frozen=True)
class ReaderKind:
    """One kind of stage-1 model: the file its folder holds, what to call it, and how to load it."""

    marker: str
    description: str
    load: Callable[[Path, ReaderSettings], Reader]


def _language_model(folder: Path, settings: ReaderSettings) -> Reader:
    return parameters_model(settings.sampler(folder), settings.max_new_tokens, settings.constrained)


def _image_network(folder: Path, settings: ReaderSettings) -> Reader:
    return load_image_network(folder)


READERS: tuple[ReaderKind, ...] = (
    ReaderKind("stage1_net.json", "a stage-1 image network (jax3dc.stage1_net), as bench/stage1_net.py "
               "packages it", _image_network),
    ReaderKind("config.json", "a parameters language model: a Hugging Face folder, as the recipe "
               "bench/stage1_model.py packages it", _language_model),
)


def load_reader(folder: str | Path, settings: ReaderSettings) -> Reader:
    """The reader of the stage-1 model in ``folder``; a folder no kind recognises is an InputFileError
    listing the markers it looked for."""
    folder = Path(folder)
    if not folder.is_dir():
        raise InputFileError(folder, "stage-1 model folder not found (--stage1-model)")
    for kind in READERS:
        if (folder / kind.marker).is_file():
            return kind.load(folder, settings)
    wanted = "; ".join(f"{kind.marker} ({kind.description})" for kind in READERS)
    raise InputFileError(folder, f"not a stage-1 model folder: it holds none of {wanted}")
