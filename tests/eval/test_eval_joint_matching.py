"""Joint matching and gates: hand-worked cases, and agreement with brute force over permutations."""

import itertools
import math

import numpy as np
import pytest

from eval.metrics.joints import GATES, gate_matches, joint_rows, match_joints
from eval.metrics.score import Case, evaluate
from eval_structures import hinge, slide, structure


def _match(pred, ref, centroids):
    p, r = joint_rows([pred], [centroids]), joint_rows([ref], [centroids])
    m = match_joints(p, r)
    return sorted(zip(p.child[m.pred].tolist(), r.child[m.ref].tolist()))


def test_matching_prefers_the_nearer_axis_among_centroid_candidates():
    # Reference joint on part 3; predicted joints on parts 4 and 5, both within 0.1 nu of part 3
    # (distances 0.05 and 0.08), part 2 far away. Costs: (4,3) = 0.5 + 0 + 10 (axis tilted 0.5 rad,
    # lines cross at the origin), (5,3) = 0.1 + 0 + 10 -> part 5 is matched.
    cen = {1: (0, 0, 0), 2: (0.5, 0, 0), 3: (0, 0.3, 0), 4: (0, 0.35, 0), 5: (0.08, 0.3, 0)}
    ref = structure({1: None, 2: 1, 3: 1, 4: 1, 5: 1}, {3: hinge()})
    tilted = lambda t: hinge(axis=(math.sin(t), 0, math.cos(t)))
    pred = structure({1: None, 2: 1, 3: 1, 4: 1, 5: 1}, {4: tilted(0.5), 5: tilted(0.1)})
    assert _match(pred, ref, cen) == [(5, 3)]
    # presence F1 = 2 * 1 matched / (2 predicted + 1 reference) = 2/3
    e = evaluate([Case("k", ref, cen, pred)])
    assert e.metrics["presence_f1"] == pytest.approx(200 / 3)


def test_matching_maximises_matched_pairs_before_cost():
    # Reference joints on 3 and 6, predicted on 4 and 5. Candidates: (4,3), (4,6) and (5,3) by
    # centroid distance (<= 0.1); (5,6) is not. Costs: (4,3) = 10 + 0, (5,3) = 10 + 0.5,
    # (4,6) = 10 + 0.4. The cheapest single pair is (4,3), but {(4,6), (5,3)} matches both joints.
    cen = {1: (0, 0, 0), 2: (1, 1, 1), 3: (0.3, 0, 0), 4: (0.35, 0.05, 0), 5: (0.3, 0.07, 0), 6: (0.4, 0.1, 0)}
    parents = {1: None, 2: 1, 3: 1, 4: 1, 5: 1, 6: 1}
    pred = structure(parents, {4: hinge(), 5: hinge(axis=(math.sin(0.5), 0, math.cos(0.5)))})
    ref = structure(parents, {3: hinge(), 6: hinge(axis=(0, math.sin(0.4), math.cos(0.4)))})
    assert _match(pred, ref, cen) == [(4, 6), (5, 3)]


def test_same_child_wins_over_a_nearby_part():
    cen = {1: (0, 0, 0), 2: (0.3, 0, 0), 3: (0.32, 0, 0)}
    ref = structure({1: None, 2: 1, 3: 1}, {2: hinge(axis=(0, 0, 1))})
    pred = structure({1: None, 2: 1, 3: 1}, {2: hinge(axis=(1, 0, 0)), 3: hinge(axis=(0, 0, 1))})
    # (2,2) = pi/2 + line distance 0; (3,2) = 0 + 0 + 10: the shared child wins
    assert _match(pred, ref, cen) == [(2, 2)]


