"""One object's verified decoding: the verdict chooses among its candidates, then repairs a
failing winner, with one verdict cache so that the repair reuses the winner's verdict."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import trimesh

from jax3dc.structure import Box
from jax3dc.verify.repair import Repaired, repair
from jax3dc.verify.select import Candidate, Choice, choose
from jax3dc.verify.verdicts import Physics, VerdictCache


@dataclass(frozen=True)
class ObjectParts:
    """What verification needs of one object beside its candidates: the part meshes (nu), metres
    per nu, whether it is fixed in place in use, and the legend's part boxes."""

    parts: dict[int, trimesh.Trimesh]
    scale: float
    mounted: bool
    boxes: Mapping[int, Box]


@dataclass(frozen=True)
class Verified:
    key: str
    choice: Choice
    repaired: Repaired | None  # None: not asked, or the winner does not parse or already passes


def verify_object(key: str, candidates: Sequence[Candidate], obj: ObjectParts, fix: bool = True,
                  backend: str = "c", dynamics: bool = True, threads: int | None = None) -> Verified:
    """The winner of ``candidates`` and, with ``fix``, its repair when its verdict fails."""
    check = VerdictCache(Physics(obj.parts, obj.scale, obj.mounted, backend, dynamics, threads))
    choice = choose(candidates, obj.boxes, check)
    fixed = None
    if fix and choice.structure is not None and not choice.rows[choice.index].ok:
        fixed = repair(choice.structure, obj.boxes, check)
    return Verified(key, choice, fixed)
