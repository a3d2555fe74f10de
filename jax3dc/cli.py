"""The `jax3dc` command: one parser, subcommands registered by each area of the project.

Each module in COMMAND_MODULES has ``register(subparsers)`` which adds its subcommands and
sets ``func(args) -> int`` on them. Errors from bad input (Jax3dcError) are caught here once:
one line on stderr, exit code 1.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from jax3dc.errors import Jax3dcError
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


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
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
    try:
        return int(args.func(args) or 0)
    except Jax3dcError as e:
        print(f"jax3dc {args.command}: error: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"jax3dc {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