def test_gates_hand_worked():
    """Nine objects, one matched joint each; every gate is hit and the shares are worked out."""
    cen = {1: (0, 0, 0), 2: (0.5, 0, 0)}
    ref_h = hinge(pivot=(0.5, 0, 0), rng=(0.0, 1.5))
    ref_s = slide(pivot=(0, 0, 0), rng=(0.0, 0.4))
    t = 0.3
    cases = [  # (prediction, reference, expected gate)
        (slide(axis=(0, 0, 1), pivot=(0.5, 0, 0)), ref_h, "type"),
        (hinge(axis=(math.sin(t), 0, math.cos(t)), pivot=(0.5, 0, 0)), ref_h, "axis"),  # 0.3 > 0.25 rad
        (hinge(pivot=(0.5, 0.06, 0)), ref_h, "origin"),  # lines 0.06 > 0.05 apart
        (hinge(pivot=(0.5, 0.04, 0), rng=(1.6, 3.0)), ref_h, "limit"),  # no overlap with [0, 1.5]
        (hinge(pivot=(0.5, 0, 0), rng=(0.0, 3.2)), ref_h, "limit"),  # spans 3.2 vs 1.5: 1.7 > 1.6057
        (hinge(axis=(0, 0, -1), pivot=(0.5, 0, 0), rng=(-1.5, 0.0)), ref_h, "success"),  # flipped: [0, 1.5]
        (hinge(pivot=(0.5, 0, 0), rng=(0.5, 2.0)), ref_h, "success"),
        (slide(pivot=(5, 5, 5), rng=(0.0, 0.8)), ref_s, "success"),  # slides pass origin; 0.4 <= 0.5
        (slide(rng=(0.0, 1.0)), ref_s, "limit"),  # span difference 0.6 > 0.5 nu
    ]
    e = evaluate([
        Case(str(i), structure({1: None, 2: 1}, {2: r}), cen, structure({1: None, 2: 1}, {2: p}))
        for i, (p, r, _) in enumerate(cases)
    ])
    assert [row["matches"][0]["gate"] for row in e.rows] == [g for _, _, g in cases]
    m = e.metrics
    # shares over 9 matched joints: type 1, axis 1, origin 1, limit 3, success 3
    assert [m["fail_type"], m["fail_axis"], m["fail_origin"], m["fail_limit"], m["success"]] == pytest.approx(
        [100 / 9, 100 / 9, 100 / 9, 300 / 9, 300 / 9])
    assert m["type_acc"] == pytest.approx(800 / 9)
    assert m["axis_acc"] == pytest.approx(800 / 9)
    # hinge-hinge pairs (rows 2-7): line distances 0, 0.06, 0.04, 0, 0 (parallel), 0 -> 0.1 / 6
    assert m["pos_err"] == pytest.approx(0.1 / 6)
    # same-type pairs (rows 2-9): IoU 1, 1, 0, 1.5/3.2, 1, 1/2 ([0.5,1.5] over [0,2]), 0.4/0.8, 0.4/1.0
    assert m["range_iou"] == pytest.approx(100 * (1 + 1 + 0 + 1.5 / 3.2 + 1 + 0.5 + 0.5 + 0.4) / 8)
    assert sum(m[k] for k in ("fail_type", "fail_axis", "fail_origin", "fail_limit", "success")) == pytest.approx(100)


def _brute_force(pred_rows, ref_rows):
    """Best partial matching by enumeration: most candidate pairs, then least total cost.

    Costs are recomputed here independently of the module (arccos angle, explicit line formula).
    """
    def cost(i, j):
        a1, a2 = pred_rows.axis[i] / np.linalg.norm(pred_rows.axis[i]), ref_rows.axis[j] / np.linalg.norm(ref_rows.axis[j])
        angle = math.acos(min(1.0, abs(float(a1 @ a2))))
        pos = 0.0
        if pred_rows.hinge[i] and ref_rows.hinge[j]:
            n = np.cross(a1, a2)
            d = ref_rows.pivot[j] - pred_rows.pivot[i]
            pos = abs(d @ n) / np.linalg.norm(n) if np.linalg.norm(n) > 1e-6 else np.linalg.norm(np.cross(d, a2))
        same = pred_rows.child[i] == ref_rows.child[j]
        return angle + pos + (0.0 if same else 10.0), same or np.linalg.norm(pred_rows.centroid[i] - ref_rows.centroid[j]) <= 0.1

    P, R = len(pred_rows.child), len(ref_rows.child)
    best = (0, 0.0, frozenset())
    for perm in itertools.permutations(range(R), min(P, R)) if P <= R else itertools.permutations(range(P), R):
        pairs = list(zip(range(P), perm)) if P <= R else list(zip(perm, range(R)))
        kept = [(i, j, c) for i, j in pairs for c, ok in [cost(i, j)] if ok]
        key = (len(kept), sum(c for _, _, c in kept))
        if key[0] > best[0] or (key[0] == best[0] and key[1] < best[1] - 1e-12):
            best = (key[0], key[1], frozenset((i, j) for i, j, _ in kept))
    return best


