"""Multi-object partition metrics: hand-worked scene, and an independent pairwise implementation."""

import itertools

import numpy as np
import pytest

from eval.metrics.partition import object_labels, partition_scores
from eval.metrics.score import Case, evaluate
from eval_structures import structure

CEN = {i: (0.3 * i, 0.0, 0.0) for i in range(1, 10)}

# reference objects {1,2,3} {4,5} {6}; prediction {1,2} {3,4,5} {6}
REF = structure({1: None, 2: 1, 3: 1, 4: None, 5: 4, 6: None})
PRED = structure({1: None, 2: 1, 3: None, 4: 3, 5: 4, 6: None})


def test_object_labels_follow_parent_chains_to_the_root():
    assert object_labels(PRED).tolist() == [1, 1, 3, 3, 3, 6]
    assert object_labels(REF).tolist() == [1, 1, 1, 4, 4, 6]


def test_partition_hand_worked():
    s = partition_scores(object_labels(PRED), object_labels(REF))
    # contingency: {1,2}->ref A 2; {3,4,5}->ref A 1, ref B 2; {6}->ref C 1
    # Hungarian: 2 + 2 + 1 = 5 of 6 nodes
    assert s.cluster_accuracy == pytest.approx(5 / 6)
    # same-object pairs: ref C(3,2)+C(2,2) = 4, pred 1 + 3 = 4, both: (1,2) and (4,5) = 2
    assert (s.pair_tp, s.pair_pred, s.pair_ref) == (2, 4, 4)
    # agreements out of C(6,2) = 15: same on both 2 + different on both (15 - 4 - 4 + 2 = 9) = 11
    assert s.rand_index == pytest.approx(11 / 15)
    assert (s.pred_objects, s.ref_objects, s.full_match) == (3, 3, False)

    m = evaluate([Case("scene", REF, CEN, PRED), Case("single", structure({1: None, 2: 1}), CEN,
                                                      structure({1: None, 2: None}))]).metrics
    # only the reference with more than one root is a scene
    assert m["counts"]["scenes"] == 1
    assert m["objects_per_scene"] == 3 and m["objects_per_scene_ref"] == 3
    assert m["count_match"] == 100.0 and m["full_partition"] == 0.0
    assert m["cluster_acc"] == pytest.approx(500 / 6)
    assert m["rand_index"] == pytest.approx(1100 / 15)
    assert m["pair_precision"] == m["pair_recall"] == m["pair_f1"] == pytest.approx(50.0)


def _independent(pred, ref):
    """Straight loops: Rand index over pairs; cluster accuracy by trying every injective mapping."""
    n = len(pred)
    agree = sum((pred[i] == pred[j]) == (ref[i] == ref[j]) for i, j in itertools.combinations(range(n), 2))
    rand = agree / (n * (n - 1) / 2)
    p_ids, r_ids = sorted(set(pred)), sorted(set(ref))
    best = 0
    if len(p_ids) <= len(r_ids):
        for perm in itertools.permutations(r_ids, len(p_ids)):
            mapping = dict(zip(p_ids, perm))
            best = max(best, sum(mapping[p] == r for p, r in zip(pred, ref)))
    else:
        for perm in itertools.permutations(p_ids, len(r_ids)):
            mapping = dict(zip(perm, r_ids))
            best = max(best, sum(mapping.get(p) == r for p, r in zip(pred, ref)))
    return rand, best / n


def test_rand_index_and_cluster_accuracy_agree_with_an_independent_implementation():
    rng = np.random.default_rng(11)
    for _ in range(300):
        n = int(rng.integers(2, 9))
        pred = rng.integers(0, int(rng.integers(1, 5)), size=n)
        ref = rng.integers(0, int(rng.integers(1, 5)), size=n)
        s = partition_scores(pred, ref)
        rand, acc = _independent(pred.tolist(), ref.tolist())
        assert s.rand_index == pytest.approx(rand)
        assert s.cluster_accuracy == pytest.approx(acc)
        same = lambda lab: {(i, j) for i, j in itertools.combinations(range(n), 2) if lab[i] == lab[j]}
        assert s.pair_tp == len(same(pred) & same(ref))
        assert s.full_match == (s.rand_index == 1.0)
