"""Stage 1 (f_geo) at inference: one triangle mesh per part, in the normalised frame (SPEC §1).

Where the parts come from is a backend, chosen by name (``--stage1 NAME`` or ``NAME:ARG``) from
``BACKENDS``: each is a callable ``(Stage1Image, Stage1Settings) -> Stage1``, so a model that
writes parts directly plugs in with ``register_backend`` beside the five built in:
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
  ``parts/``): stage 2 alone, for evaluation;
* ``slots``: the slots network (``jax3dc.stage1_slots``, ``--slots-model DIR``) reads the image and
  writes the object's parts as boxes with generic kinds, whatever the category (issue 64): one box
  mesh per kept slot, named by its kind; slots.json keeps what it wrote (boxes, kinds, parents).

A backend that reads the image (``reads_image``) is handed only an image that can hold an object
(``check_object_image``): a model asked about a blank or a noise image still answers (its grammar
makes sure the answer runs), so the object it invents would go all the way to the exports.

Either way the parts are centred with largest extent 1 (``normalise_parts``; a factory's already
are); the factor is kept as the scale (mesh: file units per nu, metres for a mesh in metres;
parameters: metres per nu).

`jax3dc --help` imports this module to list the backends, so the models (jax, 1.5 s) are imported
only when a backend loads one.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

import numpy as np
import trimesh
from PIL import Image
from scipy.ndimage import maximum_filter, minimum_filter

from jax3dc.decoding import Decoding
from jax3dc.errors import InputFileError, Jax3dcError, ProgramError
from jax3dc.factories.registry import SCHEMAS, run_parameters
from jax3dc.geometry.parts import load_parts, normalise_parts, part_boxes
from jax3dc.parameters import parse_parameters
from jax3dc.predict.mesh_input import load_segmented_mesh
from jax3dc.program.interpreter import run_program
from jax3dc.prompt import CODE_PROMPT
from jax3dc.release import default_stage1_model
from jax3dc.structure import canonicalize

if TYPE_CHECKING:
    from jax3dc.predict.models import TextModel

PARAMETERS = "parameters"
CODE = "code"
MESH = "mesh"
PARTS = "parts"
SLOTS = "slots"

Reader = Callable[[np.ndarray], str]
"""RGB uint8 image (H, W, 3) -> the one-line parameter text, e.g. ``stapler(length=0.31, ...)``."""


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
    metres_per_nu: float | None = None  # when ``scale`` is not in metres (a part program's units are nu: 1.0)

    def metres(self) -> float:
        """Metres per nu of the exports and the physics check when the caller names none: the
        source's units are taken as metres unless the backend knows better."""
        return self.scale if self.metres_per_nu is None else self.metres_per_nu


@dataclass(frozen=True)
class Stage1Image:
    """Image I as a backend reads it: RGB uint8 (H, W, 3), its PNG bytes (what the language models
    are handed), and what an error about it names (the file, or "the input image")."""

    rgb: np.ndarray
    png: bytes
    where: str


@dataclass(frozen=True)
class Stage1Config:
    """The caller's choice of stage 1 (``PredictConfig.stage1``); each backend reads the fields it needs."""

    backend: str | None = None  # NAME or NAME:ARG of BACKENDS; None: parameters when a stage-1 model is given or ships
    model_dir: str | Path | None = None  # --stage1-model (the parameters backend's; default: the shipped one)
    code_model_dir: str | Path | None = None  # --code-model
    mesh_up: str = "z"  # the mesh file's up axis: "z" (ours, jax3dc's exports) or "y" (glTF's convention)
    read_parameters: Reader | None = None  # stands in for the stage-1 model (tests; a caller's own model server)
    generate_program: TextModel | None = None  # stands in for the code model: the code prompt -> a part program
    slots_model_dir: str | Path | None = None  # --slots-model (the slots backend's network folder)


@dataclass(frozen=True)
class Stage1Settings:
    """What a backend gets besides the image. ``load_model`` loads a checkpoint folder once for the
    whole prediction (stage 2 may name the same folder), and ``load_reader`` a stage-1 model folder's
    reader once for every image predict is given (``jax3dc.predict.pipeline.Checkpoints``);
    ``write_text(name, filename, text)`` writes an output into --out at once, so that it stays for
    inspection when a later step fails."""

    config: Stage1Config
    argument: str | None  # ARG of ``NAME:ARG`` (the mesh file, the parts folder); None for a backend that takes none
    decoding: Decoding
    load_model: Callable[[str | Path], Any]  # folder -> jax3dc.sampler.Sampler
    load_reader: Callable[[str | Path], Reader]  # stage-1 model folder -> its reader (``load_reader``)
    write_text: Callable[[str, str, str], Path]


