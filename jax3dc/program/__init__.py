"""Part programs (SPEC §6): parsed and interpreted, never executed.

`run_program(text)` turns a program into part meshes; `to_blender_script(text)` writes the
same program as a Blender Python script. The language is described in `syntax.py` (what is
accepted) and `library.py` (the predefined functions).
"""

from jax3dc.program.blender import to_blender_script
from jax3dc.program.interpreter import (
    DEFAULT_MAX_SECONDS,
    DEFAULT_MAX_STEPS,
    DEFAULT_MAX_TRIANGLES,
    Budget,
    ProgramResult,
    run_program,
)
from jax3dc.program.library import FUNCTIONS
from jax3dc.program.reference import language_reference
from jax3dc.program.syntax import parse_program

__all__ = [
    "Budget", "DEFAULT_MAX_SECONDS", "DEFAULT_MAX_STEPS", "DEFAULT_MAX_TRIANGLES", "FUNCTIONS",
    "ProgramResult", "language_reference", "parse_program", "run_program", "to_blender_script",
]
