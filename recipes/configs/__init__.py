"""The shipped models' recipes, one module per release, each holding ``RECIPE``:
``python3 -m recipes.run NAME --out DIR --data DIR`` runs one."""

from __future__ import annotations

import importlib

from recipes.recipe import Recipe

NAMES: tuple[str, ...] = ("structure_release4", "structure_release5", "stage1_release5")


def recipe(name: str) -> Recipe:
    """The recipe called ``name``; an unknown name is one error naming the known ones."""
    if name not in NAMES:
        raise SystemExit(f"unknown recipe {name!r}; known: {', '.join(NAMES)}")
    return importlib.import_module(f"{__name__}.{name}").RECIPE
