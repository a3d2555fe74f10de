"""One object's physics verdicts (SPEC §8) as ``choose`` and ``repair`` use them, and their order.

Verdicts run with the dynamics (limit reachability and the gravity test) by default: on a 2-core
CPU (``bench/verified_cost.py``, the demo build's 19 test records) a verdict takes 0.85 s on average
(0.17-2.1 s) and only 13 % of it is the C MuJoCo rollouts; the rest is the collision decomposition
and the crossing checks, which the kinematic verdict needs anyway. Dropping the dynamics would save
little and lose the checks that catch unreachable limits and objects that fall over.
"""

from __future__ import annotations

from dataclasses import dataclass

import trimesh

from jax3dc.physics.findings import Verdict
from jax3dc.physics.verdict import verdict_with_curves
from jax3dc.structure import Structure, to_json


@dataclass(frozen=True)
class Physics:
    """What a verdict needs beside the structure (one object's meshes, nu) and how it runs.

    ``backend``: "c" (C MuJoCo, for CPUs) or "mjx"; ``threads``: C rollout threads (None: every
    core; fewer when objects are checked in parallel processes).
    """

    parts: dict[int, trimesh.Trimesh]
    scale: float
    mounted: bool
    backend: str = "c"
    dynamics: bool = True
    threads: int | None = None

    def verdict(self, structure: Structure) -> Verdict:
        return verdict_with_curves(structure, self.parts, self.scale, self.backend, self.dynamics,
                                   self.mounted, self.threads)[0]


class VerdictCache:
    """Verdicts by canonical JSON, so a structure sampled (or tried) twice is checked once."""

    def __init__(self, physics: Physics):
        self.physics = physics
        self._seen: dict[str, Verdict] = {}

    def __call__(self, structure: Structure) -> Verdict:
        key = to_json(structure)
        if key not in self._seen:
            self._seen[key] = self.physics.verdict(structure)
        return self._seen[key]