Stage1Runner = Callable[[Stage1Image, Stage1Settings], Stage1]


@dataclass(frozen=True)
class Stage1Backend:
    """One source of parts, as ``--stage1`` names it."""

    name: str
    summary: str  # its line in `jax3dc predict --help`
    run: Stage1Runner
    argument: str | None = None  # the metavar of ``NAME:ARG`` ("FILE"); None: the name alone
    reads_image: bool = False  # refuse an image with no object in it before running (check_object_image)

    @property
    def usage(self) -> str:
        return self.name if self.argument is None else f"{self.name}:{self.argument}"


BACKENDS: dict[str, Stage1Backend] = {}
"""Name -> backend, in the order `jax3dc predict --help` lists them."""


def register_backend(backend: Stage1Backend) -> Stage1Backend:
    """Adds ``backend`` to BACKENDS (before the parser is built, for `jax3dc predict --help` to list
    it); a name already taken, or one with a colon, is a ValueError rather than a silent replacement."""
    if not backend.name or ":" in backend.name:
        raise ValueError(f"a stage-1 backend's name is a word without a colon, not {backend.name!r}")
    if backend.name in BACKENDS:
        raise ValueError(f"a stage-1 backend named {backend.name!r} exists already")
    BACKENDS[backend.name] = backend
    return backend


def backend_choices() -> str:
    """The backends' usages on one line, for error messages."""
    usages = [f"`{b.usage}`" for b in BACKENDS.values()]
    listed = usages[0] if len(usages) == 1 else f"{', '.join(usages[:-1])} or {usages[-1]}"
    return f"{listed} (`jax3dc predict --help` says what each reads)"


def backend_help() -> str:
    """One line per backend (usage, then summary), for `jax3dc predict --help`."""
    width = max(len(b.usage) for b in BACKENDS.values()) + 2
    return "\n".join(f"  {b.usage:<{width}}{b.summary}" for b in BACKENDS.values())


def parse_stage1(spec: str | None, model_dir: str | Path | None = None) -> tuple[Stage1Backend, str | None]:
    """The backend ``spec`` names and its argument: ``NAME`` -> (backend, None), ``NAME:ARG`` ->
    (backend, ARG) for a backend that takes one. No spec means ``parameters`` when a stage-1 model
    is given (``model_dir``) or ships; otherwise, and for an unknown name or a missing or
    unexpected argument, an InputFileError naming the choices."""
    if spec is None:
        if model_dir is None and default_stage1_model() is None:
            raise InputFileError("--stage1", "no stage-1 model ships with this install, so say where the parts come "
                                             "from (--stage1-model DIR names a stage-1 model): "
                                             f"--stage1 {backend_choices()}")
        spec = PARAMETERS
    name, colon, argument = spec.partition(":")
    backend = BACKENDS.get(name)
    if backend is not None:
        if backend.argument is None and not colon:
            return backend, None
        if backend.argument is not None and argument:
            return backend, argument
    raise InputFileError(spec, f"--stage1 must be {backend_choices()}")


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
# The thresholds leave a wide margin on the data (`python3 -m eval.evaluate image_check --data DIR ...`):
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
    from jax3dc.predict.models import parameters_model  # lazy: jax and the grammars (1.5 s), see the module docstring

    return parameters_model(settings.sampler(folder), settings.max_new_tokens, settings.constrained)


def _image_network(folder: Path, settings: ReaderSettings) -> Reader:
    from jax3dc.stage1_net import load_reader as load_image_network  # lazy: jax (2 s), see the module docstring

    return load_image_network(folder)


