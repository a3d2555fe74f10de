"""Stage 1 (f_geo) at inference: one triangle mesh per part, in the normalised frame (SPEC §1).

Backends:
* ``parameters``: a stage-1 model reads the image and writes a factory's category and parameters
  (``jax3dc.parameters``, one line); the factory runs them into parts with ids 1..N, semantic
  names and a metric scale (``jax3dc.factories.run_parameters``). The default when a stage-1 model
  ships (``jax3dc/release/stage1/``);
* ``code``: a part program (written by the code model from the image, or handed in) runs in the
  interpreter (parsed, never exec-ed) into part meshes with semantic names (the program's materials
  are not used: materials are stage 2's to predict, from the image);
* ``mesh:FILE``: a part-segmented mesh from any tool (see :mod:`jax3dc.predict.mesh_input`);
* ``parts:DIR``: ground-truth parts, a folder of ``<id>.obj`` (``.stl``, ``.ply``, ``.glb``) as
  ``jax3dc.geometry.parts`` writes it (a dataset object's parts, or a previous prediction's
  ``parts/``): stage 2 alone, for evaluation.

Either way the parts are centred with largest extent 1 (``normalise_parts``; a factory's already
are); the factor is kept as the scale (mesh: file units per nu, metres for a mesh in metres;
parameters: metres per nu).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import trimesh

from jax3dc.errors import InputFileError, ProgramError
from jax3dc.factories.registry import SCHEMAS, run_parameters
from jax3dc.geometry.parts import load_parts, normalise_parts, part_boxes
from jax3dc.parameters import parse_parameters
from jax3dc.predict.mesh_input import load_segmented_mesh
from jax3dc.program.interpreter import run_program
from jax3dc.release import default_stage1_model
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
