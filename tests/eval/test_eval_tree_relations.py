"""Parent accuracy, edge F1 and relation metrics: hand-worked examples."""

import pytest

from eval.metrics.score import Case, evaluate
from eval.metrics.tree import parent_rows, tree_counts
from eval_structures import structure
from jax3dc.structure.schema import Relation

CEN = {i: (0.3 * i, 0.0, 0.0) for i in range(1, 10)}


def test_parent_accuracy_and_edge_f1_hand_worked():
    # reference 2->1, 3->1, 4->2; prediction 2->1, 3->2, 4->2
    ref = structure({1: None, 2: 1, 3: 1, 4: 2})
    pred = structure({1: None, 2: 1, 3: 2, 4: 2})
    c = tree_counts(parent_rows([pred], [ref]))
    # parents right for 1 (root on both sides), 2, 4; wrong for 3 -> 3/4
    assert (c.parent_correct[0], c.nodes[0]) == (3, 4)
    # edges {(2,1),(3,1),(4,2)} vs {(2,1),(3,2),(4,2)}: TP 2 -> F1 = 2*2 / (3 + 3) = 2/3
    assert (c.edge_tp[0], c.edge_pred[0], c.edge_ref[0]) == (2, 3, 3)
    m = evaluate([Case("k", ref, CEN, pred)]).metrics
    assert m["parent_acc"] == pytest.approx(75.0)
    assert m["edge_f1"] == pytest.approx(200 / 3)


def test_tree_metrics_are_means_over_objects_and_edge_free_objects_are_left_out_of_edge_f1():
    # object a: parent 3/4, edge F1 2/3 (above); object b: a single part, no edges on either side
    a = Case("a", structure({1: None, 2: 1, 3: 1, 4: 2}), CEN, structure({1: None, 2: 1, 3: 2, 4: 2}))
    b = Case("b", structure({1: None}), CEN, structure({1: None}))
    m = evaluate([a, b]).metrics
    assert m["parent_acc"] == pytest.approx((75.0 + 100.0) / 2)
    assert m["edge_f1"] == pytest.approx(200 / 3)


def test_relation_f1_is_summed_over_the_split_and_plane_over_common_pairs():
    parents = {i: (None if i == 1 else 1) for i in range(1, 9)}
    # object 1: sym ref {(2,3) yz, (4,5) xz}, pred {(2,3) yz, (4,5) xy}; inst ref {(6,7),(6,8)}, pred {(6,7)}
    ref1 = structure(parents, relations=(Relation("symmetric", 2, 3, "yz"), Relation("symmetric", 4, 5, "xz"),
                                         Relation("instance", 6, 7), Relation("instance", 6, 8)))
    pred1 = structure(parents, relations=(Relation("symmetric", 2, 3, "yz"), Relation("symmetric", 4, 5, "xy"),
                                          Relation("instance", 6, 7)))
    # object 2: sym ref {}, pred {(2,3) yz}; inst ref {(2,3)}, pred {}
    ref2 = structure(parents, relations=(Relation("instance", 2, 3),))
    pred2 = structure(parents, relations=(Relation("symmetric", 2, 3, "yz"),))
    m = evaluate([Case("1", ref1, CEN, pred1), Case("2", ref2, CEN, pred2)]).metrics
    # symmetric: TP 2, predicted 3, reference 2 -> F1 = 2*2 / 5 = 80
    assert m["sym_f1"] == pytest.approx(80.0)
    # instance: TP 1, predicted 1, reference 3 -> F1 = 2*1 / 4 = 50
    assert m["inst_f1"] == pytest.approx(50.0)
    # plane: of the 2 common symmetric pairs, 1 has the same plane -> 50
    assert m["plane_acc"] == pytest.approx(50.0)


def test_metrics_with_nothing_to_measure_are_none_not_zero():
    ref = structure({1: None, 2: 1})
    m = evaluate([Case("k", ref, CEN, ref)]).metrics
    for key in ("presence_f1", "type_acc", "axis_acc", "pos_err", "range_iou", "success", "sym_f1", "inst_f1",
                "plane_acc", "count_match", "cluster_acc"):
        assert m[key] is None, key
