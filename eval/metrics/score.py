"""Scoring a split: per-object rows and the split-level metrics of Tables 1 and 2.

Input is a list of `Case`s whose structures are already parsed and canonicalised (see
`eval.metrics.cases`). Tree and joint measures are computed for all objects at once on flat numpy
rows; relations and scene partitions are small set / table computations per object.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np

from eval.metrics.joints import AXIS_TOLERANCE, GATES, gate_matches, joint_rows, match_joints
from eval.metrics.partition import object_labels, partition_scores
from eval.metrics.relations import RELATION_FIELDS, relation_counts
from eval.metrics.tree import parent_rows, tree_counts
from jax3dc.structure.schema import Structure

Vec3 = tuple[float, float, float]

# metrics.json keys of Table 1 and Table 2 (SPEC §5); all percentages 0-100 except pos_err (nu)
# and objects_per_scene (a count). A metric with nothing to average over is None.
TABLE1_KEYS: tuple[str, ...] = (
    "parse", "parent_acc", "edge_f1", "presence_f1", "type_acc", "axis_acc", "pos_err", "range_iou",
    "fail_type", "fail_axis", "fail_origin", "fail_limit", "success", "sym_f1", "inst_f1", "plane_acc",
)
TABLE2_KEYS: tuple[str, ...] = (
    "objects_per_scene", "count_match", "full_partition", "cluster_acc", "rand_index",
    "pair_precision", "pair_recall", "pair_f1",
)


@dataclass(frozen=True)
class Case:
    """One reference and its prediction, both canonical; ``prediction`` None = parse failure.

    ``centroids`` are the reference part boxes' centroids (nu), which decide joint candidates.
    ``failure_rule`` / ``failure`` say why the prediction did not parse (StructureError rule and
    message, or ``missing`` when there was no prediction line).
    """

    key: str
    reference: Structure
    centroids: Mapping[int, Vec3]
    prediction: Structure | None
    failure_rule: str | None = None
    failure: str | None = None


@dataclass
class Evaluation:
    metrics: dict[str, Any]
    rows: list[dict[str, Any]] = field(default_factory=list)


def _pct(num: float, den: float) -> float | None:
    return 100.0 * num / den if den else None


def _mean_pct(values: np.ndarray) -> float | None:
    return 100.0 * float(np.mean(values)) if len(values) else None


def _f1(tp: float, n_pred: float, n_ref: float) -> float | None:
    return 200.0 * tp / (n_pred + n_ref) if n_pred + n_ref else None


def _finite(x: float) -> float | None:
    return None if math.isnan(x) else x


def evaluate(cases: Sequence[Case]) -> Evaluation:
    """Score every case; returns split metrics (metrics.json) and one row per object."""
    parsed = [c for c in cases if c.prediction is not None]
    preds = [c.prediction for c in parsed]
    refs = [c.reference for c in parsed]

    tree = tree_counts(parent_rows(preds, refs))
    pred_joints = joint_rows(preds, [c.centroids for c in parsed])
    ref_joints = joint_rows(refs, [c.centroids for c in parsed])
    matched = gate_matches(pred_joints, ref_joints, match_joints(pred_joints, ref_joints))
    n_matched = np.bincount(matched.obj, minlength=len(parsed))
    n_pred, n_ref = pred_joints.counts, ref_joints.counts
    rels = [relation_counts(p, r) for p, r in zip(preds, refs)]

    scene_ref = [sum(n.parent is None for n in c.reference.nodes.values()) > 1 for c in cases]
    is_scene = {id(c): flag for c, flag in zip(cases, scene_ref)}
    partitions = {
        i: partition_scores(object_labels(c.prediction), object_labels(c.reference))
        for i, c in enumerate(parsed)
        if is_scene[id(c)]
    }

    # ---- split-level metrics -------------------------------------------------------------
    m: dict[str, Any] = {"parse": _pct(len(parsed), len(cases))}
    m["parent_acc"] = _mean_pct(tree.parent_correct / np.maximum(tree.nodes, 1))
    has_edge = tree.edge_pred + tree.edge_ref > 0
    m["edge_f1"] = _mean_pct(2 * tree.edge_tp[has_edge] / (tree.edge_pred + tree.edge_ref)[has_edge])
    has_joint = n_pred + n_ref > 0
    m["presence_f1"] = _mean_pct(2 * n_matched[has_joint] / (n_pred + n_ref)[has_joint])
    m["type_acc"] = _mean_pct(matched.type_ok)
    m["axis_acc"] = _mean_pct(matched.angle <= AXIS_TOLERANCE)
    hinge_pairs = matched.line_distance[~np.isnan(matched.line_distance)]
    m["pos_err"] = float(hinge_pairs.mean()) if len(hinge_pairs) else None
    same_type = matched.range_iou[~np.isnan(matched.range_iou)]
    m["range_iou"] = _mean_pct(same_type)
    gate_counts = np.bincount(matched.gate, minlength=len(GATES))
    for gate, count in zip(GATES, gate_counts):
        m["success" if gate == "success" else f"fail_{gate}"] = _pct(count, len(matched.gate))
    total = {k: sum(getattr(r, k) for r in rels) for k in RELATION_FIELDS}
    m["sym_f1"] = _f1(total["sym_tp"], total["sym_pred"], total["sym_ref"])
    m["inst_f1"] = _f1(total["inst_tp"], total["inst_pred"], total["inst_ref"])
    m["plane_acc"] = _pct(total["plane_correct"], total["sym_tp"])

    scenes = list(partitions.values())
    m["scene_parse"] = _pct(len(scenes), sum(scene_ref))
    m["objects_per_scene"] = float(np.mean([s.pred_objects for s in scenes])) if scenes else None
    m["objects_per_scene_ref"] = float(np.mean([s.ref_objects for s in scenes])) if scenes else None
    m["count_match"] = _mean_pct(np.array([s.pred_objects == s.ref_objects for s in scenes]))
    m["full_partition"] = _mean_pct(np.array([s.full_match for s in scenes]))
    m["cluster_acc"] = _mean_pct(np.array([s.cluster_accuracy for s in scenes]))
    m["rand_index"] = _mean_pct(np.array([s.rand_index for s in scenes]))
    tp = sum(s.pair_tp for s in scenes)
    pp = sum(s.pair_pred for s in scenes)
    rp = sum(s.pair_ref for s in scenes)
    m["pair_precision"] = _pct(tp, pp)
    m["pair_recall"] = _pct(tp, rp)
    m["pair_f1"] = _f1(tp, pp, rp)

    m["counts"] = {
        "objects": len(cases),
        "parsed": len(parsed),
        "joints_pred": int(n_pred.sum()),
        "joints_ref": int(n_ref.sum()),
        "joints_matched": len(matched.gate),
        "scenes": int(sum(scene_ref)),
        "scenes_parsed": len(scenes),
    }
    m["parse_failures"] = dict(sorted(Counter(c.failure_rule for c in cases if c.prediction is None).items()))

    # ---- per-object rows -----------------------------------------------------------------
    rows: list[dict[str, Any]] = []
    match_rows = [
        {"pred_child": pc, "ref_child": rc, "type_ok": ok, "angle": angle, "line_distance": _finite(dist),
         "range_iou": _finite(iou), "gate": GATES[gate]}
        for pc, rc, ok, angle, dist, iou, gate in zip(
            matched.pred_child.tolist(), matched.ref_child.tolist(), matched.type_ok.tolist(),
            matched.angle.tolist(), matched.line_distance.tolist(), matched.range_iou.tolist(), matched.gate.tolist())
    ]
    index = {id(c): i for i, c in enumerate(parsed)}
    starts = np.searchsorted(matched.obj, np.arange(len(parsed) + 1))
    for case, is_scene in zip(cases, scene_ref):
        row: dict[str, Any] = {"key": case.key, "parsed": case.prediction is not None, "scene": is_scene}
        i = index.get(id(case))
        if i is None:
            row.update(failure_rule=case.failure_rule, failure=case.failure)
            rows.append(row)
            continue
        edges = int(tree.edge_pred[i] + tree.edge_ref[i])
        joints = int(n_pred[i] + n_ref[i])
        row.update(
            nodes=int(tree.nodes[i]),
            parent_acc=100.0 * int(tree.parent_correct[i]) / max(int(tree.nodes[i]), 1),
            edge_f1=_f1(int(tree.edge_tp[i]), int(tree.edge_pred[i]), int(tree.edge_ref[i])) if edges else None,
            joints_pred=int(n_pred[i]),
            joints_ref=int(n_ref[i]),
            joints_matched=int(n_matched[i]),
            presence_f1=_f1(int(n_matched[i]), int(n_pred[i]), int(n_ref[i])) if joints else None,
            **{k: getattr(rels[i], k) for k in RELATION_FIELDS},
        )
        row["matches"] = match_rows[starts[i]:starts[i + 1]]
        if i in partitions:
            s = partitions[i]
            row.update(
                pred_objects=s.pred_objects,
                ref_objects=s.ref_objects,
                full_partition=s.full_match,
                cluster_acc=100.0 * s.cluster_accuracy,
                rand_index=100.0 * s.rand_index,
                pair_tp=s.pair_tp,
                pair_pred=s.pair_pred,
                pair_ref=s.pair_ref,
            )
        rows.append(row)
    return Evaluation(m, rows)
