"""The `jax3dc` command: one parser, subcommands registered by each area of the project.

Each module in COMMAND_MODULES has ``register(subparsers)`` which adds its subcommands and
sets ``func(args) -> int`` on them. Errors from bad input (Jax3dcError) are caught here once:
one line on stderr, exit code 1.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import sys
import warnings

from jax3dc.errors import Jax3dcError, shorten
from jax3dc.gl import configure_gl

# Modules are imported lazily by name so that `jax3dc validate` does not pay for importing jax.
COMMAND_MODULES: tuple[str, ...] = (
    "data_pipeline.cli",
    "jax3dc.program.cli",
    "jax3dc.structure_cli",
    "jax3dc.export.cli",
    "eval.cli",
    "train.cli",
    "eval.demo_cli",
    "eval.physics.cli",
    "eval.predict.cli",
    "jax3dc.viewer.cli",
)


def command_group(subparsers: argparse._SubParsersAction, name: str, **kwargs) -> argparse._SubParsersAction:
    """Adds a command that only holds subcommands and returns their subparsers; given alone
    (``jax3dc NAME``) it prints its help and exits 2."""
    parser = subparsers.add_parser(name, **kwargs)

    def usage(_args: argparse.Namespace) -> int:
        parser.print_help()
        return 2

    parser.set_defaults(func=usage)
    return parser.add_subparsers(dest=f"{name}_command", metavar="SUBCOMMAND")


def positive_int(text: str) -> int:
    """argparse type of counts that must be at least 1 (batch sizes, workers)."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {text!r}")
    return value


def positive_float(text: str) -> float:
    """argparse type of rates that must be above 0 (temperature, top-p)."""
    try:
        value = float(text)
    except ValueError:
        value = 0.0
    if not value > 0 or value != value or value == float("inf"):
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}")
    return value


class _Parser(argparse.ArgumentParser):
    """argparse, with its error messages cut to one readable line (they echo the argument given)."""

    def error(self, message: str):
        super().error(shorten(message))


RECURSION_LIMIT = 20_000
"""Python's default (1000) is below a legitimate 1000-deep parent chain; pure-Python recursion
costs no C stack on 3.11, and deeper input is refused as a RecursionError, one line."""


def _quiet_library_noise() -> None:
    """numpy floating-point and trimesh warnings would print before the error line that explains
    them; the project checks finiteness itself and says what went wrong."""
    warnings.filterwarnings("ignore", message=r"(overflow|invalid value|divide by zero|underflow) encountered",
                            category=RuntimeWarning)
    logging.getLogger("trimesh").setLevel(logging.ERROR)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="jax3dc",
        description="One image in, a structured, articulated, simulation-ready 3D object out.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    configure_gl()  # before the command modules: some import mujoco, which reads MUJOCO_GL only then
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    _quiet_library_noise()
    sys.setrecursionlimit(max(sys.getrecursionlimit(), RECURSION_LIMIT))
    try:
        return int(args.func(args) or 0)
    except Jax3dcError as e:
        return _fail(args, str(e))
    except RecursionError:
        return _fail(args, "the input is nested too deeply (parent chains, JSON or XML nesting)")
    except MemoryError:
        return _fail(args, "out of memory: the input is too large for this machine")
    except OSError as e:
        # A file the user named could not be opened or written (a missing output folder, no permission).
        where = e.filename if e.filename is not None else "file"
        return _fail(args, f"{where}: {e.strerror or e}")
    except KeyboardInterrupt:
        print(f"jax3dc {args.command}: interrupted", file=sys.stderr)
        return 130


def _fail(args: argparse.Namespace, message: str) -> int:
    print(f"jax3dc {args.command}: error: {shorten(message)}", file=sys.stderr)
    return 1


if __name__ == "__main__":
    sys.exit(main())
