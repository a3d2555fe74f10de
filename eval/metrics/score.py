"""Scoring a split: per-object rows and the split-level metrics of Tables 1 and 2.

Input is a list of `Case`s whose structures are already parsed and canonicalised (see
`eval.metrics.cases`). Tree and joint measures are computed for all objects at once on flat numpy
rows; relations and scene partitions are small set / table computations per object.

How each metric is aggregated (percentages 0-100; None when there is nothing to measure):
* parse: parsed predictions over all references; everything else over the parsed subset.
* parent_acc: mean over objects. edge_f1: mean over objects with an edge on either side.
* presence_f1: mean over objects with a joint on either side.
* type_acc, axis_acc, the five failure shares: over all matched joints of the split (the shares
  sum to 100). pos_err (nu): mean line distance over matched pairs that are both hinges.
  range_iou: mean over matched pairs of the same type.
* sym_f1, inst_f1: true positives and set sizes summed over the split (micro); plane_acc over the
  symmetric pairs found on both sides.
* Scenes are references with more than one root. scene_parse: parsed scenes over scenes;
  objects_per_scene (predicted) and objects_per_scene_ref: means; count_match, full_partition,
  cluster_acc, rand_index: means over parsed scenes; pair precision / recall / F1: same-object node
  pairs summed over scenes (micro).
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np

from eval.metrics.joints import AXIS_TOLERANCE, GATES, MatchedJoints, gate_matches, joint_rows, match_joints
from eval.metrics.partition import PartitionScores, object_labels, partition_scores
from eval.metrics.relations import RELATION_FIELDS, RelationCounts, relation_counts
from eval.metrics.tree import TreeCounts, parent_rows, tree_counts
from jax3dc.structure.schema import Structure

Vec3 = tuple[float, float, float]

# metrics.json keys of Table 1 and Table 2 (SPEC §5); all percentages 0-100 except pos_err (nu)
# and objects_per_scene (a count).
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


@dataclass(frozen=True)
class _Measures:
    """Everything measured on the parsed cases, object index = position among parsed cases."""

    tree: TreeCounts
    joints_pred: np.ndarray
    joints_ref: np.ndarray
    joints_matched: np.ndarray
    matched: MatchedJoints
    relations: list[RelationCounts]
    partitions: dict[int, PartitionScores]  # parsed scenes only


def _pct(num: float, den: float) -> float | None:
    return 100.0 * float(num) / den if den else None


def _mean_pct(values: Sequence[float] | np.ndarray) -> float | None:
    return 100.0 * float(np.mean(values)) if len(values) else None


def _f1(tp: float, n_pred: float, n_ref: float) -> float | None:
    return 200.0 * float(tp) / (n_pred + n_ref) if n_pred + n_ref else None


def _is_scene(s: Structure) -> bool:
    return sum(n.parent is None for n in s.nodes.values()) > 1


def _measure(parsed: Sequence[Case]) -> _Measures:
    preds = [c.prediction for c in parsed]
    refs = [c.reference for c in parsed]
    centroids = [c.centroids for c in parsed]
    pred_joints, ref_joints = joint_rows(preds, centroids), joint_rows(refs, centroids)
    matched = gate_matches(pred_joints, ref_joints, match_joints(pred_joints, ref_joints))
    return _Measures(
        tree=tree_counts(parent_rows(preds, refs)),
        joints_pred=pred_joints.counts,
        joints_ref=ref_joints.counts,
        joints_matched=np.bincount(matched.obj, minlength=len(parsed)),
        matched=matched,
        relations=[relation_counts(p, r) for p, r in zip(preds, refs)],
        partitions={
            i: partition_scores(object_labels(p), object_labels(r))
            for i, (p, r) in enumerate(zip(preds, refs))
            if _is_scene(r)
        },
    )


def _tree_joint_metrics(x: _Measures) -> dict[str, Any]:
    t, mj = x.tree, x.matched
    has_edge = t.edge_pred + t.edge_ref > 0
    joints = x.joints_pred + x.joints_ref
    hinge_pairs = mj.line_distance[~np.isnan(mj.line_distance)]
    m = {
        "parent_acc": _mean_pct(t.parent_correct / np.maximum(t.nodes, 1)),
        "edge_f1": _mean_pct(2 * t.edge_tp[has_edge] / (t.edge_pred + t.edge_ref)[has_edge]),
        "presence_f1": _mean_pct(2 * x.joints_matched[joints > 0] / joints[joints > 0]),
        "type_acc": _mean_pct(mj.type_ok),
        "axis_acc": _mean_pct(mj.angle <= AXIS_TOLERANCE),
        "pos_err": float(hinge_pairs.mean()) if len(hinge_pairs) else None,
        "range_iou": _mean_pct(mj.range_iou[~np.isnan(mj.range_iou)]),
    }
    for gate, count in zip(GATES, np.bincount(mj.gate, minlength=len(GATES))):
        m["success" if gate == "success" else f"fail_{gate}"] = _pct(count, len(mj.gate))
    return m


def _relation_metrics(relations: Sequence[RelationCounts]) -> dict[str, Any]:
    total = {k: sum(getattr(r, k) for r in relations) for k in RELATION_FIELDS}
    return {
        "sym_f1": _f1(total["sym_tp"], total["sym_pred"], total["sym_ref"]),
        "inst_f1": _f1(total["inst_tp"], total["inst_pred"], total["inst_ref"]),
        "plane_acc": _pct(total["plane_correct"], total["sym_tp"]),
    }


def _scene_metrics(scenes: Sequence[PartitionScores], n_scene_refs: int) -> dict[str, Any]:
    tp, pp, rp = (sum(getattr(s, k) for s in scenes) for k in ("pair_tp", "pair_pred", "pair_ref"))
    return {
        "scene_parse": _pct(len(scenes), n_scene_refs),
        "objects_per_scene": float(np.mean([s.pred_objects for s in scenes])) if scenes else None,
        "objects_per_scene_ref": float(np.mean([s.ref_objects for s in scenes])) if scenes else None,
        "count_match": _mean_pct([s.pred_objects == s.ref_objects for s in scenes]),
        "full_partition": _mean_pct([s.full_match for s in scenes]),
        "cluster_acc": _mean_pct([s.cluster_accuracy for s in scenes]),
        "rand_index": _mean_pct([s.rand_index for s in scenes]),
        "pair_precision": _pct(tp, pp),
        "pair_recall": _pct(tp, rp),
        "pair_f1": _f1(tp, pp, rp),
    }


def _finite(x: float) -> float | None:
    return None if math.isnan(x) else x


def _object_rows(cases: Sequence[Case], parsed_index: Mapping[int, int], x: _Measures) -> list[dict[str, Any]]:
    mj = x.matched
    matches = [
        {"pred_child": pc, "ref_child": rc, "type_ok": ok, "angle": angle, "line_distance": _finite(dist),
         "range_iou": _finite(iou), "gate": GATES[gate]}
        for pc, rc, ok, angle, dist, iou, gate in zip(
            mj.pred_child.tolist(), mj.ref_child.tolist(), mj.type_ok.tolist(), mj.angle.tolist(),
            mj.line_distance.tolist(), mj.range_iou.tolist(), mj.gate.tolist())
    ]
    starts = np.searchsorted(mj.obj, np.arange(len(parsed_index) + 1)).tolist()
    t = x.tree
    rows = []
    for k, case in enumerate(cases):
        row: dict[str, Any] = {"key": case.key, "parsed": case.prediction is not None, "scene": _is_scene(case.reference)}
        i = parsed_index.get(k)
        if i is None:
            row.update(failure_rule=case.failure_rule, failure=case.failure)
            rows.append(row)
            continue
        tp, ep, er = int(t.edge_tp[i]), int(t.edge_pred[i]), int(t.edge_ref[i])
        jm, jp, jr = int(x.joints_matched[i]), int(x.joints_pred[i]), int(x.joints_ref[i])
        row.update(
            nodes=int(t.nodes[i]),
            parent_acc=100.0 * int(t.parent_correct[i]) / max(int(t.nodes[i]), 1),
            edge_f1=_f1(tp, ep, er),
            joints_pred=jp,
            joints_ref=jr,
            joints_matched=jm,
            presence_f1=_f1(jm, jp, jr),
            **{f: getattr(x.relations[i], f) for f in RELATION_FIELDS},
            matches=matches[starts[i]:starts[i + 1]],
        )
        if i in x.partitions:
            s = x.partitions[i]
            row.update(
                pred_objects=s.pred_objects, ref_objects=s.ref_objects, full_partition=s.full_match,
                cluster_acc=100.0 * s.cluster_accuracy, rand_index=100.0 * s.rand_index,
                pair_tp=s.pair_tp, pair_pred=s.pair_pred, pair_ref=s.pair_ref,
            )
        rows.append(row)
    return rows


def evaluate(cases: Sequence[Case]) -> Evaluation:
    """Score every case; returns split metrics (metrics.json) and one row per object."""
    parsed_index = {k: i for i, k in enumerate(k for k, c in enumerate(cases) if c.prediction is not None)}
    parsed = [cases[k] for k in parsed_index]
    x = _measure(parsed)
    metrics: dict[str, Any] = {"parse": _pct(len(parsed), len(cases))}
    metrics.update(_tree_joint_metrics(x))
    metrics.update(_relation_metrics(x.relations))
    n_scene_refs = sum(_is_scene(c.reference) for c in cases)
    metrics.update(_scene_metrics(list(x.partitions.values()), n_scene_refs))
    metrics["counts"] = {
        "objects": len(cases),
        "parsed": len(parsed),
        "joints_pred": int(x.joints_pred.sum()),
        "joints_ref": int(x.joints_ref.sum()),
        "joints_matched": len(x.matched.gate),
        "scenes": n_scene_refs,
        "scenes_parsed": len(x.partitions),
    }
    failures = Counter(c.failure_rule for c in cases if c.prediction is None)
    metrics["parse_failures"] = dict(sorted(failures.items()))
    return Evaluation(metrics, _object_rows(cases, parsed_index, x))