READERS: tuple[ReaderKind, ...] = (
    ReaderKind("stage1_net.json", "a stage-1 image network (jax3dc.stage1_net), as recipes/stage1_net.py "
               "packages it", _image_network),
    ReaderKind("config.json", "a parameters language model: a Hugging Face folder, as the recipe "
               "recipes/stage1_model.py packages it", _language_model),
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


# The built-in backends, in the order of the module docstring.


def _parameters_text(rgb: np.ndarray, settings: Stage1Settings) -> str:
    """The stage-1 model's parameter text for image I (``read_parameters``, else the reader of the
    model folder: --stage1-model, else the shipped one), decoded under the parameter grammar unless
    the decoding is unconstrained (for a language model)."""
    config = settings.config
    read = config.read_parameters
    if read is None:
        folder = config.model_dir if config.model_dir is not None else default_stage1_model()
        if folder is None:
            raise InputFileError("--stage1-model", "--stage1 parameters needs a stage-1 model folder (--stage1-model "
                                                   "DIR); none ships with this install")
        read = settings.load_reader(folder)
    return read(rgb)


def _program_text(png: bytes, settings: Stage1Settings) -> str:
    """The code model's part program for image I (its prompt is jax3dc.prompt.CODE_PROMPT), decoded
    under the part-program grammar unless the decoding is unconstrained."""
    generate = settings.config.generate_program
    if generate is None:
        folder = settings.config.code_model_dir
        if folder is None:
            raise InputFileError("--code-model", "--stage1 code needs a code model checkpoint (--code-model DIR)")
        from jax3dc.predict.models import code_model  # lazy: jax and the grammars (1.5 s), see the module docstring

        decoding = settings.decoding
        generate = code_model(settings.load_model(folder), png, decoding.max_new_tokens, decoding.options.constrained)
    return generate(CODE_PROMPT)


def _from_parameters(image: Stage1Image, settings: Stage1Settings) -> Stage1:
    text = _parameters_text(image.rgb, settings)
    settings.write_text("parameters", "parameters.txt", text)  # kept even when it fails to run
    parts = stage1_from_parameters(text)
    settings.write_text("program", "program.txt", parts.program)
    return parts


def _from_code(image: Stage1Image, settings: Stage1Settings) -> Stage1:
    program = _program_text(image.png, settings)
    settings.write_text("program", "program.txt", program)  # kept even when it fails to run
    return stage1_from_program(program)


def _from_mesh(image: Stage1Image, settings: Stage1Settings) -> Stage1:
    return stage1_from_mesh(settings.argument, settings.config.mesh_up)


def _from_parts_dir(image: Stage1Image, settings: Stage1Settings) -> Stage1:
    return stage1_from_parts_dir(settings.argument)


_SLOTS_READERS: dict[Path, Callable] = {}  # folder -> reader: a batch of images loads (and compiles) it once


def stage1_from_slots(slots: list, where: str) -> Stage1:
    """Box parts (ids 1..N in slot order, named ``<kind>_<id>``) of a slots network's kept slots
    (jax3dc.stage1_slots.PartSlot); none kept is a Jax3dcError naming ``where``. A photo gives no
    metric size, so the object is taken as 1 m across (``--scale`` says otherwise)."""
    if not slots:
        raise Jax3dcError(f"{where}: the slots network found no part in the image (no slot reached its exists "
                          "threshold); slots.json holds what it wrote")
    parts = {pid: trimesh.creation.box(extents=slot.extent, transform=trimesh.transformations.translation_matrix(
             slot.centre)) for pid, slot in enumerate(slots, start=1)}
    normalised, scale = _normalised(parts, where)
    names = {pid: f"{slot.kind}_{pid}" for pid, slot in enumerate(slots, start=1)}
    return Stage1(normalised, names, scale, SLOTS, metres_per_nu=1.0)


def _from_slots(image: Stage1Image, settings: Stage1Settings) -> Stage1:
    folder = settings.config.slots_model_dir
    if folder is None:
        raise InputFileError("--slots-model", "--stage1 slots needs a slots-network folder (--slots-model DIR, as "
                                              "recipes/stage1_slots.py packages it)")
    key = Path(folder).resolve()
    if key not in _SLOTS_READERS:
        from jax3dc.stage1_slots import load_slots_reader  # lazy: jax (2 s), see the module docstring

        _SLOTS_READERS[key] = load_slots_reader(folder)
    slots = _SLOTS_READERS[key](image.rgb)
    doc = {"slots_model": str(folder), "parts": [{"id": pid, **slot.to_dict()} for pid, slot in enumerate(slots, 1)]}
    settings.write_text("slots", "slots.json", json.dumps(doc, indent=1) + "\n")  # kept when no part is found
    return stage1_from_slots(slots, image.where)


register_backend(Stage1Backend(PARAMETERS, "a stage-1 model (--stage1-model; default: the shipped one) writes a "
                             "factory's parameters, run into parts", _from_parameters, reads_image=True))
register_backend(Stage1Backend(CODE, "the code model (--code-model) writes a part program, run by the interpreter",
                               _from_code, reads_image=True))
register_backend(Stage1Backend(MESH, "a part-segmented mesh: a GLB with one node per part, or an OBJ with one group "
                               "per part", _from_mesh, argument="FILE"))
register_backend(Stage1Backend(PARTS, "ground-truth parts, a folder of <id>.obj: stage 2 alone", _from_parts_dir,
                               argument="DIR"))
register_backend(Stage1Backend(SLOTS, "the slots network (--slots-model) writes the object's parts as boxes with "
                               "kinds, whatever its category", _from_slots, reads_image=True))