def test_matching_agrees_with_brute_force_on_random_small_cases():
    rng = np.random.default_rng(7)
    for trial in range(200):
        n_parts = 7
        cen = {i: tuple(rng.uniform(0, 0.25, 3)) for i in range(1, n_parts + 1)}
        parents = {1: None, **{i: 1 for i in range(2, n_parts + 1)}}

        def random_joints(k):
            joints = {}
            for child in rng.choice(np.arange(2, n_parts + 1), size=k, replace=False):
                axis = tuple(rng.normal(size=3))
                pivot = tuple(rng.uniform(-0.5, 0.5, 3))
                joints[int(child)] = hinge(axis, pivot) if rng.random() < 0.7 else slide(axis, pivot)
            return joints

        pred = structure(parents, random_joints(int(rng.integers(0, 5))))
        ref = structure(parents, random_joints(int(rng.integers(0, 5))))
        p, r = joint_rows([pred], [cen]), joint_rows([ref], [cen])
        m = match_joints(p, r)
        count, total, pairs = _brute_force(p, r)
        got = frozenset(zip((m.pred - p.offsets[0]).tolist(), (m.ref - r.offsets[0]).tolist()))
        assert len(got) == count, trial
        assert got == pairs, trial


def test_batched_matching_equals_object_by_object():
    rng = np.random.default_rng(3)
    preds, refs, cens = [], [], []
    for _ in range(30):
        cen = {i: tuple(rng.uniform(0, 0.3, 3)) for i in range(1, 6)}
        parents = {1: None, 2: 1, 3: 1, 4: 1, 5: 1}
        mk = lambda: {int(c): hinge(tuple(rng.normal(size=3)), tuple(rng.normal(size=3)))
                      for c in rng.choice([2, 3, 4, 5], size=int(rng.integers(0, 4)), replace=False)}
        preds.append(structure(parents, mk()))
        refs.append(structure(parents, mk()))
        cens.append(cen)
    p, r = joint_rows(preds, cens), joint_rows(refs, cens)
    batch = gate_matches(p, r, match_joints(p, r))
    for o in range(30):
        po, ro = joint_rows([preds[o]], [cens[o]]), joint_rows([refs[o]], [cens[o]])
        single = gate_matches(po, ro, match_joints(po, ro))
        sel = batch.obj == o
        np.testing.assert_array_equal(batch.pred_child[sel], single.pred_child)
        np.testing.assert_array_equal(batch.ref_child[sel], single.ref_child)
        np.testing.assert_array_equal(batch.gate[sel], single.gate)
    assert set(np.unique(batch.gate)) <= set(range(len(GATES)))


def test_absurd_predicted_pivots_still_match_and_fail_the_origin_gate():
    cen = {1: (0, 0, 0), 2: (0.1, 0, 0), 3: (0.12, 0, 0)}
    ref = structure({1: None, 2: 1, 3: 1}, {2: hinge(), 3: hinge()})
    pred = structure({1: None, 2: 1, 3: 1}, {2: hinge(pivot=(1e300, 0, 0)), 3: hinge(pivot=(0, 1e250, 0))})
    rows = evaluate([Case("k", ref, cen, pred)]).rows[0]["matches"]
    assert [(r["pred_child"], r["ref_child"], r["gate"]) for r in rows] == [(2, 2, "origin"), (3, 3, "origin")]
