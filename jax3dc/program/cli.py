"""`jax3dc program ...`: check, run and export part programs (SPEC §6) from the command line."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from jax3dc.cli_args import command_group, positive_float, positive_int
from jax3dc.errors import InputFileError
from jax3dc.program.blender import to_blender_script
from jax3dc.program.interpreter import DEFAULT_MAX_SECONDS, DEFAULT_MAX_TRIANGLES, Budget, run_program
from jax3dc.program.reference import language_reference
from jax3dc.program.syntax import MAX_PROGRAM_CHARS

MESH_FORMATS = ("obj", "stl", "ply", "glb")


def _read(path: str) -> str:
    """The program text; a file too long to be a program is refused without reading it whole."""
    limit = 4 * MAX_PROGRAM_CHARS  # UTF-8 takes at most 4 bytes a character
    try:
        with open(path, "rb") as f:
            data = f.read(limit + 1)
        if len(data) > limit:
            raise InputFileError(path, f"the file is over {limit} bytes; a program has at most "
                                       f"{MAX_PROGRAM_CHARS} characters")
        return data.decode("utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputFileError(path, f"cannot read the program: {getattr(exc, 'strerror', None) or exc}") from None


def _write(path: Path, text: str) -> None:
    try:
        path.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise InputFileError(path, f"cannot write: {exc.strerror or exc}") from None


def _budget(args: argparse.Namespace) -> Budget:
    return Budget(max_seconds=args.max_seconds, max_triangles=args.max_triangles)


def _run(args: argparse.Namespace) -> int:
    result = run_program(_read(args.program), _budget(args))
    for pid, mesh in result.parts.items():
        material = result.materials.get(pid)
        family = material.family if material else "-"
        print(f"{pid:4d}  {result.names[pid]:<24s} {family:<9s} {len(mesh.faces):7d} triangles"
              f"  watertight={mesh.is_watertight}")
    if args.out is None:
        return 0
    out = Path(args.out)
    try:
        out.mkdir(parents=True, exist_ok=True)
        for pid, mesh in result.parts.items():
            mesh.export(out / f"{pid}.{args.format}")
    except OSError as exc:
        raise InputFileError(out, f"cannot write the part meshes: {exc.strerror or exc}") from None
    meta = {str(pid): {"name": result.names[pid],
                       "material": ({"family": m.family, "desc": m.desc} if (m := result.materials.get(pid)) else None)}
            for pid in result.parts}
    _write(out / "parts.json", json.dumps(meta, indent=1, sort_keys=True))
    print(f"wrote {len(result.parts)} part meshes and parts.json to {out}")
    return 0


def _blender(args: argparse.Namespace) -> int:
    script = to_blender_script(_read(args.program), _budget(args))
    if args.output:
        _write(Path(args.output), script)
        print(f"wrote {args.output}; run it with: blender --background --python {args.output}")
    else:
        print(script, end="")
    return 0


def _reference(_args: argparse.Namespace) -> int:
    print(language_reference(), end="")
    return 0


def _budget_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--max-seconds", type=positive_float, default=DEFAULT_MAX_SECONDS,
                        help=f"time budget in seconds (default: {DEFAULT_MAX_SECONDS:g})")
    parser.add_argument("--max-triangles", type=positive_int, default=DEFAULT_MAX_TRIANGLES,
                        help=f"triangle budget: built and emitted triangles (default: {DEFAULT_MAX_TRIANGLES})")


def register(subparsers: argparse._SubParsersAction) -> None:
    group = command_group(
        subparsers, "program", help="check, run and export part programs",
        description="Part programs describe an object part by part with predefined shape functions "
                    "(see `jax3dc program reference`). They are interpreted, never executed as Python.")

    run = group.add_parser(
        "run", help="run a program: list its parts, optionally write one mesh per part",
        description="Run a part program and list its parts. With --out, write <id>.<format> per part "
                    "and parts.json (names, materials). Example: jax3dc program run chair.py --out parts/")
    run.add_argument("program", help="the part program file (Python syntax)")
    run.add_argument("--out", help="folder for the part meshes (created if missing)")
    run.add_argument("--format", choices=MESH_FORMATS, default="obj", help="mesh file format (default: obj)")
    _budget_arguments(run)
    run.set_defaults(func=_run)

    blender = group.add_parser(
        "blender", help="write the program as a Blender Python script",
        description="Translate a part program into a Blender (bpy/bmesh) script that builds the same "
                    "parts as named objects. The program is run first under the same budget as `program run`, so a "
                    "script is written only for a program that runs. Example: jax3dc program blender chair.py -o chair_bpy.py")
    blender.add_argument("program", help="the part program file")
    blender.add_argument("-o", "--output", help="script file to write (default: print to stdout)")
    _budget_arguments(blender)
    blender.set_defaults(func=_blender)

    ref = group.add_parser("reference", help="print the language reference",
                           description="Print every predefined function with its arguments.")
    ref.set_defaults(func=_reference)
