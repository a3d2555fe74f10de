"""One object's physics verdicts (SPEC §8) as ``choose`` and ``repair`` use them, and their order.

Verdicts run with the dynamics (limit reachability and the gravity test) by default: on a 2-core
CPU (``bench/verified_cost.py``, the demo build's 19 test records) a verdict takes 0.85 s on average
(0.17-2.1 s) and only 13 % of it is the C MuJoCo rollouts; the rest is the collision decomposition
and the crossing checks, which the kinematic verdict needs anyway. Dropping the dynamics would save
little and lose the checks that catch unreachable limits and objects that fall over.

With backend "mjx" the structures asked for together (``VerdictCache.many``: the candidates of
``choose``, the alternatives ``repair`` tries for one joint) are checked together, their
interpenetration sweeps in one MJX launch (``physics.candidate_verdicts``); with "c" one by one.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import trimesh

from jax3dc.physics.candidate_verdicts import candidate_verdicts
from jax3dc.physics.findings import Verdict
from jax3dc.physics.verdict import verdict_with_curves
from jax3dc.structure import Structure, to_json


@dataclass(frozen=True)
class Physics:
    """What a verdict needs beside the structure (one object's meshes, nu) and how it runs.

    ``backend``: "c" (C MuJoCo, for CPUs) or "mjx" (the interpenetration sweeps of the structures
    checked together in one MJX launch, the rollouts in C); ``threads``: C rollout threads (None:
    every core; fewer when objects are checked in parallel processes).
    """

    parts: dict[int, trimesh.Trimesh]
    scale: float
    mounted: bool
    backend: str = "c"
    dynamics: bool = True
    threads: int | None = None

    def __post_init__(self) -> None:
        if self.backend not in ("c", "mjx"):
            raise ValueError(f"physics backend must be 'c' or 'mjx', got {self.backend!r}")

    @property
    def batches(self) -> bool:
        """Whether checking structures together saves time (one MJX launch), so callers ask ahead."""
        return self.backend == "mjx"

    def verdict(self, structure: Structure) -> Verdict:
        return self.verdicts([structure])[0]

    def verdicts(self, structures: Sequence[Structure]) -> list[Verdict]:
        if self.batches:
            return candidate_verdicts(structures, self.parts, self.scale, self.mounted, self.dynamics, self.threads)
        return [verdict_with_curves(s, self.parts, self.scale, self.backend, self.dynamics, self.mounted,
                                    self.threads)[0] for s in structures]


class VerdictCache:
    """Verdicts by canonical JSON, so a structure sampled (or tried) twice is checked once."""

    def __init__(self, physics: Physics):
        self.physics = physics
        self._seen: dict[str, Verdict] = {}

    def __call__(self, structure: Structure) -> Verdict:
        return self.many([structure])[0]

    def many(self, structures: Sequence[Structure]) -> list[Verdict]:
        """The verdicts of ``structures`` in order; the distinct unseen ones are checked together."""
        keys = [to_json(s) for s in structures]
        todo = {k: s for k, s in zip(keys, structures) if k not in self._seen}
        self._seen.update(zip(todo, self.physics.verdicts(list(todo.values()))))
        return [self._seen[k] for k in keys]

