"""A recipe as data: the calls of a trainer that made a shipped model, each a typed frozen config.

A config's fields are the trainer's flags (``None`` leaves the trainer's default), so the recipe of a
release reads as its settings and runs through the same command line a person types. Paths that
differ between hosts are named, not written: ``Data("D-0")`` is a folder under ``--data``,
``Earlier("c")`` the packaged folder of an earlier call of the same recipe, ``Work("metrics.jsonl")``
a file under ``--out``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar, Union


@dataclass(frozen=True)
class Data:
    """A dataset folder under the run's ``--data`` root (built or imported beforehand)."""

    name: str


@dataclass(frozen=True)
class Earlier:
    """The packaged model of an earlier call of the same recipe (its ``--out`` folder's package)."""

    call: str


@dataclass(frozen=True)
class Work:
    """A file the calls share under the run's ``--out`` folder (e.g. a cache)."""

    name: str


Path_ = Union[str, Data, Earlier, Work]


@dataclass(frozen=True)
class Share:
    """A dataset folder trained at its own share of examples (``recipes.release_model --mix DIR=SHARE``)."""

    path: Path_
    share: float


@dataclass(frozen=True)
class StructureCall:
    """One call of ``recipes.release_model`` (the structure model)."""

    trainer: ClassVar[str] = "recipes.release_model"
    package: ClassVar[str] = "release"
    init: Path_ | None = None
    tokenizer: Path_ | None = None
    objects: int | None = None
    scenes: int | None = None
    views: int | None = None
    augment: bool | None = None
    appearance: str | None = None
    image_size: int | None = None
    real: Path_ | None = None
    real_weight: float | None = None
    mix: tuple[Share, ...] = ()
    fuse_handles: bool | None = None
    pivot_frame: str | None = None
    steps: int | None = None
    batch: int | None = None
    lr: float | None = None
    heldout: Path_ | None = None
    fixtures: Path_ | None = None
    heldout_varied: Path_ | None = None
    fixtures_varied: Path_ | None = None
    compare: Path_ | None = None
    set: tuple[str, ...] = ()  # `jax3dc train --set` overrides, one flag each


@dataclass(frozen=True)
class Stage1NetCall:
    """One call of ``recipes.stage1_net`` (the stage-1 image network)."""

    trainer: ClassVar[str] = "recipes.stage1_net"
    package: ClassVar[str] = "stage1"
    data: tuple[Path_, ...] = ()
    init: Path_ | None = None
    image_size: int | None = None
    widths: tuple[int, ...] | None = None
    blocks: int | None = None
    hidden: int | None = None
    batch: int | None = None
    lr: float | None = None
    steps: int | None = None
    minutes: float | None = None
    number_weight: float | None = None
    box_weight: float | None = None
    discrete_weight: float | None = None
    box_cache: Path_ | None = None
    compare: Path_ | None = None


Call = Union[StructureCall, Stage1NetCall]
REPEATED_FLAGS = ("mix", "set")  # fields whose values each take the flag again (argparse's append)


@dataclass(frozen=True)
class Recipe:
    """A shipped model's recipe: its calls in order, by name (a later call may start from an
    earlier one's package), and the release it made."""

    release: str
    calls: tuple[tuple[str, Call], ...]


def resolve(value: Path_, data: Path, out: Path, package: str) -> str:
    """A path field as the trainer reads it on this host."""
    if isinstance(value, Data):
        return str(data / value.name)
    if isinstance(value, Earlier):
        return str(out / value.call / package)
    if isinstance(value, Work):
        return str(out / value.name)
    return value


def flags(call: Call, data: Path, out: Path) -> list[str]:
    """The trainer's command line for ``call``: each set field as ``--field-name VALUE...``; a
    boolean as ``--name`` / ``--no-name``."""
    argv: list[str] = []
    for field in dataclasses.fields(call):
        value = getattr(call, field.name)
        flag = "--" + field.name.replace("_", "-")
        if value is None or value == ():
            continue
        if isinstance(value, bool):
            argv.append(flag if value else f"--no-{field.name.replace('_', '-')}")
        elif field.name in REPEATED_FLAGS:
            for v in value:
                argv += [flag, f"{resolve(v.path, data, out, call.package)}={v.share:g}" if isinstance(v, Share) else v]
        elif isinstance(value, tuple):
            argv += [flag, *(resolve(v, data, out, call.package) if not isinstance(v, int) else str(v) for v in value)]
        else:
            argv += [flag, resolve(value, data, out, call.package) if not isinstance(value, (int, float)) else
                     f"{value:g}" if isinstance(value, float) else str(value)]
    return argv
