"""The `jax3dc` command: one parser, subcommands registered by each area of the project.

Each command module has ``register(subparsers)`` which adds its subcommands and sets
``func(args) -> int`` on them. The core's modules are imported here; the packages built on the
core (data, train, eval, demo) declare theirs as entry points of the group ``jax3dc.commands`` in
pyproject.toml, found at run time, so the core names none of them. Errors from bad input
(Jax3dcError) are caught here once: one line on stderr, exit code 1.
"""

from __future__ import annotations

import argparse
import logging
import sys
import warnings
from importlib.metadata import entry_points

from jax3dc.errors import Jax3dcError, shorten
# importing the package chose the headless GL backend (jax3dc/__init__.py) before the command
# modules below, some of which import mujoco, which reads MUJOCO_GL only then
from jax3dc import structure_cli  # noqa: E402
from jax3dc.edits import cli as edits_cli  # noqa: E402
from jax3dc.export import cli as export_cli  # noqa: E402
from jax3dc.physics import cli as physics_cli  # noqa: E402
from jax3dc.predict import cli as predict_cli  # noqa: E402
from jax3dc.program import cli as program_cli  # noqa: E402
from jax3dc.serve import cli as serve_cli  # noqa: E402
from jax3dc.viewer import cli as viewer_cli  # noqa: E402

CORE_COMMANDS = (program_cli, structure_cli, export_cli, physics_cli, predict_cli, edits_cli, viewer_cli, serve_cli)
COMMAND_GROUP = "jax3dc.commands"  # entry-point group of the commands of the packages above the core


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


def _entry_command(entry_name: str) -> str:
    """The top-level command an entry point adds to: ``eval`` adds ``eval``; ``physics-sweep`` adds
    a subcommand to the core's ``physics``."""
    return entry_name.split("-", 1)[0]


def build_parser(argv: list[str] | None = None) -> argparse.ArgumentParser:
    """The parser of ``argv``'s command: the core's commands and, of the packages above the core,
    only the entry points that add to the command ``argv`` names, so that ``jax3dc predict`` loads
    no evaluation, data or training code. Every entry point loads when ``argv`` names no command
    or one nobody knows (the help and argparse's choices list them all)."""
    parser = _Parser(
        prog="jax3dc",
        description="One image in, a structured, articulated, simulation-ready 3D object out.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module in CORE_COMMANDS:
        module.register(sub)
    entries = sorted(entry_points(group=COMMAND_GROUP), key=lambda e: e.name)
    argv = sys.argv[1:] if argv is None else argv
    named = argv[0] if argv and not argv[0].startswith("-") else None  # the command comes first
    wanted = [e for e in entries if _entry_command(e.name) == named]
    for entry in wanted if wanted or named in sub.choices else entries:
        entry.load()(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser(argv)
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
