"""The ``jax3dc data`` command group.

Each module in SUBCOMMAND_MODULES has ``register(subparsers)`` that adds its ``jax3dc data ...``
subcommands and sets ``func(args) -> int`` on them; add a module to the tuple to add commands.
"""

from __future__ import annotations

import argparse
import importlib

from jax3dc.cli_args import command_group

SUBCOMMAND_MODULES: tuple[str, ...] = (
    "data_pipeline.convert_cli",
    "data_pipeline.build_cli",
    "data_pipeline.tokenizer_cli",
    "data_pipeline.restyle_cli",
)


def register(subparsers: argparse._SubParsersAction) -> None:
    group = command_group(
        subparsers, "data",
        help="convert, build and inspect datasets",
        description="Dataset commands: convert source objects (URDF, MJCF) into structure + part "
        "meshes, and more. Run `jax3dc data SUBCOMMAND --help` for each.",
    )
    for name in SUBCOMMAND_MODULES:
        importlib.import_module(name).register(group)
