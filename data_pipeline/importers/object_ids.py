"""Object ids for the sources of one import: readable, deterministic and unique.

An object's id names its records (``<category>/<object id>/<view>``), picks its split by hash and
keys the build's list of skipped objects, so two sources must never share one. Datasets repeat
file names by design (``a/microwave.xml`` and ``b/microwave.xml``, every ``mobility.urdf``), and a
user importing both expects both, so a shared name is told apart by the folders above it rather
than refused. A name that no other source shares keeps its plain form, which keeps the ids, keys
and hash splits of existing builds as they were.
"""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path

from jax3dc.errors import InputFileError

SEPARATOR = "__"
"""Joins parent folder names to the source's name ("/" would split a record key)."""


def _folders(path: Path) -> tuple[str, ...]:
    """Names of the folders holding ``path`` (an absolute path), outermost first."""
    return path.parent.parts[1:]


def _with_folders(path: Path, depth: int) -> str:
    return SEPARATOR.join([*_folders(path)[-depth:], path.name])


def object_ids(paths: list[Path]) -> list[str]:
    """One id per source path, in order: its file or folder name where no other source has that
    name, else the name behind the fewest parent folders that tell every source of that name apart
    (``a/microwave.xml``, ``b/microwave.xml`` -> ``a__microwave.xml``, ``b__microwave.xml``).

    InputFileError naming both paths when one source is given twice, or when two ids still clash
    (a folder that is itself called ``a__microwave.xml``).
    """
    resolved = [Path(p).resolve() for p in paths]
    first_given: dict[Path, Path] = {}
    for given, path in zip(paths, resolved):
        if path in first_given:
            raise InputFileError(given, f"the same source is given twice (also as {first_given[path]})")
        first_given[path] = Path(given)
    by_name: dict[str, list[int]] = defaultdict(list)
    for index, path in enumerate(resolved):
        by_name[path.name].append(index)
    ids = [path.name for path in resolved]
    for members in by_name.values():
        if len(members) < 2:
            continue
        deepest = max(len(_folders(resolved[i])) for i in members)
        depth = next(d for d in range(1, deepest + 1)
                     if len({_with_folders(resolved[i], d) for i in members}) == len(members))
        for i in members:
            ids[i] = _with_folders(resolved[i], depth)
    owner: dict[str, int] = {}
    for index, object_id in enumerate(ids):
        if object_id in owner:
            raise InputFileError(paths[index], f"its object id {object_id!r} is also the id of "
                                               f"{paths[owner[object_id]]}; rename one of them")
        owner[object_id] = index
    return ids
