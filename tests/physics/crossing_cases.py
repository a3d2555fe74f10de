"""The board-crossing check as the verdict runs it (``verdict.CheckRun.crossed``: a plan, its
queries answered in numpy, resolved), for tests that give their own joint sweeps."""

from __future__ import annotations

import numpy as np
import trimesh

from jax3dc.physics.crossing import crossing_plan, first_crossings
from jax3dc.structure.schema import Structure


def crossings(structure: Structure, parts: dict[int, trimesh.Trimesh], sweeps: dict[int, np.ndarray],
              pieces: dict[int, list[np.ndarray]] | None = None) -> dict[int, tuple[int, float]]:
    """Per jointed part of ``sweeps``: (other part, joint value) of its first crossing (``CrossingPlan.resolve``)."""
    plan = crossing_plan(structure, parts, sweeps, pieces)
    return plan.resolve(first_crossings(plan))
