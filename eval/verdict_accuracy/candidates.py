"""Candidate sets for best-of-K without a model: a correct structure and joint perturbations of it
(flipped axis, moved pivot, wrong type), as a sampler's wrong candidates look.

Used to compare the physics backends' choices (``tests/physics/test_physics_candidate_verdicts.py``)
and to time best-of-K verification (``bench/candidates_mjx.py``) on objects that have no predictions.
"""

from __future__ import annotations

import numpy as np
import trimesh

from eval.verdict_accuracy.mutations import mutations_of
from jax3dc.structure import Structure, to_json
from jax3dc.verify.select import Candidate

JOINT_KINDS = ("flipped axis", "pivot moved", "hinge-slide swapped")  # mutations that keep the tree


def sampled_candidates(structure: Structure, parts: dict[int, trimesh.Trimesh], k: int, seed: int) -> list[Candidate]:
    """Up to ``k`` distinct candidates in a seeded random order: the structure itself and ``k`` − 1
    perturbations drawn from every joint's (each changes one joint); log-probabilities are drawn,
    so the likelihood tie-break falls either way. Fewer when there are too few joints to perturb."""
    if k < 1:
        raise ValueError(f"k must be at least 1, got {k}")
    rng = np.random.default_rng(seed)
    single = [m.structure for m in mutations_of(structure, parts) if m.kind in JOINT_KINDS]
    order = rng.permutation(len(single))
    chosen = [single[i] for i in order[:k - 1]]
    texts = list(dict.fromkeys([to_json(structure)] + [to_json(s) for s in chosen]))
    rng.shuffle(texts)
    return [Candidate(t, float(rng.normal(-50.0, 5.0))) for t in texts]
