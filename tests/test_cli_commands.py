"""The `jax3dc` parser loads the commands of the packages above the core only where they are
asked for: a core command's call runs no evaluation, data or training code, while the help and an
unknown command's error still list every command."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

ABOVE_CORE = ("data_pipeline", "train", "eval")
PROBE = f"""
import json, sys
from jax3dc.cli import build_parser
parser = build_parser(sys.argv[1:])
commands = sorted(parser._subparsers._group_actions[0].choices)
loaded = sorted({{m.split(".")[0] for m in sys.modules}} & set({list(ABOVE_CORE)!r}))
print(json.dumps([commands, loaded]))
"""


def _probe(*argv: str) -> tuple[list[str], list[str]]:
    """(the parser's commands, the packages above the core imported) for ``jax3dc ARGV``, in a fresh process."""
    out = subprocess.run([sys.executable, "-c", PROBE, *argv], capture_output=True, text=True, check=True).stdout
    commands, loaded = json.loads(out)
    return commands, loaded


@pytest.mark.parametrize("argv", [("predict", "image.png", "--out", "o"), ("export", "--help"), ("view", "o")])
def test_a_core_command_loads_nothing_above_the_core(argv):
    commands, loaded = _probe(*argv)
    assert loaded == []
    assert "predict" in commands and "eval" not in commands


@pytest.mark.parametrize("argv, package", [(("eval", "run", "--help"), "eval"), (("data", "build"), "data_pipeline"),
                                           (("physics", "sweep", "--help"), "eval")])
def test_a_command_above_the_core_loads_its_own_package(argv, package):
    commands, loaded = _probe(*argv)
    assert package in loaded and "train" not in loaded
    assert argv[0] in commands


@pytest.mark.parametrize("argv", [(), ("--help",), ("-h", "predict"), ("no-such-command",)])
def test_help_and_unknown_commands_list_every_command(argv):
    commands, _ = _probe(*argv)
    assert {"data", "demo", "eval", "train", "predict", "physics", "export"} <= set(commands)
