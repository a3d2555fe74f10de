"""Stage 1 (f_geo) at inference: one triangle mesh per part, in the normalised frame (SPEC §1).

Backends:
* ``code``: a part program (written by the code model from the image, or handed in) runs in the
  interpreter (parsed, never exec-ed) into part meshes with semantic names (the program's materials
  are not used: materials are stage 2's to predict, from the image);
* ``mesh:FILE``: a part-segmented mesh from any tool (see :mod:`eval.predict.mesh_input`).

Either way the parts are then centred with largest extent 1 (``normalise_parts``); the factor is
kept as the scale (mesh: file units per nu, metres for a mesh in metres).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import trimesh

from eval.predict.mesh_input import load_segmented_mesh
from jax3dc.errors import InputFileError, ProgramError
from jax3dc.geometry.parts import normalise_parts
from jax3dc.program.interpreter import run_program

CODE = "code"
MESH_PREFIX = "mesh:"


@dataclass(frozen=True)
class Stage1:
    """The parts of one image: meshes (nu), names by part id, and where they came from."""

    parts: dict[int, trimesh.Trimesh]
    names: dict[int, str]
    scale: float  # source units per nu
    source: str  # "code" or the mesh file's path
    program: str | None = None


def parse_stage1(spec: str) -> str | Path:
    """``code`` -> "code"; ``mesh:FILE`` -> Path(FILE); anything else is an InputFileError."""
    if spec == CODE:
        return CODE
    if spec.startswith(MESH_PREFIX) and len(spec) > len(MESH_PREFIX):
        return Path(spec[len(MESH_PREFIX):])
    raise InputFileError(spec, "--stage1 must be `code` or `mesh:FILE` "
                               "(a GLB with one node per part, or an OBJ with groups)")


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


def stage1_from_program(text: str) -> Stage1:
    """Runs a part program; a program that fails raises ProgramError naming the line."""
    result = run_program(text)
    try:
        parts, scale = normalise_parts(result.parts)
    except ValueError as e:
        raise ProgramError(None, f"the program's parts have no normalised frame: {e}") from None
    return Stage1(parts, dict(result.names), scale, CODE, text)
