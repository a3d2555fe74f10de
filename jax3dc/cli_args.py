"""What every command module's ``register(subparsers)`` shares: command groups and argument types.

Apart from ``jax3dc.cli`` so that the command modules, which ``jax3dc.cli`` imports, do not import it back.
"""

from __future__ import annotations

import argparse


def command_group(subparsers: argparse._SubParsersAction, name: str, **kwargs) -> argparse._SubParsersAction:
    """Adds a command that only holds subcommands and returns their subparsers; given alone
    (``jax3dc NAME``) it prints its help and exits 2. Asked again for a group that exists, it
    returns that group's subparsers, so another package can add a subcommand to it (evaluation's
    ``physics sweep`` joins the core's ``physics``)."""
    if name in subparsers.choices:
        return subparsers.choices[name].subcommands
    parser = subparsers.add_parser(name, **kwargs)

    def usage(_args: argparse.Namespace) -> int:
        parser.print_help()
        return 2

    parser.set_defaults(func=usage)
    parser.subcommands = parser.add_subparsers(dest=f"{name}_command", metavar="SUBCOMMAND")
    return parser.subcommands


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
