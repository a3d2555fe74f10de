"""Run a shipped model's recipe by name: each call of ``recipes/configs/NAME.py`` in order, into
``OUT/<call>``, through its trainer's command line.

    python3 -m recipes.run structure_release4 --out runs/release4 --data .carry
    python3 -m recipes.run stage1_release5 --out runs/stage1 --data runs/builds --print

``--print`` shows the trainer commands without running them. A recipe's trainers resume, so a
call cut short is finished by running the same command again.
"""

from __future__ import annotations

import argparse
import importlib
import shlex
from collections.abc import Sequence
from pathlib import Path

from recipes.configs import NAMES, recipe
from recipes.recipe import flags


def commands(name: str, out: Path, data: Path) -> list[tuple[str, list[str]]]:
    """(trainer module, argv) of each call of recipe ``name``."""
    return [(call.trainer, ["--out", str(out / label), *flags(call, data, out)]) for label, call in recipe(name).calls]


def main(argv: Sequence[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("name", choices=NAMES, help="the recipe (a module of recipes/configs)")
    p.add_argument("--out", required=True, help="folder of the run; call C writes OUT/C")
    p.add_argument("--data", default=".", help="folder holding the datasets the recipe names")
    p.add_argument("--print", action="store_true", help="print the trainer commands, run nothing")
    a = p.parse_args(argv)
    for trainer, args in commands(a.name, Path(a.out), Path(a.data)):
        print(f"python3 -m {trainer} {shlex.join(args)}", flush=True)
        if not a.print:
            importlib.import_module(trainer).main(args)


if __name__ == "__main__":
    main()
